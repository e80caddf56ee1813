#!/usr/bin/env python3
"""Trains graspd's grasp-type network (method.md §4, dissertation ch. 4.2.2) and exports it to ONNX
under the model contract (docs/model-contract.md).

    python models/grasp_type/train.py --train DIR --val DIR --test DIR --out models/grasp_type

Data: either folders written by `gen-grasp-type-data` (x.npy, y.npy: already resized by graspd's
own preprocessing) or, with --data DIR, your own labelled frames in the format of MODEL_CARD.md
("Retraining on your own data"): NAME_rgb.png, NAME_depth.png (16-bit, millimetres) and
NAME_labels.png (8-bit, bit s-1 set where grasp type s suits the pixel), resized here exactly as
graspd resizes (bilinear, pixel centres aligned, only valid depths interpolated).

The network is a small U-Net (four scales, 16-96 channels) with a per-pixel sigmoid
cross-entropy loss per type (Eq 4.1-4.2; multi-label). It is exported with a fixed 160x120 input
(graspd resizes frames to it), verified against ONNX Runtime, and evaluated on the test split:
per-type IoU at probability 0.5 (laid out like Table 4.1) and a confusion matrix.
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

TYPES = ["large_wrap", "small_wrap", "power", "pinch", "precision", "tripod"]
MEAN = np.array([0.485, 0.456, 0.406], np.float32)
STD = np.array([0.229, 0.224, 0.225], np.float32)


# ---------------------------------------------------------------------------------------------
# Data


def bilinear_taps(src, dst):
    """Taps (i0, i1, fraction of i1) of graspd's resize (perception/grasp_type/model.rs)."""
    r = src / dst
    s = np.clip((np.arange(dst) + 0.5) * r - 0.5, 0, src - 1)
    i0 = np.floor(s).astype(np.int64)
    return i0, np.minimum(i0 + 1, src - 1), (s - i0).astype(np.float32)


def resized_planes(rgb, depth, w, h):
    """numpy twin of graspd_core::perception::resized_planes: [4, h, w] float32."""
    fh, fw = depth.shape
    if (fw, fh) == (w, h):
        return np.concatenate([rgb.transpose(2, 0, 1).astype(np.float32), depth[None]], 0)
    x0, x1, a = bilinear_taps(fw, w)
    y0, y1, b = bilinear_taps(fh, h)
    a, b = a[None, :], b[:, None]
    wts = [(1 - a) * (1 - b), a * (1 - b), (1 - a) * b, a * b]
    idx = [(y0[:, None], x0[None]), (y0[:, None], x1[None]), (y1[:, None], x0[None]), (y1[:, None], x1[None])]
    out = np.zeros((4, h, w), np.float32)
    rgbf = rgb.astype(np.float32)
    for k in range(3):
        out[k] = sum(wt * rgbf[yy, xx, k] for wt, (yy, xx) in zip(wts, idx))
    num = np.zeros((h, w), np.float32)
    den = np.zeros((h, w), np.float32)
    for wt, (yy, xx) in zip(wts, idx):
        d = depth[yy, xx]
        ok = (d > 0) & (wt > 0)
        num += np.where(ok, wt * d, 0)
        den += np.where(ok, wt, 0)
    out[3] = np.where(den > 0, num / np.maximum(den, 1e-12), 0)
    return out


def label_sources(src, dst):
    return np.minimum(((np.arange(dst) + 0.5) * (src / dst)).astype(np.int64), src - 1)


def load_own_frame(stem, w, h):
    from PIL import Image

    rgb = np.array(Image.open(f"{stem}_rgb.png").convert("RGB"))
    depth = np.array(Image.open(f"{stem}_depth.png")).astype(np.float32) / 1000.0
    labels = np.array(Image.open(f"{stem}_labels.png"))
    x = resized_planes(rgb, depth, w, h)
    fh, fw = labels.shape
    y = labels[label_sources(fh, h)[:, None], label_sources(fw, w)[None]]
    return x, y


