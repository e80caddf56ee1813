#!/usr/bin/env python3
"""Trains graspd's recogniser (dissertation §3.2.1, the object by name) and exports it to ONNX
under its contract (docs/model-contract.md, "The recogniser").

    python models/recogniser/train.py --train DIR --val DIR --test DIR --out models/recogniser

Data: folders written by `gen-recogniser-data` (crop.npy [M, 5, 64, 64], size.npy [M, 3],
label.npy [M], meta.json with the class names): each segmented object's crop and size exactly as
graspd makes them (graspd_core::perception::recognition::object_crop).

The network is a small CNN (four stride-2 stages, 24-128 channels, global average pooling) whose
pooled features are joined with the three size features before a two-layer head; cross-entropy
over the classes (the known objects and `unknown`), AdamW, one-cycle learning rate, augmented by
mirroring, 90-degree turns, brightness and colour gains on the object's pixels and jitter of the
size features. It is exported with a dynamic batch, verified against ONNX Runtime, and evaluated
on the test split: accuracy, per-class recall and the confusion matrix (metrics.json).
"""
import argparse
import hashlib
import json
import os
import time
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

MEAN = np.array([0.485, 0.456, 0.406], np.float32)
STD = np.array([0.229, 0.224, 0.225], np.float32)


def load(folder):
    d = Path(folder)
    meta = json.loads((d / "meta.json").read_text())
    crop = np.load(d / "crop.npy", mmap_mode="r")
    size = np.load(d / "size.npy")
    label = np.load(d / "label.npy").astype(np.int64)
    source = np.load(d / "source.npy") if (d / "source.npy").exists() else None
    meta["source"] = source
    return np.array(crop), size, label, meta


