"""What the BioTac SP direction-of-slip recordings can and cannot show (issue 16, part 3).

Reads ../shared/testdata/tactile/biotac_sp/dos_basic (7 labels: the folder names n, s, e, w,
cw, aw and t for touch; 4 objects; ~280 frames of 24 electrodes each; no licence: measured on,
never trained into shipped weights) and prints one table: accuracy per feature set, classifier
and split. The point is the split:

- **by object** (leave one object out) and **by recording** (5 folds, a recording's frames all
  on one side) are the honest protocols;
- **windows at random** (5-frame windows, 5 folds, 1-nearest-neighbour) mixes windows of one
  recording into training and test, which is how a published per-window figure such as 82.6 %
  can be reached without sensing direction at all;
- **the first frame alone** (the reading before anything slides) is a control: it cannot know
  the direction, so whatever it scores above chance (1/7) is the recording setup (each label's
  recordings were made one after another, and the sensor's baseline drifts), not slip.

Feature sets (each recording, baseline its own first frame):
- `change`: the electrodes' final change, unit norm (24);
- `flow`: tactile optical flow, the brightness-constancy fit dI_i = -(v + w x r_i) . grad I_i on
  the schematic layout (service/sensors/biotac_sp.toml; gradients by weighted local planes over
  7 neighbours), summed over the recording: v_x, v_y, w, the pattern centred on its pressure
  centroid; plus the log of the largest and mean change (touch vs slide);
- `first frame`: the raw first reading (the control above).

    python slip_direction.py [--data DIR]
"""

from __future__ import annotations

import argparse
import glob
import os
import re

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_DATA = os.path.join(
    HERE, "..", "..", "..", "shared", "testdata", "tactile", "biotac_sp", "dos_basic"
)
# service/sensors/biotac_sp.toml, E1..E24 (mm, schematic).
LAYOUT = np.array([
    [0.0, -5.6], [-2.0, -4.2], [-8.0, -7.0], [-10.0, -5.6], [-12.0, -2.8], [-14.0, -7.0],
    [-16.0, -5.6], [-18.0, -1.4], [-20.0, -4.2], [-22.0, -5.6], [0.0, 5.6], [-2.0, 4.2],
    [-8.0, 7.0], [-10.0, 5.6], [-12.0, 2.8], [-14.0, 7.0], [-16.0, 5.6], [-18.0, 1.4],
    [-20.0, 4.2], [-22.0, 5.6], [-4.0, 0.0], [-6.0, -1.4], [-6.0, 1.4], [-10.0, 0.0],
])
SHRINK = 0.3  # covariance shrinkage of the discriminant (the calibration's classifier kind)
FLOW_STEP = 10  # frames between the two images of one flow fit


def load(root):
    """[(label, object, frames x 24)] in a fixed order."""
    out = []
    for label in sorted(os.listdir(root)):
        for path in sorted(glob.glob(os.path.join(root, label, "*.csv"))):
            obj = re.match(r"[a-z]+", os.path.basename(path)).group(0)
            out.append((label, obj, np.loadtxt(path, delimiter=",", skiprows=1)))
    return out


def gradient_operators(k=7, scale_mm=4.0):
    """Per electrode, the 2 x 24 map from the image to its spatial gradient (local plane)."""
    n = len(LAYOUT)
    ops = np.zeros((n, 2, n))
    for i in range(n):
        d = np.linalg.norm(LAYOUT - LAYOUT[i], axis=1)
        nb = np.argsort(d)[:k]
        a = np.c_[np.ones(k), LAYOUT[nb] - LAYOUT[i]]
        w = np.diag(np.exp(-((d[nb] / scale_mm) ** 2)))
        ops[i][:, nb] = np.linalg.solve(a.T @ w @ a + 1e-6 * np.eye(3), a.T @ w)[1:]
    return ops


GRAD = gradient_operators()


def smooth(x, w=5):
    k = np.ones(w) / w
    return np.array([np.convolve(x[:, j], k, mode="valid") for j in range(x.shape[1])]).T


