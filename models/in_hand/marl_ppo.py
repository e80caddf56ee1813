"""PPO with several value agents (dissertation §7.4, Algorithm 6): one policy, one value head per
reward (a shared two-layer trunk, Fig 7.5), advantages from the composite value
V_comp = Σ βᵢ Vᵢ (Eq 7.9) and the composite reward (GAE, Eq 7.10), a transition model whose
prediction error is the uncertainty reward (Eq 7.6, 7.7), all optimised together (Eq 7.11).

The algorithms of §7.5.2 are this one with different reward sets:
  ppo        r_ext                       (one value agent)
  ppo_hand   r_ext, r_hand               (two value agents)
  ppo_unc    r_ext, r_unc                (two value agents)
  marl       r_ext, r_hand, r_unc        (three value agents: the method)
  composite  β₁ r_ext + β₂ r_hand + β₃ r_unc as one reward (one value agent: the single-agent
             baseline the MARL setting is compared with)
"""

import numpy as np
import torch
from torch import nn

BETA = {"ext": 1.0, "hand": 0.5, "unc": 0.1}
ALGORITHMS = {
    "ppo": (["ext"], False),
    "ppo_hand": (["ext", "hand"], False),
    "ppo_unc": (["ext", "unc"], False),
    "marl": (["ext", "hand", "unc"], False),
    "composite": (["ext", "hand", "unc"], True),
}


def uncertainty_reward(d_unc):
    """r_unc of Eq 7.7 for the prediction error d_unc (squared distance, normalised state):
    1.5 below 0.2, rising linearly from 0 to 1 over [0.2, 25], −10 beyond."""
    d = np.asarray(d_unc, dtype=np.float64)
    return np.where(d < 0.2, 1.5, np.where(d <= 25.0, (d - 0.2) / (25.0 - 0.2), -10.0))


class RunningNorm:
    """Running mean and variance of the states (the networks see standardised states)."""

    def __init__(self, dim):
        self.mean, self.var, self.count = np.zeros(dim), np.ones(dim), 1e-4

    def update(self, x):
        m, v, n = x.mean(0), x.var(0), len(x)
        total = self.count + n
        delta = m - self.mean
        self.mean = self.mean + delta * n / total
        self.var = (self.var * self.count + v * n + delta ** 2 * self.count * n / total) / total
        self.count = total

    def __call__(self, x):
        return np.clip((x - self.mean) / np.sqrt(self.var + 1e-8), -10, 10)


def mlp(sizes, last=None):
    layers = []
    for i in range(len(sizes) - 1):
        layers.append(nn.Linear(sizes[i], sizes[i + 1]))
        if i < len(sizes) - 2:
            layers.append(nn.Tanh())
    if last is not None:
        layers.append(last)
    return nn.Sequential(*layers)


class Policy(nn.Module):
    """π(a|s): three tanh layers of 256 (§7.5.1) to the Gaussian's mean; a learned log σ."""

    def __init__(self, state_dim, action_dim):
        super().__init__()
        self.mean = mlp([state_dim, 256, 256, 256, action_dim])
        self.log_std = nn.Parameter(torch.full((action_dim,), -1.2))

    def dist(self, s):
        return torch.distributions.Normal(self.mean(s), self.log_std.exp())


class Values(nn.Module):
    """Vᵢ(s) for each reward: a shared trunk of two tanh layers, then per agent one tanh layer and
    the value (Fig 7.5)."""

    def __init__(self, state_dim, heads):
        super().__init__()
        self.trunk = mlp([state_dim, 256, 256], last=nn.Tanh())
        self.heads = nn.ModuleList([mlp([256, 256, 1]) for _ in range(heads)])

    def forward(self, s):
        h = self.trunk(s)
        return torch.cat([head(h) for head in self.heads], dim=-1)


class Dynamics(nn.Module):
    """f(s, a) → ŝ_{t+1} (Eq 7.6), in standardised states, predicted as a change."""

    def __init__(self, state_dim, action_dim):
        super().__init__()
        self.net = mlp([state_dim + action_dim, 256, 256, state_dim])

    def forward(self, s, a):
        return s + self.net(torch.cat([s, a], dim=-1))


def gae(rewards, values, next_values, dones, gamma, lam):
    """GAE(γ, λ) advantages over a (T, N) rollout; the value of s_{t+1} is cut where an episode
    ended."""
    adv = np.zeros_like(rewards)
    last = np.zeros(rewards.shape[1])
    for t in reversed(range(len(rewards))):
        notdone = 1.0 - dones[t]
        delta = rewards[t] + gamma * next_values[t] * notdone - values[t]
        last = delta + gamma * lam * notdone * last
        adv[t] = last
    return adv