def conv(cin, cout, stride):
    return nn.Sequential(
        nn.Conv2d(cin, cout, 3, stride, 1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(inplace=True)
    )


class Recogniser(nn.Module):
    def __init__(self, classes):
        super().__init__()
        self.features = nn.Sequential(
            conv(5, 24, 2), conv(24, 24, 1),  # 32
            conv(24, 48, 2), conv(48, 48, 1),  # 16
            conv(48, 96, 2), conv(96, 96, 1),  # 8
            conv(96, 128, 2),  # 4
        )
        self.size = nn.Sequential(nn.Linear(3, 32), nn.ReLU(inplace=True))
        self.head = nn.Sequential(
            nn.Linear(128 + 32, 128), nn.ReLU(inplace=True), nn.Dropout(0.2), nn.Linear(128, classes)
        )

    def forward(self, crop, size):
        f = self.features(crop).mean(dim=(2, 3))
        return self.head(torch.cat([f, self.size(size)], 1))


def augment(crop, size, rng):
    """Mirror, 90-degree turns, brightness and per-channel gains on the object's pixels (the
    normalised colour is undone and redone), and 5 % jitter of the sizes."""
    crop = crop.clone()
    n = crop.shape[0]
    flip = torch.from_numpy(rng.random(n) < 0.5)
    crop[flip] = crop[flip].flip(-1)
    k = int(rng.integers(0, 4))
    crop = torch.rot90(crop, k, dims=(2, 3))
    mean = torch.from_numpy(MEAN)[None, :, None, None]
    std = torch.from_numpy(STD)[None, :, None, None]
    mask = (crop[:, 3:4] > 0).float()
    rgb = crop[:, :3] * std + mean
    gain = torch.from_numpy(rng.uniform(0.75, 1.25, (n, 1, 1, 1)) * rng.uniform(0.9, 1.1, (n, 3, 1, 1))).float()
    rgb = (rgb * gain).clamp(0, 1)
    crop[:, :3] = (rgb - mean) / std * mask
    size = size * torch.from_numpy(rng.uniform(0.95, 1.05, size.shape)).float()
    return crop, size


def evaluate(model, crop, size, label, batch=256):
    model.eval()
    out = []
    with torch.no_grad():
        for i in range(0, len(label), batch):
            out.append(model(torch.from_numpy(crop[i : i + batch]), torch.from_numpy(size[i : i + batch])))
    return torch.cat(out).softmax(1).numpy()


def metrics(prob, label, classes, source=None):
    pred = prob.argmax(1)
    k = len(classes)
    confusion = np.zeros((k, k), np.int64)
    for t, p in zip(label, pred):
        confusion[t, p] += 1
    recall = {c: (float(confusion[i, i] / confusion[i].sum()) if confusion[i].sum() else None) for i, c in enumerate(classes)}
    known = label != k - 1
    extra = {}
    if source is not None and (source == 12).any():
        # The chips can (--unseen): a real object never seen in training.
        extra["unseen_object_crops"] = int((source == 12).sum())
        extra["unseen_object_taken_for_unknown"] = float((pred[source == 12] == k - 1).mean())
        procedural = source == 255
        extra["procedural_taken_for_unknown"] = float((pred[procedural] == k - 1).mean())
    return extra | {
        "crops": int(len(label)),
        "accuracy": float((pred == label).mean()),
        "accuracy_known": float((pred[known] == label[known]).mean()) if known.any() else None,
        "unknown_taken_for_known": float((pred[~known] != k - 1).mean()) if (~known).any() else None,
        "recall": recall,
        "confusion": confusion.tolist(),
    }


def export(model, path, classes, check, info):
    import onnx
    import onnxruntime as ort

    model.eval()
    crop = torch.zeros(1, 5, 64, 64)
    size = torch.zeros(1, 3)
    torch.onnx.export(
        model,
        (crop, size),
        path,
        input_names=["crop", "size"],
        output_names=["logits"],
        dynamic_axes={"crop": {0: "n"}, "size": {0: "n"}, "logits": {0: "n"}},
        opset_version=17,
        dynamo=False,
    )
    m = onnx.load(path)
    meta = {
        "graspd.classes": ",".join(classes),
        "graspd.model": "recogniser CNN (models/recogniser/MODEL_CARD.md)",
    }
    meta.update(info)
    for k, v in meta.items():
        e = m.metadata_props.add()
        e.key, e.value = k, str(v)
    onnx.checker.check_model(m)
    onnx.save(m, path)
    sess = ort.InferenceSession(path, providers=["CPUExecutionProvider"])
    c, s = check
    with torch.no_grad():
        ref = model(torch.from_numpy(c), torch.from_numpy(s)).numpy()
    got = sess.run(None, {"crop": c, "size": s})[0]
    worst = float(np.abs(ref - got).max())
    if worst > 1e-3:
        raise SystemExit(f"ONNX Runtime disagrees with PyTorch by {worst} (> 1e-3)")
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", required=True)
    ap.add_argument("--val", required=True)
    ap.add_argument("--test", required=True)
    ap.add_argument("--out", default=str(Path(__file__).parent), help="folder for recogniser.onnx and metrics")
    ap.add_argument("--epochs", type=int, default=30)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--lr", type=float, default=3e-3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.manual_seed(args.seed)
    np.random.seed(args.seed)
    torch.set_num_threads(args.threads)
    rng = np.random.default_rng(args.seed)

    xtr, str_, ytr, meta = load(args.train)
    xva, sva, yva, _ = load(args.val)
    xte, ste, yte, meta_te = load(args.test)
    classes = meta["classes"]
    print(f"train {len(ytr)} crops, val {len(yva)}, test {len(yte)}; classes {classes}")
    counts = np.bincount(ytr, minlength=len(classes))
    # Classes weighted toward balance (unknown is the most common).
    weight = torch.from_numpy((counts.sum() / (len(classes) * np.maximum(counts, 1))) ** 0.5).float()

    model = Recogniser(len(classes))
    params = sum(p.numel() for p in model.parameters())
    opt = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    steps = args.epochs * ((len(ytr) + args.batch - 1) // args.batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=args.lr, total_steps=steps)
    best, best_state, history = -1.0, None, []
    started = time.time()
    for epoch in range(args.epochs):
        model.train()
        order = rng.permutation(len(ytr))
        loss_sum = 0.0
        for i in range(0, len(order), args.batch):
            idx = np.sort(order[i : i + args.batch])
            c, s = augment(torch.from_numpy(xtr[idx]), torch.from_numpy(str_[idx]), rng)
            loss = F.cross_entropy(model(c, s), torch.from_numpy(ytr[idx]), weight=weight, label_smoothing=0.05)
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            loss_sum += float(loss.detach()) * len(idx)
        acc = metrics(evaluate(model, xva, sva, yva), yva, classes)["accuracy"]
        history.append({"epoch": epoch + 1, "loss": loss_sum / len(ytr), "val_accuracy": acc})
        print(f"epoch {epoch + 1}: loss {loss_sum / len(ytr):.4f}, val accuracy {acc:.4f} ({time.time() - started:.0f} s)")
        if acc >= best:
            best, best_state = acc, {k: v.clone() for k, v in model.state_dict().items()}
    model.load_state_dict(best_state)
    test = metrics(evaluate(model, xte, ste, yte), yte, classes, meta_te["source"])
    val = metrics(evaluate(model, xva, sva, yva), yva, classes)
    print(f"test accuracy {test['accuracy']:.4f} (known objects {test['accuracy_known']:.4f}, unknown taken for a known object {test['unknown_taken_for_known']:.4f}, unseen chips can taken for unknown {test.get('unseen_object_taken_for_unknown')})")

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    digest = hashlib.sha256()
    for f in ("crop.npy", "label.npy"):
        digest.update((Path(args.train) / f).read_bytes()[:1 << 20])
    onnx_path = str(out / "recogniser.onnx")
    worst = export(model, onnx_path, classes, (xte[:16].copy(), ste[:16].copy()), {
        "graspd.train_data": f"gen-recogniser-data seed {meta['seed']}, {meta['scenes']} scenes, {len(ytr)} crops",
        "graspd.test_accuracy": f"{test['accuracy']:.4f}",
    })
    report = {
        "classes": classes,
        "parameters": params,
        "train": {"crops": int(len(ytr)), "per_class": counts.tolist(), "seed": meta["seed"], "scenes": meta["scenes"]},
        "val": val,
        "test": test,
        "test_data": {"seed": meta_te["seed"], "scenes": meta_te["scenes"], "unseen": meta_te["unseen"]},
        "history": history,
        "train_seconds": time.time() - started,
        "onnx_max_abs_diff": worst,
        "torch": torch.__version__,
        "train_digest": digest.hexdigest()[:16],
    }
    (out / "metrics.json").write_text(json.dumps(report, indent=1) + "\n")
    print(f"wrote {onnx_path} ({os.path.getsize(onnx_path) / 1e6:.2f} MB, {params} parameters); ONNX Runtime vs PyTorch max |diff| {worst:.2e}")


if __name__ == "__main__":
    main()
