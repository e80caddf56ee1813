"""The training's own arithmetic against hand-computed values (run by train.sh before training;
`python -m pytest models/in_hand`): r_unc (Eq 7.7), GAE, and the identity of Eq 7.10 that lets
the value agents' advantages combine linearly."""

import numpy as np

from marl_ppo import ALGORITHMS, BETA, gae, uncertainty_reward


def test_eq_7_7_by_hand():
    got = uncertainty_reward([0.0, 0.19, 0.2, 12.6, 25.0, 25.1])
    # 1.5 below 0.2; (d − 0.2) / 24.8 over [0.2, 25]; −10 beyond.
    want = [1.5, 1.5, 0.0, 0.5, 1.0, -10.0]
    assert np.allclose(got, want)


def test_gae_by_hand():
    # One environment, three steps, the episode ending at the last: γ = 0.5, λ = 0.5.
    r = np.array([[1.0], [0.0], [2.0]])
    v = np.array([[0.5], [1.0], [0.0]])
    v1 = np.array([[1.0], [0.0], [4.0]])  # the last is cut: the episode ended
    done = np.array([[0.0], [0.0], [1.0]])
    # δ = (1 + 0.5·1 − 0.5, 0 + 0.5·0 − 1, 2 − 0) = (1, −1, 2)
    # A₂ = 2, A₁ = −1 + 0.25·2 = −0.5, A₀ = 1 + 0.25·(−0.5) = 0.875
    assert np.allclose(gae(r, v, v1, done, 0.5, 0.5)[:, 0], [0.875, -0.5, 2.0])


def test_composite_advantage_is_the_weighted_sum_of_the_agents_advantages():
    # Eq 7.10: GAE is linear in (r, V), so the advantage of Σβ r with Σβ V is Σβ of each
    # agent's own; the MARL setting differs from `composite` in how the values are learned.
    rng = np.random.default_rng(0)
    beta = np.array([BETA[n] for n in ALGORITHMS["marl"][0]])
    r, v, v1 = (rng.normal(size=(7, 4, 3)) for _ in range(3))
    done = (rng.random((7, 4)) < 0.2).astype(float)
    whole = gae((r * beta).sum(-1), (v * beta).sum(-1), (v1 * beta).sum(-1), done, 0.99, 0.95)
    parts = sum(b * gae(r[..., i], v[..., i], v1[..., i], done, 0.99, 0.95)
                for i, b in enumerate(beta))
    assert np.allclose(whole, parts)
