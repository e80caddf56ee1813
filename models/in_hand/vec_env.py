"""The in-hand rotation task (dissertation §7.5) as `graspd-sim in-hand-env` serves it over a pipe
(clients/sim/src/in_hand/env_server.rs): the scene, state, action, r_ext (Eq 7.12) and r_hand
(Eq 7.5) are the simulator's own, so the policy trains on what graspd-sim scores it on. Several
server processes (one per core) each step a share of the environments."""

import json
import subprocess

import numpy as np


class InHandVecEnv:
    """`envs` environments split over `workers` `graspd-sim in-hand-env` processes; episodes
    restart by themselves (see `step`)."""

    def __init__(self, sim, graspd, testdata, obj, rotation, envs, workers, seed):
        share = [envs // workers + (1 if k < envs % workers else 0) for k in range(workers)]
        share = [n for n in share if n > 0]
        self.procs, self.sizes, first = [], share, seed
        for n in share:
            cmd = [sim, "--graspd", graspd, "--testdata", testdata, "in-hand-env",
                   "--object", obj, "--rotation", rotation, "--envs", str(n),
                   "--seed", str(first)]
            p = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
            line = p.stdout.readline()
            if not line:
                raise RuntimeError(f"graspd-sim in-hand-env did not start: {' '.join(cmd)}")
            self.header = json.loads(line)
            self.procs.append(p)
            first += n
        self.envs = sum(share)
        self.state_dim = self.header["state_dim"]
        self.action_dim = self.header["action_dim"]
        self.episode_steps = self.header["episode_steps"]
        self.joints = self.header["joints"]

    def _read(self, p, count):
        buf = p.stdout.read(4 * count)
        if len(buf) != 4 * count:
            raise RuntimeError("graspd-sim in-hand-env stopped answering")
        return np.frombuffer(buf, dtype="<f4")

    def reset(self):
        """s₀ of every environment, (envs, state_dim)."""
        for p in self.procs:
            p.stdin.write(b"R")
            p.stdin.flush()
        return np.concatenate([self._read(p, n * self.state_dim).reshape(n, -1)
                               for p, n in zip(self.procs, self.sizes)])

    def step(self, actions):
        """One control step of every environment with `actions` (envs, action_dim) in [−1, 1].
        Returns (s_{t+1}, next state to act on — s₀ of a new episode where one ended —, r_ext,
        r_hand, angle to the target, done, success, dropped)."""
        a = np.asarray(actions, dtype="<f4").reshape(self.envs, self.action_dim)
        start = 0
        for p, n in zip(self.procs, self.sizes):
            p.stdin.write(b"S" + a[start:start + n].tobytes())
            p.stdin.flush()
            start += n
        row = 2 * self.state_dim + 4
        rows = np.concatenate([self._read(p, n * row).reshape(n, row)
                               for p, n in zip(self.procs, self.sizes)])
        d = self.state_dim
        flags = rows[:, 2 * d + 3].astype(np.int64)
        return (rows[:, :d], rows[:, d:2 * d], rows[:, 2 * d].astype(np.float64),
                rows[:, 2 * d + 1].astype(np.float64), rows[:, 2 * d + 2].astype(np.float64),
                (flags & 1) > 0, (flags & 2) > 0, (flags & 4) > 0)

    def close(self):
        for p in self.procs:
            try:
                p.stdin.write(b"Q")
                p.stdin.flush()
                p.stdin.close()
            except (BrokenPipeError, ValueError):
                pass
            p.wait(timeout=10)
