#!/usr/bin/env python3
"""Trains graspd's learned parallel-jaw grasp quality (dissertation §3.2.2, Eq 3.1) and exports it
to ONNX under its contract (docs/model-contract.md, "The grasp-quality network").

    python models/grasp_quality/train.py --data DIR --out models/grasp_quality

Data: a folder written by `graspd-sim label-grasps` (crop.npy [N, 2, 32, 32], configuration.npy
[N, 1], label.npy [N], meta.jsonl): sampled Robotiq 2F-85 grasps straight down, each executed in
MuJoCo (label 1: lifted, held and shaken without dropping), with the view graspd's planner has of
it (graspd_core::planning::grasp_quality::crop::grasp_view).

Splits: scenes whose seed halved ends in 8 are validation, in 9 test (a YCB scene and a
primitive scene each); the objects named by
--unseen-objects (default: three shared YCB objects) are left out of training and validation and
reported on their own, as are the generated primitives of the test scenes.

The network follows Figure 3.4: four convolutional layers on the crop (ReLU), their features
joined with the grasp's configuration, fully connected layers, and two outputs P and Q whose
softmax is P(y = 1) = e^Q / (e^P + e^Q) (Eq 3.1); cross-entropy, AdamW, one-cycle learning rate,
augmented by mirroring the crop along and across the jaws' axis (the gripper is symmetric both
ways). Besides accuracy it reports what the planner needs: per test scene, how often the grasp
the network rates highest succeeds, against the scene's average grasp (metrics.json).
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

UNSEEN = ["gelatin_box", "apple", "mustard_bottle"]


def load(folder):
    d = Path(folder)
    crop = np.load(d / "crop.npy")
    conf = np.load(d / "configuration.npy")
    label = np.load(d / "label.npy").astype(np.int64)
    meta = [json.loads(line) for line in (d / "meta.jsonl").read_text().splitlines() if line.strip()]
    if not (len(meta) == len(label) == len(crop) == len(conf)):
        raise SystemExit(f"{d}: {len(crop)} crops, {len(conf)} configurations, {len(label)} labels, {len(meta)} meta lines")
    return crop, conf, label, meta


class GraspQuality(nn.Module):
    """Figure 3.4: four convolutions, the configuration joined, fully connected layers, (P, Q)."""

    def __init__(self):
        super().__init__()
        self.features = nn.Sequential(
            nn.Conv2d(2, 32, 5, 1, 2), nn.ReLU(inplace=True),  # 32
            nn.Conv2d(32, 32, 3, 2, 1), nn.ReLU(inplace=True),  # 16
            nn.Conv2d(32, 64, 3, 2, 1), nn.ReLU(inplace=True),  # 8
            nn.Conv2d(64, 64, 3, 2, 1), nn.ReLU(inplace=True),  # 4
        )
        self.head = nn.Sequential(
            nn.Linear(64 * 4 * 4 + 1, 128), nn.ReLU(inplace=True), nn.Dropout(0.2),
            nn.Linear(128, 64), nn.ReLU(inplace=True),
            nn.Linear(64, 2),
        )

    def forward(self, crop, configuration):
        f = self.features(crop).flatten(1)
        return self.head(torch.cat([f, configuration], 1))


def augment(crop, rng):
    n = crop.shape[0]
    along = torch.from_numpy(rng.random(n) < 0.5)
    across = torch.from_numpy(rng.random(n) < 0.5)
    crop = crop.clone()
    crop[along] = crop[along].flip(-1)
    crop[across] = crop[across].flip(-2)
    return crop


def predict(model, crop, conf, batch=512):
    model.eval()
    out = []
    with torch.no_grad():
        for i in range(0, len(crop), batch):
            out.append(model(torch.from_numpy(crop[i : i + batch]), torch.from_numpy(conf[i : i + batch])))
    return torch.cat(out).softmax(1)[:, 1].numpy() if out else np.zeros(0)


def auc(p, y):
    pos, neg = p[y == 1], p[y == 0]
    if len(pos) == 0 or len(neg) == 0:
        return None
    order = np.argsort(np.concatenate([pos, neg]), kind="mergesort")
    ranks = np.empty(len(order))
    ranks[order] = np.arange(1, len(order) + 1)
    return float((ranks[: len(pos)].sum() - len(pos) * (len(pos) + 1) / 2) / (len(pos) * len(neg)))


def metrics(p, y, scenes):
    """Accuracy at 0.5, balanced accuracy, AUC, and per scene the top-rated grasp's success
    against the scene's mean (scenes with at least two grasps)."""
    if len(y) == 0:
        return {"grasps": 0}
    pred = (p >= 0.5).astype(np.int64)
    tpr = float((pred[y == 1] == 1).mean()) if (y == 1).any() else None
    tnr = float((pred[y == 0] == 0).mean()) if (y == 0).any() else None
    top, mean = [], []
    for s in np.unique(scenes):
        k = np.flatnonzero(scenes == s)
        if len(k) < 2:
            continue
        top.append(y[k[np.argmax(p[k])]])
        mean.append(y[k].mean())
    return {
        "grasps": int(len(y)),
        "positives": float(y.mean()),
        "accuracy": float((pred == y).mean()),
        "balanced_accuracy": (tpr + tnr) / 2 if tpr is not None and tnr is not None else None,
        "auc": auc(p, y),
        "scenes": len(top),
        "top_rated_success": float(np.mean(top)) if top else None,
        "mean_grasp_success": float(np.mean(mean)) if mean else None,
    }