def load_own_data(folder, w, h):
    stems = sorted(str(p)[: -len("_rgb.png")] for p in Path(folder).glob("*_rgb.png"))
    if not stems:
        raise SystemExit(f"{folder}: no NAME_rgb.png files (see MODEL_CARD.md)")
    xs, ys = zip(*(load_own_frame(s, w, h) for s in stems))
    return np.stack(xs), np.stack(ys), stems


def split_by_name(stems, share):
    """A stable split by a hash of the file name: the same files always land in the same part."""
    keys = np.array([int(hashlib.sha1(Path(s).name.encode()).hexdigest()[:8], 16) / 2**32 for s in stems])
    return keys < share


def load_split(folder):
    x = np.load(os.path.join(folder, "x.npy"), mmap_mode="r")
    y = np.load(os.path.join(folder, "y.npy"), mmap_mode="r")
    return x, y


def to_input(x):
    """Raw planes (0-255 colour, metres) to the contract's input: colour normalised, depth as is."""
    x = torch.as_tensor(np.asarray(x, np.float32)).clone()
    x[:, :3] = (x[:, :3] / 255.0 - torch.tensor(MEAN)[None, :, None, None]) / torch.tensor(STD)[None, :, None, None]
    return x


def to_targets(y):
    y = torch.as_tensor(np.asarray(y, np.uint8)).long()
    return torch.stack([(y >> s) & 1 for s in range(6)], 1).float()


# ---------------------------------------------------------------------------------------------
# Model


def block(cin, cout, stride=1, dilation=1):
    return nn.Sequential(
        nn.Conv2d(cin, cout, 3, stride, padding=dilation, dilation=dilation, bias=False),
        nn.BatchNorm2d(cout),
        nn.ReLU(inplace=True),
    )


class GraspTypeNet(nn.Module):
    """Small U-Net. The depth channel is turned into a validity mask, depth relative to the
    frame's mean valid depth, and absolute depth (metric size needs both), inside the graph, so
    graspd feeds metres as the contract says."""

    def __init__(self, w=(16, 32, 64, 96)):
        super().__init__()
        # The stem halves the resolution at once: full-resolution layers dominated the cost.
        self.e0 = nn.Sequential(block(6, w[0], 2), block(w[0], w[0]))
        self.e1 = nn.Sequential(block(w[0], w[1], 2), block(w[1], w[1]))
        self.e2 = nn.Sequential(block(w[1], w[2], 2), block(w[2], w[2], dilation=2))
        self.e3 = nn.Sequential(block(w[2], w[3], 2), block(w[3], w[3], dilation=2))
        self.d2 = block(w[3] + w[2], w[2])
        self.d1 = block(w[2] + w[1], w[1])
        self.d0 = block(w[1] + w[0], w[0])
        self.head = nn.Conv2d(w[0], 6, 1)

    def forward(self, x):
        rgb, d = x[:, :3], x[:, 3:4]
        valid = (d > 0).float()
        mean_d = (d * valid).sum((2, 3), keepdim=True) / valid.sum((2, 3), keepdim=True).clamp(min=1.0)
        rel = (d - mean_d) * valid * 10.0  # decimetres from the mean
        absolute = (d - 0.7) * valid * 3.0
        f = torch.cat([rgb, rel, absolute, valid], 1)
        f0 = self.e0(f)
        f1 = self.e1(f0)
        f2 = self.e2(f1)
        f3 = self.e3(f2)
        up = lambda a, size: F.interpolate(a, size=size, mode="bilinear", align_corners=False)
        g2 = self.d2(torch.cat([up(f3, f2.shape[2:]), f2], 1))
        g1 = self.d1(torch.cat([up(g2, f1.shape[2:]), f1], 1))
        g0 = self.d0(torch.cat([up(g1, f0.shape[2:]), f0], 1))
        # Logits at half resolution, interpolated to the input size (maps as sharp as the frame
        # allows without full-resolution convolutions).
        return up(self.head(g0), x.shape[2:])


# ---------------------------------------------------------------------------------------------
# Metrics


