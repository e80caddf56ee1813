"""Trains one algorithm of dissertation §7.5.2 on one rotation task (docs/in-hand.md): rollouts
from `graspd-sim in-hand-env` (vec_env.py), PPO with one value agent per reward (marl_ppo.py).
Writes OUT/curve.csv (one row per rollout: environment steps, success rate of the episodes that
ended, returns per reward), OUT/metrics.json (the final deterministic evaluation) and, with
--export, OUT/policy.onnx (raw state → joint-target action in [−1, 1], the state standardisation
inside)."""

import argparse
import csv
import json
import os
import time

import numpy as np
import torch

from marl_ppo import ALGORITHMS, BETA, Dynamics, Policy, RunningNorm, Values, gae, uncertainty_reward
from vec_env import InHandVecEnv


def parse():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--sim", required=True, help="the graspd-sim binary")
    p.add_argument("--graspd", required=True, help="graspd's gRPC address (for the synergies)")
    p.add_argument("--testdata", required=True)
    p.add_argument("--object", choices=["block", "egg"], default="block")
    p.add_argument("--rotation", choices=["z", "xyz"], default="z")
    p.add_argument("--algo", choices=sorted(ALGORITHMS), default="marl")
    p.add_argument("--steps", type=int, default=200_000, help="environment steps")
    p.add_argument("--envs", type=int, default=16)
    p.add_argument("--workers", type=int, default=2, help="graspd-sim processes (cores)")
    p.add_argument("--rollout", type=int, default=2048, help="steps per rollout (N_rollout)")
    p.add_argument("--epochs", type=int, default=10, help="optimisation passes (N_opt)")
    p.add_argument("--batch", type=int, default=256)
    p.add_argument("--lr", type=float, default=3e-4, help="initial rate, decayed linearly")
    p.add_argument("--optimizer", choices=["adam", "sgd"], default="adam",
                   help="sgd: the dissertation's SGD with momentum 0.9 (use --lr 1e-4)")
    p.add_argument("--gamma", type=float, default=0.99)
    p.add_argument("--lam", type=float, default=0.95)
    p.add_argument("--clip", type=float, default=0.2)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--eval-episodes", type=int, default=32)
    p.add_argument("--export", action="store_true", help="write policy.onnx")
    p.add_argument("--out", required=True)
    return p.parse_args()


class Exported(torch.nn.Module):
    """The deterministic policy on raw states: standardise, mean action, clip to [−1, 1]."""

    def __init__(self, policy, norm):
        super().__init__()
        self.policy = policy
        self.register_buffer("mean", torch.tensor(norm.mean, dtype=torch.float32))
        self.register_buffer("std", torch.tensor(np.sqrt(norm.var + 1e-8), dtype=torch.float32))

    def forward(self, state):
        s = torch.clamp((state - self.mean) / self.std, -10.0, 10.0)
        return torch.clamp(self.policy.mean(s), -1.0, 1.0)


def evaluate(args, policy, norm, episodes):
    """Success rate of the deterministic policy (mean action) over `episodes` episodes from
    seeds the training never drew; success is the orientation within 0.1 rad at the episode's
    end (Eq 7.12)."""
    envs = min(args.envs, episodes)
    env = InHandVecEnv(args.sim, args.graspd, args.testdata, args.object, args.rotation,
                       envs, args.workers, 1_000_000 + args.seed * 1000)
    s = env.reset()
    ended, successes, drops, angles = 0, 0, 0, []
    while ended < episodes:
        with torch.no_grad():
            a = policy.mean(torch.tensor(norm(s), dtype=torch.float32)).clamp(-1, 1).numpy()
        _, s, _, _, angle, done, success, dropped = env.step(a)
        for k in np.flatnonzero(done):
            if ended < episodes:
                ended += 1
                successes += int(success[k])
                drops += int(dropped[k])
                angles.append(float(angle[k]))
    env.close()
    return {"episodes": ended, "success_rate": successes / ended, "drop_rate": drops / ended,
            "median_final_angle_rad": float(np.median(angles))}