def export(model, path, check, info):
    import onnx
    import onnxruntime as ort

    model.eval()
    torch.onnx.export(
        model,
        (torch.zeros(1, 2, 32, 32), torch.zeros(1, 1)),
        path,
        input_names=["crop", "configuration"],
        output_names=["logits"],
        dynamic_axes={"crop": {0: "n"}, "configuration": {0: "n"}, "logits": {0: "n"}},
        opset_version=17,
        dynamo=False,
    )
    m = onnx.load(path)
    meta = {"graspd.model": "parallel-jaw grasp quality CNN (models/grasp_quality/MODEL_CARD.md)"}
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
    got = sess.run(None, {"crop": c, "configuration": s})[0]
    worst = float(np.abs(ref - got).max())
    if worst > 1e-3:
        raise SystemExit(f"ONNX Runtime disagrees with PyTorch by {worst} (> 1e-3)")
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True, action="append", help="label-grasps folder (repeatable)")
    ap.add_argument("--out", default=str(Path(__file__).parent))
    ap.add_argument("--unseen-objects", default=",".join(UNSEEN))
    ap.add_argument("--epochs", type=int, default=40)
    ap.add_argument("--batch", type=int, default=128)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.manual_seed(args.seed)
    np.random.seed(args.seed)
    torch.set_num_threads(args.threads)
    rng = np.random.default_rng(args.seed)

    parts = [load(d) for d in args.data]
    crop = np.concatenate([p[0] for p in parts])
    conf = np.concatenate([p[1] for p in parts])
    label = np.concatenate([p[2] for p in parts])
    meta = [m for p in parts for m in p[3]]
    scene = np.array([m["scene_seed"] for m in meta])
    obj = np.array([m["object"] for m in meta])
    unseen = set(o for o in args.unseen_objects.split(",") if o)
    held_obj = np.array([o in unseen for o in obj])
    primitive = np.array([("box_" in o or "cylinder_" in o) for o in obj])
    # label-grasps alternates YCB objects (even seeds) and primitives (odd): pairs of scenes
    # go to one split, so that each split has both.
    val = ((scene // 2) % 10 == 8) & ~held_obj
    test = ((scene // 2) % 10 == 9) & ~held_obj
    train = ~val & ~test & ~held_obj
    print(f"{len(label)} grasps ({label.mean():.3f} held): train {train.sum()}, val {val.sum()}, test {test.sum()}, unseen objects {held_obj.sum()}")

    xtr, ctr, ytr = crop[train], conf[train], label[train]
    pos = ytr.mean()
    weight = torch.tensor([0.5 / (1 - pos), 0.5 / pos]).float()
    model = GraspQuality()
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
            c = augment(torch.from_numpy(xtr[idx]), rng)
            loss = F.cross_entropy(model(c, torch.from_numpy(ctr[idx])), torch.from_numpy(ytr[idx]), weight=weight)
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            loss_sum += float(loss.detach()) * len(idx)
        mv = metrics(predict(model, crop[val], conf[val]), label[val], scene[val])
        score = mv.get("auc") or 0.0
        history.append({"epoch": epoch + 1, "loss": loss_sum / len(ytr), "val_accuracy": mv.get("accuracy"), "val_auc": score})
        print(f"epoch {epoch + 1}: loss {loss_sum / len(ytr):.4f}, val accuracy {mv.get('accuracy')}, AUC {score:.4f} ({time.time() - started:.0f} s)")
        if score >= best:
            best, best_state = score, {k: v.clone() for k, v in model.state_dict().items()}
    model.load_state_dict(best_state)

    def on(mask):
        return metrics(predict(model, crop[mask], conf[mask]), label[mask], scene[mask])

    report_test = on(test)
    report = {
        "parameters": params,
        "data": [str(d) for d in args.data],
        "grasps": int(len(label)),
        "train": {"grasps": int(train.sum()), "positives": float(pos)},
        "val": on(val),
        "test": report_test,
        "test_ycb": on(test & ~primitive),
        "test_primitives": on(test & primitive),
        "unseen_objects": sorted(unseen),
        "test_unseen_objects": on(held_obj),
        "history": history,
        "train_seconds": time.time() - started,
        "torch": torch.__version__,
    }
    print(json.dumps({k: report[k] for k in ("test", "test_ycb", "test_primitives", "test_unseen_objects")}, indent=1))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    digest = hashlib.sha256()
    for d in args.data:
        digest.update((Path(d) / "label.npy").read_bytes())
    path = str(out / "grasp_quality.onnx")
    report["onnx_max_abs_diff"] = export(model, path, (crop[test][:16].copy(), conf[test][:16].copy()), {
        "graspd.train_data": f"graspd-sim label-grasps, {int(train.sum())} grasps",
        "graspd.test_accuracy": f"{report_test['accuracy']:.4f}",
        "graspd.crop": "2x32x32, 4 mm cells, heights ±60 mm about the grasp",
    })
    report["train_digest"] = digest.hexdigest()[:16]
    (out / "metrics.json").write_text(json.dumps(report, indent=1) + "\n")
    print(f"wrote {path} ({os.path.getsize(path) / 1e6:.2f} MB, {params} parameters)")


if __name__ == "__main__":
    main()
