"""Learning curves of the in-hand runs (the dissertation's Fig 7.7): per task, the success rate
of the training episodes against environment steps for each algorithm (smoothed over five
rollouts), the drops beside it, and docs/in-hand/results.md with the final evaluation and the
steps each algorithm needed to reach given success rates."""

import argparse
import csv
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ORDER = ["ppo", "ppo_hand", "ppo_unc", "composite", "marl"]
LEVELS = [0.05, 0.2, 0.5, 0.8]


def smooth(x, k=5):
    x = np.asarray(x, dtype=float)
    out = np.empty_like(x)
    for i in range(len(x)):
        w = x[max(0, i - k + 1):i + 1]
        w = w[~np.isnan(w)]
        out[i] = w.mean() if len(w) else np.nan
    return out


def steps_to(steps, rate, level):
    hit = np.flatnonzero(rate >= level)
    return int(steps[hit[0]]) if len(hit) else None


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--runs", required=True, help="RUNS/TASK/ALGO/{curve.csv,metrics.json}")
    p.add_argument("--docs", required=True)
    args = p.parse_args()
    os.makedirs(args.docs, exist_ok=True)
    lines = ["# In-hand rotation: learning curves and evaluation", "",
             "Made by `models/in_hand/plot.py` from the runs of `models/in_hand/train.sh` "
             "(docs/in-hand.md). Success: the orientation within 0.1 rad of the target at the "
             "episode's end (Eq 7.12). Steps to a rate: the first rollout whose success rate, "
             "smoothed over five rollouts, reaches it.", ""]
    for task in sorted(os.listdir(args.runs)):
        tdir = os.path.join(args.runs, task)
        if not os.path.isdir(tdir):
            continue
        algos = [a for a in ORDER if os.path.exists(os.path.join(tdir, a, "metrics.json"))]
        if not algos:
            continue
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
        lines += [f"## {task}", "",
                  "| algorithm | steps | final success (deterministic) | drops | "
                  + " | ".join(f"steps to {int(l * 100)} %" for l in LEVELS) + " | train time |",
                  "|---|---:|---:|---:|" + "---:|" * len(LEVELS) + "---:|"]
        for algo in algos:
            with open(os.path.join(tdir, algo, "curve.csv")) as f:
                rows = list(csv.DictReader(f))
            with open(os.path.join(tdir, algo, "metrics.json")) as f:
                m = json.load(f)
            steps = np.array([int(r["steps"]) for r in rows])
            rate = smooth([float(r["success_rate"]) for r in rows])
            drop = smooth([float(r["drop_rate"]) for r in rows])
            ax1.plot(steps, rate, label=algo)
            ax2.plot(steps, drop, label=algo)
            ev = m["evaluation"]
            reach = [steps_to(steps, rate, l) for l in LEVELS]
            lines.append(
                f"| {algo} | {m['steps']:,} | {100 * ev['success_rate']:.1f} % "
                f"({ev['episodes']} episodes) | {100 * ev['drop_rate']:.1f} % | "
                + " | ".join(f"{r:,}" if r is not None else "not reached" for r in reach)
                + f" | {m['train_seconds'] / 60:.0f} min |")
        ax1.set(title=f"{task} rotation: success rate", xlabel="environment steps",
                ylabel="episodes ending within 0.1 rad", ylim=(0, 1))
        ax2.set(title=f"{task} rotation: object dropped", xlabel="environment steps",
                ylabel="episodes", ylim=(0, 1))
        ax1.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(args.docs, f"{task}.png"), dpi=90)
        plt.close(fig)
        lines += ["", f"![{task}]({task}.png)", ""]
    with open(os.path.join(args.docs, "results.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
