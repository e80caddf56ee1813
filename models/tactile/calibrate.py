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
    phase_items = []
    for mat, cls in REAL_CLASSES.items():
        for n in CALIBRATION_SAMPLES:
            base = os.path.join(data, mat, f"{mat}_{n}")
            b = sim.read_bio_csv(base + "_bio.csv")
            labels, fz, speed = real_labels(b["timestamp"], base + "_cw.csv", base + "_cv.csv")
            _, feats = sim.detector_samples(b["tdc"], b["tac"], b["pdc"], b["pac"], b["electrodes"],
                                            "pretared")
            by_class[cls].append((feats, labels))
            force[cls].append(fz[labels > 0])
            phase_items.append((feats, speed, b["pac"].mean(axis=1)))
    out = {"phases": _phase_stats(phase_items)}
    for cls, items in by_class.items():
        f = np.concatenate([x[0] for x in items])
        l = np.concatenate([x[1] for x in items])
        out[cls] = summarise(f, l)
        out[cls]["fz_in_contact"] = [round(float(x), 2) for x in np.percentile(np.concatenate(force[cls]), PCT)]
    return out


def _phase_stats(items) -> dict:
    """Label-free / event-phase statistics pooled over all materials (no per-material value):
    `items` are (features, arm speed m/s, pac frame mean) per recording; "moving" = arm speed
    >= 5 mm/s (the slide phase), no force or material used."""
    vib, lag1, lag10, sd1s, dpdc, first_moving, floor = [], [], [], [], [], [], []
    pdc_by_second = [[] for _ in range(8)]
    for feats, speed, pac_mean in items:
        mv = speed >= sim.SLIP_SPEED
        vib.extend(feats[mv, 2])
        for lag, out in ((1, lag1), (10, lag10)):
            m = mv[lag:] & mv[:-lag]
            out.extend((pac_mean[lag:] - pac_mean[:-lag])[m])
        dp = np.diff(feats[:, 0])
        dpdc.extend(dp[mv[1:] & mv[:-1]])
        for t in range(100, len(feats), 10):
            if mv[t]:
                sd1s.append(pac_mean[t - 99 : t + 1].std())
        moving = np.flatnonzero(mv)
        first_moving.append(int(moving[0]) if len(moving) else len(mv))
        floor.append(np.percentile(pac_mean, 5))
        for k in range(8):
            pdc_by_second[k].extend(feats[k * 100 : (k + 1) * 100, 0])
    pct = lambda v: [round(float(x), 2) for x in np.percentile(v, PCT)]  # noqa: E731
    return {
        "about": "pooled over all materials, samples 1-10; moving = arm planar speed >= 5 mm/s",
        "moving_fraction": round(float(np.mean([len(i[1]) and (i[1] >= sim.SLIP_SPEED).mean() for i in items])), 4),
        "first_moving_frame": pct(first_moving),
        "pac_vibration_moving": pct(vib),
        "pac_mean_lag1_diff_std_moving": round(float(np.std(lag1)), 1),
        "pac_mean_lag10_diff_std_moving": round(float(np.std(lag10)), 1),
        "pac_mean_1s_std_moving": pct(sd1s),
        "pac_mean_p5_per_recording": pct(floor),
        "pdc_frame_diff_std_moving": round(float(np.std(dpdc)), 2),
        "pdc_median_by_second": [round(float(np.median(v)), 1) for v in pdc_by_second if v],
    }


def generated_stats(seed: int, count: int) -> dict:
    seqs = [s for s in sim.generate_set(seed, count) if s.style == "pretared"]
    feats_of = {id(s): sim.detector_samples(s.tdc, s.tac, s.pdc, s.pac, s.electrodes, s.style)[1] for s in seqs}
    out = {"phases": _phase_stats([(feats_of[id(s)], s.speed, s.pac.mean(axis=1)) for s in seqs])}
    for cls in sim.MATERIALS:
        fs, ls = [], []
        for s in seqs:
            if s.material != cls:
                continue
            fs.append(feats_of[id(s)])
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
    for key in result["generated"]["phases"]:
        if key != "about":
            print(f"{key}: real {result.get('real', {}).get('phases', {}).get(key)}  generated {result['generated']['phases'][key]}")
    print("label fractions real", {c: result.get("real", {}).get(c, {}).get("label_fraction") for c in sim.MATERIALS})
    print("label fractions gen ", {c: result["generated"][c]["label_fraction"] for c in sim.MATERIALS})


if __name__ == "__main__":
    main()