def evaluate(model, x, y, batch=32):
    """Per-type IoU at p >= 0.5 over all pixels, and the confusion matrix over labelled pixels:
    row = a true type of the pixel, column = the most probable predicted type (rows sum to 1)."""
    model.eval()
    inter = np.zeros(6)
    union = np.zeros(6)
    conf = np.zeros((6, 6))
    with torch.no_grad():
        for i in range(0, len(x), batch):
            logits = model(to_input(x[i : i + batch]))
            t = to_targets(y[i : i + batch]).numpy().astype(bool)
            p = torch.sigmoid(logits).numpy()
            pred = p >= 0.5
            inter += (pred & t).sum((0, 2, 3))
            union += (pred | t).sum((0, 2, 3))
            top = p.argmax(1)
            for s in range(6):
                conf[s] += np.bincount(top[t[:, s]], minlength=6)
    iou = inter / np.maximum(union, 1)
    conf = conf / np.maximum(conf.sum(1, keepdims=True), 1)
    return iou, conf


def table(iou, conf):
    lines = ["| " + " | ".join(TYPES) + " | mean |", "|" + "---|" * 7]
    lines.append("| " + " | ".join(f"{v:.2f}" for v in iou) + f" | {iou.mean():.2f} |")
    lines += ["", "Confusion (row: a true type of the pixel; column: most probable predicted type):", ""]
    lines.append("| true \\ predicted | " + " | ".join(TYPES) + " |")
    lines.append("|" + "---|" * 7)
    for s in range(6):
        lines.append(f"| {TYPES[s]} | " + " | ".join(f"{v:.2f}" for v in conf[s]) + " |")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Export


def export(model, path, w, h, check_x, info):
    import onnx
    import onnxruntime as ort

    model.eval()
    dummy = torch.zeros(1, 4, h, w)
    torch.onnx.export(
        model, dummy, path, input_names=["frame"], output_names=["logits"], opset_version=17, dynamo=False
    )
    m = onnx.load(path)
    meta = {
        "graspd.mean": ",".join(str(v) for v in MEAN),
        "graspd.std": ",".join(str(v) for v in STD),
        "graspd.model": "grasp-type U-Net (models/grasp_type/MODEL_CARD.md)",
        "graspd.types": ",".join(TYPES),
    }
    meta.update(info)
    for k, v in meta.items():
        e = m.metadata_props.add()
        e.key, e.value = k, str(v)
    onnx.checker.check_model(m)
    onnx.save(m, path)
    sess = ort.InferenceSession(path, providers=["CPUExecutionProvider"])
    worst = 0.0
    with torch.no_grad():
        for i in range(len(check_x)):
            xi = to_input(check_x[i : i + 1])
            ref = model(xi).numpy()
            got = sess.run(None, {"frame": xi.numpy()})[0]
            worst = max(worst, float(np.abs(ref - got).max()))
    if worst > 1e-3:
        raise SystemExit(f"ONNX Runtime disagrees with PyTorch by {worst} (> 1e-3)")
    return worst


