"""The learning curve of docs/environment.md: a tiny evolution strategy over a linear drop policy, in NumPy.

The agents of ``agent-assisted-office`` (two agents, the frontier explorer moving them: ``motion="builtin"``) learn
when to drop a router from six numbers of their observation. Each iteration draws ``POP`` antithetic perturbations of
the weights, scores each by the team's return over one episode (common seeds across the population), and moves the
weights along the return-weighted perturbations. Writes ``docs/env-learning.png``; about 3 minutes on one core.

    .venv/bin/python tools/env_learning_curve.py
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from amronet.env import deployment_env, policies

ITERATIONS, POP, SIGMA, STEP, EPISODE = 12, 4, 0.5, 0.3, 400
OUT = Path(__file__).resolve().parents[1] / "docs" / "env-learning.png"


def features(obs: dict) -> np.ndarray:
    """Six numbers an agent knows: a relay heard, its distance and margin (scaled), stock, connected, bias."""
    relay = obs["relay"]
    return np.array([relay[0], relay[1] / 6.0, relay[2] / 30.0, obs["stock"][0], obs["flags"][0], 1.0])


def episode(env, w: np.ndarray | None, seed: int) -> float:
    """The team's return with the linear policy ``w`` (``None``: the paper's rule)."""
    paper = policies.LastReference(env)
    obs, _ = env.reset(seed=seed)
    total = 0.0
    while env.agents:
        if w is None:
            actions = paper(obs)
        else:
            actions = {a: int(features(obs[a]) @ w > 0) for a in env.agents}
        obs, rewards, *_ = env.step(actions)
        total += sum(rewards.values())
    return total


def main() -> None:
    """Train, and draw the curve with the paper's rule as the line to beat."""
    env = deployment_env(overrides={"agents.per_base": 2}, max_steps=EPISODE, motion="builtin", actions="discrete",
                         seed=0)
    rng = np.random.default_rng(1)
    w = np.zeros(6)
    w[5] = -1.0  # start by never dropping
    curve, paper = [], []
    for it in range(ITERATIONS):
        seed = 100 + it
        eps = rng.standard_normal((POP, 6))
        up = np.array([episode(env, w + SIGMA * e, seed) for e in eps])
        down = np.array([episode(env, w - SIGMA * e, seed) for e in eps])
        w = w + STEP / (2 * POP * SIGMA) * ((up - down) / (np.std(np.concatenate([up, down])) + 1e-9)) @ eps
        curve.append(episode(env, w, 999))
        paper.append(episode(env, None, 999))
        print(f"iteration {it + 1}: return {curve[-1]:.1f} (paper's rule {paper[-1]:.1f}), weights {np.round(w, 2)}")
    fig, ax = plt.subplots(figsize=(6, 3.2))
    ax.plot(np.arange(1, ITERATIONS + 1), curve, marker="o", label="linear policy (evolution strategy)")
    ax.axhline(paper[-1], color="grey", ls="--", label="the paper's drop rule")
    ax.set_xlabel("iteration")
    ax.set_ylabel("team return, held-out seed")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT, dpi=110)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