def main():
    args = parse()
    os.makedirs(args.out, exist_ok=True)
    torch.manual_seed(args.seed)
    torch.set_num_threads(1)
    rng = np.random.default_rng(args.seed)
    names, single = ALGORITHMS[args.algo]
    beta = np.array([BETA[n] for n in names])
    heads = 1 if single else len(names)
    head_beta = np.ones(1) if single else beta
    env = InHandVecEnv(args.sim, args.graspd, args.testdata, args.object, args.rotation,
                       args.envs, args.workers, args.seed * 1000)
    d, m, n_env = env.state_dim, env.action_dim, env.envs
    horizon = max(1, args.rollout // n_env)
    norm = RunningNorm(d)
    policy, values, dynamics = Policy(d, m), Values(d, heads), Dynamics(d, m)
    uses_unc = "unc" in names
    params = list(policy.parameters()) + list(values.parameters())
    if uses_unc:
        params += list(dynamics.parameters())
    if args.optimizer == "sgd":
        opt = torch.optim.SGD(params, lr=args.lr, momentum=0.9)
    else:
        opt = torch.optim.Adam(params, lr=args.lr)
    s = env.reset()
    steps, t0 = 0, time.time()
    ep_ret = np.zeros((n_env, 3))
    rows = []
    while steps < args.steps:
        for g in opt.param_groups:
            g["lr"] = args.lr * max(0.0, 1.0 - steps / args.steps)
        S = np.zeros((horizon, n_env, d), np.float32)
        S1 = np.zeros_like(S)
        A = np.zeros((horizon, n_env, m), np.float32)
        LOGP = np.zeros((horizon, n_env), np.float32)
        R = np.zeros((horizon, n_env, 3))
        DONE = np.zeros((horizon, n_env))
        finished = []
        for t in range(horizon):
            sn = norm(s).astype(np.float32)
            with torch.no_grad():
                dist = policy.dist(torch.tensor(sn))
                a = dist.sample()
                logp = dist.log_prob(a).sum(-1)
            s1, s_next, r_ext, r_hand, angle, done, success, dropped = env.step(a.clamp(-1, 1).numpy())
            S[t], S1[t], A[t], LOGP[t] = sn, norm(s1), a.numpy(), logp.numpy()
            R[t, :, 0], R[t, :, 1], DONE[t] = r_ext, r_hand, done
            ep_ret[:, :2] += np.stack([r_ext, r_hand], 1)
            for k in np.flatnonzero(done):
                finished.append((bool(success[k]), bool(dropped[k]), float(angle[k]), ep_ret[k].copy()))
                ep_ret[k] = 0
            s = s_next
        steps += horizon * n_env
        flat = lambda x: torch.tensor(x.reshape(horizon * n_env, -1))
        St, S1t, At = flat(S), flat(S1), flat(A)
        # r_unc (Eq 7.7) from the transition model's error before this update (its mean per step
        # is logged: it is known only after the rollout).
        if uses_unc:
            with torch.no_grad():
                d_unc = ((S1t - dynamics(St, At)) ** 2).sum(-1).numpy().reshape(horizon, n_env)
            R[:, :, 2] = uncertainty_reward(d_unc)
        streams = np.stack([R[:, :, ["ext", "hand", "unc"].index(n)] for n in names], -1)
        if single:
            streams = (streams * beta).sum(-1, keepdims=True)
        with torch.no_grad():
            V = values(St).numpy().reshape(horizon, n_env, heads)
            V1 = values(S1t).numpy().reshape(horizon, n_env, heads)
        # The advantage of the composite value and reward (Eq 7.9, 7.10); each agent's own
        # TD(λ) target (Eq 7.8).
        adv = gae((streams * head_beta).sum(-1), (V * head_beta).sum(-1), (V1 * head_beta).sum(-1),
                  DONE, args.gamma, args.lam)
        targets = np.stack([gae(streams[..., i], V[..., i], V1[..., i], DONE, args.gamma, args.lam)
                            + V[..., i] for i in range(heads)], -1)
        ADV, TGT = flat(adv.astype(np.float32)), flat(targets.astype(np.float32))
        LP = flat(LOGP).squeeze(-1)
        n = horizon * n_env
        for _ in range(args.epochs):
            for idx in np.array_split(rng.permutation(n), max(1, n // args.batch)):
                idx = torch.tensor(idx)
                s_b, a_b = St[idx], At[idx]
                dist = policy.dist(s_b)
                ratio = (dist.log_prob(a_b).sum(-1) - LP[idx]).exp()
                adv_b = ADV[idx].squeeze(-1)
                adv_b = (adv_b - adv_b.mean()) / (adv_b.std() + 1e-8)
                l_clip = -torch.min(ratio * adv_b,
                                    ratio.clamp(1 - args.clip, 1 + args.clip) * adv_b).mean()
                l_v = ((values(s_b) - TGT[idx]) ** 2).mean(0).sum()
                loss = l_clip + 0.5 * l_v
                if uses_unc:
                    loss = loss + ((dynamics(s_b, a_b) - S1t[idx]) ** 2).sum(-1).mean()
                opt.zero_grad()
                loss.backward()
                torch.nn.utils.clip_grad_norm_(params, 0.5)
                opt.step()
        norm.update(np.concatenate([S, S1]).reshape(-1, d) * np.sqrt(norm.var + 1e-8) + norm.mean)
        row = {"steps": steps, "episodes": len(finished),
               "success_rate": np.mean([f[0] for f in finished]) if finished else float("nan"),
               "drop_rate": np.mean([f[1] for f in finished]) if finished else float("nan"),
               "final_angle": np.mean([f[2] for f in finished]) if finished else float("nan"),
               "return_ext": np.mean([f[3][0] for f in finished]) if finished else float("nan"),
               "return_hand": np.mean([f[3][1] for f in finished]) if finished else float("nan"),
               "mean_r_unc": float(R[:, :, 2].mean()) if uses_unc else float("nan"),
               "seconds": round(time.time() - t0, 1)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    env.close()
    with open(os.path.join(args.out, "curve.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    metrics = {"algorithm": args.algo, "object": args.object, "rotation": args.rotation,
               "steps": steps, "seed": args.seed, "train_seconds": round(time.time() - t0, 1),
               "evaluation": evaluate(args, policy, norm, args.eval_episodes),
               "settings": {k: v for k, v in vars(args).items()
                            if k not in ("sim", "graspd", "testdata", "out")}}
    with open(os.path.join(args.out, "metrics.json"), "w") as f:
        json.dump(metrics, f, indent=2)
    print(json.dumps(metrics["evaluation"]))
    if args.export:
        export(policy, norm, d, os.path.join(args.out, "policy.onnx"))


def export(policy, norm, d, path):
    """policy.onnx (input `state` [batch, d], output `action` [batch, m]), checked against
    PyTorch through ONNX Runtime."""
    model = Exported(policy, norm).eval()
    x = torch.randn(4, d) * torch.tensor(np.sqrt(norm.var), dtype=torch.float32) \
        + torch.tensor(norm.mean, dtype=torch.float32)
    torch.onnx.export(model, (x,), path, input_names=["state"], output_names=["action"],
                      dynamic_axes={"state": {0: "batch"}, "action": {0: "batch"}},
                      opset_version=17, dynamo=False)
    import onnxruntime as ort
    got = ort.InferenceSession(path).run(None, {"state": x.numpy()})[0]
    want = model(x).detach().numpy()
    assert np.abs(got - want).max() < 1e-4, "ONNX export differs from PyTorch"


if __name__ == "__main__":
    main()