# ---------------------------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", help="generated training split (x.npy, y.npy)")
    ap.add_argument("--val", help="generated validation split")
    ap.add_argument("--test", help="generated held-out test split")
    ap.add_argument("--data", help="own labelled frames (NAME_rgb.png, NAME_depth.png, NAME_labels.png)")
    ap.add_argument("--test-share", type=float, default=0.15, help="share of --data held out")
    ap.add_argument("--out", default=str(Path(__file__).parent), help="folder for grasp_type.onnx and metrics")
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--epochs", type=int, default=20)
    ap.add_argument("--batch", type=int, default=16)
    ap.add_argument("--lr", type=float, default=3e-3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--self-check", action="store_true",
                    help="check that the numpy resize matches graspd's on the generator's preview frames")
    args = ap.parse_args()
    torch.manual_seed(args.seed)
    np.random.seed(args.seed)
    torch.set_num_threads(args.threads)
    w, h = args.width, args.height

    if args.self_check:
        x, y = load_split(args.test)
        stems = sorted(str(p)[: -len("_rgb.png")] for p in Path(args.test).glob("*_rgb.png"))
        for s in stems:
            i = int(Path(s).name)
            xo, yo = load_own_frame(s, w, h)
            dc = np.abs(xo[:3] - x[i, :3]).max()
            dd = np.abs(xo[3] - x[i, 3]).max()
            print(f"{Path(s).name}: colour max diff {dc:.4f}, depth max diff {dd * 1000:.3f} mm, labels equal {np.array_equal(yo, y[i])}")
            assert dc < 1e-3 and dd < 6e-4 and np.array_equal(yo, y[i])
        return

    if args.data:
        x_all, y_all, stems = load_own_data(args.data, w, h)
        held = split_by_name(stems, args.test_share)
        xtr, ytr = x_all[~held], y_all[~held]
        xte, yte = x_all[held], y_all[held]
        xva, yva = xte, yte
        source = f"own data {args.data}: {len(xtr)} train, {len(xte)} held out"
    else:
        (xtr, ytr), (xva, yva), (xte, yte) = load_split(args.train), load_split(args.val), load_split(args.test)
        xtr, ytr = np.asarray(xtr), np.asarray(ytr)
        source = f"generated: {len(xtr)} train, {len(xva)} val, {len(xte)} test"
    print(source, flush=True)

    # Positive weights against the rarity of each type (sqrt of the negative/positive ratio).
    t = to_targets(ytr[: min(len(ytr), 2000)])
    pos = t.mean((0, 2, 3)).clamp(min=1e-4)
    pos_weight = ((1 - pos) / pos).sqrt().clamp(1.0, 8.0)
    print("type pixel shares", [f"{v:.4f}" for v in pos.tolist()], "pos_weight", [f"{v:.1f}" for v in pos_weight.tolist()])

    model = GraspTypeNet()
    opt = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    steps = args.epochs * (len(xtr) // args.batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=args.lr, total_steps=steps, pct_start=0.1)
    rng = np.random.default_rng(args.seed)
    best = (-1.0, None)
    started = time.time()
    for epoch in range(args.epochs):
        model.train()
        order = rng.permutation(len(xtr))
        total = 0.0
        for b in range(len(xtr) // args.batch):
            idx = np.sort(order[b * args.batch : (b + 1) * args.batch])
            xb, yb = to_input(xtr[idx]), to_targets(ytr[idx])
            if rng.random() < 0.5:  # mirror: grasp types do not depend on handedness of the view
                xb, yb = xb.flip(3), yb.flip(3)
            loss = F.binary_cross_entropy_with_logits(model(xb), yb, pos_weight=pos_weight[None, :, None, None])
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            total += loss.item()
        iou, _ = evaluate(model, xva, yva)
        print(f"epoch {epoch + 1}/{args.epochs}: loss {total / (len(xtr) // args.batch):.4f}, "
              f"val IoU {' '.join(f'{v:.2f}' for v in iou)} mean {iou.mean():.3f}, {time.time() - started:.0f} s",
              flush=True)
        if iou.mean() > best[0]:
            best = (iou.mean(), {k: v.clone() for k, v in model.state_dict().items()})
    model.load_state_dict(best[1])
    train_seconds = time.time() - started

    iou, conf = evaluate(model, xte, yte)
    report = table(iou, conf)
    print(report)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    onnx_path = str(out / "grasp_type.onnx")
    worst = export(model, onnx_path, w, h, xte[:8], {
        "graspd.train_data": source,
        "graspd.test_mean_iou": f"{iou.mean():.3f}",
    })
    metrics = {
        "source": source,
        "test_iou": dict(zip(TYPES, iou.round(4).tolist())),
        "test_mean_iou": round(float(iou.mean()), 4),
        "confusion": conf.round(4).tolist(),
        "onnx_max_abs_diff": worst,
        "train_seconds": round(train_seconds),
        "epochs": args.epochs,
        "parameters": sum(p.numel() for p in model.parameters()),
        "torch": torch.__version__,
    }
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    (out / "metrics.md").write_text(report + "\n")
    print(f"wrote {onnx_path} ({os.path.getsize(onnx_path) / 1e6:.2f} MB); ONNX Runtime vs PyTorch max |diff| {worst:.2e}")


if __name__ == "__main__":
    main()
