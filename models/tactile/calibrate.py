"""Measures the statistics the generator's ranges were set from, on the real recordings and on
generated data, and writes both side by side to calibration.json (MODEL_CARD.md, "Calibration").

Only samples 1-10 of each material of ../shared/testdata/tactile/biotac_slide are read here
(the calibration split); samples 11-20 are left for the real-data evaluation. Nothing from the
recordings becomes a training sample: only the percentiles below are written.

    python calibrate.py [--data DIR] [--out calibration.json]
"""

from __future__ import annotations

import argparse
import json
import os

import numpy as np

import biotac_sim as sim

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_DATA = os.path.join(HERE, "..", "..", "..", "shared", "testdata", "tactile", "biotac_slide")
# README "Material classes used by this project".
REAL_CLASSES = {
    "mat5": "plastic", "mat8": "paper", "mat9": "plastic", "mat10": "plastic", "mat13": "plastic",
    "mat14": "paper", "mat17": "foam", "mat18": "foam", "mat19": "foam", "mat20": "metal",
}
CALIBRATION_SAMPLES = range(1, 11)
PCT = [5, 25, 50, 75, 95]


def read_series(path: str, cols: list[str]):
    """`_cw.csv` / `_cv.csv`: timestamp and the named columns (`-nan` allowed)."""
    with open(path) as f:
        lines = [l.strip().rstrip(",") for l in f if l.strip()]
    names = lines[0].split(",")
    a = np.array([[float(x) if "nan" not in x else np.nan for x in l.split(",")] for l in lines[1:]])
    return a[:, names.index("timestamp")], [a[:, names.index(c)] for c in cols]


def real_labels(bio_ts, cw_path, cv_path):
    """recording.rs: contact iff interpolated fz >= 0.5 N, slip iff also planar speed >= 0.005."""
    tw, (fz,) = read_series(cw_path, ["fz"])
    tv, (vx, vy) = read_series(cv_path, ["x", "y"])
    interp = lambda t, v: np.interp(bio_ts, t[np.isfinite(v)], v[np.isfinite(v)])  # noqa: E731
    f = interp(tw, fz)
    sp = np.hypot(interp(tv, vx), interp(tv, vy))
    return np.where(f < sim.CONTACT_FORCE_N, 0, np.where(sp >= sim.SLIP_SPEED, 2, 1)), f, sp


def summarise(feats: np.ndarray, labels: np.ndarray) -> dict:
    """Percentiles of the detector features over in-contact frames."""
    m = labels > 0
    top3 = np.sort(feats[:, 5:], axis=1)[:, -3:].mean(axis=1)
    out = {}
    for name, v in [("pdc", feats[:, 0]), ("pac_mean", feats[:, 1]), ("pac_vibration", feats[:, 2]),
                    ("tdc", feats[:, 3]), ("tac", feats[:, 4]), ("electrode_top3", top3)]:
        out[name] = [round(float(x), 2) for x in np.percentile(v[m], PCT)] if m.any() else None
    out["label_fraction"] = [round(float((labels == k).mean()), 4) for k in range(3)]
    out["frames"] = int(len(labels))
    return out


def real_stats(data: str) -> dict:
    by_class: dict[str, list] = {c: [] for c in sim.MATERIALS}
    force: dict[str, list] = {c: [] for c in sim.MATERIALS}
    for mat, cls in REAL_CLASSES.items():
        for n in CALIBRATION_SAMPLES:
            base = os.path.join(data, mat, f"{mat}_{n}")
            b = sim.read_bio_csv(base + "_bio.csv")
            labels, fz, _ = real_labels(b["timestamp"], base + "_cw.csv", base + "_cv.csv")
            _, feats = sim.detector_samples(b["tdc"], b["tac"], b["pdc"], b["pac"], b["electrodes"],
                                            "pretared")
            by_class[cls].append((feats, labels))
            force[cls].append(fz[labels > 0])
    out = {}
    for cls, items in by_class.items():
        f = np.concatenate([x[0] for x in items])
        l = np.concatenate([x[1] for x in items])
        out[cls] = summarise(f, l)
        out[cls]["fz_in_contact"] = [round(float(x), 2) for x in np.percentile(np.concatenate(force[cls]), PCT)]
    return out


def generated_stats(seed: int, count: int) -> dict:
    seqs = [s for s in sim.generate_set(seed, count) if s.style == "pretared"]
    out = {}
    for cls in sim.MATERIALS:
        fs, ls = [], []
        for s in seqs:
            if s.material != cls:
                continue
            _, feats = sim.detector_samples(s.tdc, s.tac, s.pdc, s.pac, s.electrodes, s.style)
            fs.append(feats)
            ls.append(s.labels)
        out[cls] = summarise(np.concatenate(fs), np.concatenate(ls))
        out[cls]["fz_in_contact"] = [round(float(x), 2) for x in np.percentile(
            np.concatenate([s.force[s.labels > 0] for s in seqs if s.material == cls]), PCT)]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default=DEFAULT_DATA)
    ap.add_argument("--out", default=os.path.join(HERE, "calibration.json"))
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    result = {
        "about": "Percentiles (5, 25, 50, 75, 95) of detector features over in-contact frames. "
                 "real: biotac_slide samples 1-10 per material (calibration split), features "
                 "as graspd computes them with TareConfig::pretared(); generated: the "
                 "pretared-style sequences of biotac_sim.generate_set(seed, 400).",
        "percentiles": PCT,
        "generated": generated_stats(args.seed, 400),
    }
    if os.path.isdir(args.data):
        result["real"] = real_stats(args.data)
    else:
        print(f"{args.data} not found: writing generated statistics only")
    with open(args.out, "w") as f:
        json.dump(result, f, indent=1)
    for key in ("pdc", "electrode_top3", "pac_vibration", "tdc", "tac", "pac_mean", "fz_in_contact"):
        print(key)
        for cls in sim.MATERIALS:
            r = result.get("real", {}).get(cls, {}).get(key)
            g = result["generated"][cls][key]
            print(f"  {cls:8s} real {r}  generated {g}")
    print("label fractions real", {c: result.get("real", {}).get(c, {}).get("label_fraction") for c in sim.MATERIALS})
    print("label fractions gen ", {c: result["generated"][c]["label_fraction"] for c in sim.MATERIALS})


if __name__ == "__main__":
    main()