def flow(x):
    """Summed (v_x, v_y, w) of the brightness-constancy fits over the recording."""
    img = smooth(x - x[0])
    total = np.zeros(3)
    for t in range(0, len(img) - FLOW_STEP, FLOW_STEP):
        a, b = img[t], img[t + FLOW_STEP]
        mid = (a + b) / 2
        g = np.einsum("iaj,j->ia", GRAD, mid)
        p = np.abs(mid)
        r = LAYOUT - (p @ LAYOUT) / (p.sum() + 1e-9)
        design = np.c_[g, -r[:, 1] * g[:, 0] + r[:, 0] * g[:, 1]]
        total += np.linalg.lstsq(design, -(b - a), rcond=1e-6)[0]
    return total


def features(x, kind):
    d = x - x[0]
    if kind == "change":
        e = smooth(d)[-1]
        return e / (np.linalg.norm(e) + 1e-9)
    if kind == "flow":
        mag = [np.log1p(np.abs(d).sum(1).max()), np.log1p(np.abs(np.diff(x, axis=0)).sum(1).mean())]
        return np.r_[flow(x), mag]
    if kind == "first frame":
        return x[0]
    raise ValueError(kind)


def discriminant(xtr, ytr, xte):
    """Shrunk-covariance linear discriminant (equal priors)."""
    classes = sorted(set(ytr))
    ytr = np.asarray(ytr)
    mu = np.array([xtr[ytr == c].mean(0) for c in classes])
    r = xtr - mu[[classes.index(c) for c in ytr]]
    s = r.T @ r / len(xtr)
    s = (1 - SHRINK) * s + SHRINK * np.trace(s) / len(s) * np.eye(len(s))
    si = np.linalg.pinv(s)
    score = xte @ si @ mu.T - 0.5 * np.einsum("kd,de,ke->k", mu, si, mu)
    return np.array(classes)[score.argmax(1)]


def nearest(xtr, ytr, xte):
    d = ((xte[:, None, :] - xtr[None, :, :]) ** 2).sum(-1)
    return np.asarray(ytr)[d.argmin(1)]


def accuracy(x, y, groups, classify):
    ok = 0
    for g in np.unique(groups):
        te = groups == g
        mu, sd = x[~te].mean(0), x[~te].std(0) + 1e-9
        pred = classify((x[~te] - mu) / sd, y[~te], (x[te] - mu) / sd)
        ok += int((pred == y[te]).sum())
    return ok / len(y)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=DEFAULT_DATA)
    args = ap.parse_args()
    data = load(args.data)
    y = np.array([label for label, _, _ in data])
    objects = np.array([obj for _, obj, _ in data])
    by_recording = np.arange(len(data)) % 5
    print(f"{len(data)} recordings, {len(set(y))} labels, objects {', '.join(sorted(set(objects.tolist())))}; "
          f"chance {1 / len(set(y)):.1%}\n")
    print("| features | classifier | by object | by recording |")
    print("|---|---|---:|---:|")
    for kind in ("change", "flow", "first frame"):
        x = np.array([features(f, kind) for _, _, f in data])
        for name, classify in (("discriminant", discriminant), ("1-nearest", nearest)):
            print(f"| {kind} | {name} | {accuracy(x, y, objects, classify):.1%} "
                  f"| {accuracy(x, y, by_recording, classify):.1%} |")
    # 5-frame windows of the raw readings, 1-nearest-neighbour, three splits.
    wx, wy, wrec, wobj = [], [], [], []
    for i, (label, obj, f) in enumerate(data):
        for t in range(0, len(f) - 5, 5):
            wx.append(f[t:t + 5].ravel())
            wy.append(label)
            wrec.append(i % 5)
            wobj.append(obj)
    wx, wy = np.array(wx, float), np.array(wy)
    at_random = np.random.default_rng(0).integers(0, 5, len(wy))
    print(f"\n5-frame windows of the raw readings ({len(wy)}), 1-nearest-neighbour:")
    print("| split | accuracy |")
    print("|---|---:|")
    for name, groups in (("windows at random", at_random), ("by recording", np.array(wrec)),
                         ("by object", np.array(wobj))):
        print(f"| {name} | {accuracy(wx, wy, groups, nearest):.1%} |")


if __name__ == "__main__":
    main()
