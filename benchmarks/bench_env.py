"""Throughput of the learning environments in env-steps/s (docs/environment.md, *Speed*).

An env-step is one step of one environment with every one of its agents acting (random actions; for the routers a
settle wish at 0.2 % per step); an agent-step is one agent's share of it (env-steps/s times the agents of one
environment). Single PettingZoo environments, then the vectorised router environment over G seeds in one batch.
Rates are per second of this process's CPU time (one core: nothing here runs threads below 30 000 robots), so that
other jobs on a shared machine do not count. ``.venv/bin/python benchmarks/bench_env.py`` (about a minute).
"""

from __future__ import annotations

import time

import numpy as np

from amronet.env import deployment_env, router_env
from amronet.env.vector import VecRouterEnv

STEPS = 150
RNG = np.random.default_rng(0)


def single(env) -> float:
    env.reset(seed=1)
    env.step({a: env.action_space(a).sample() for a in env.agents})  # (compiles what is left to compile)
    t, n = time.process_time(), 0
    while env.agents and n < STEPS:
        actions = {}
        for a in env.agents:
            act = env.action_space(a).sample()
            if env.possible_agents[0].startswith("router"):
                act[-1] = float(RNG.random() < 0.002)
            actions[a] = act
        env.step(actions)
        n += 1
    return n / (time.process_time() - t)


def vector(g: int, motion: str) -> tuple[float, int]:
    """Env-steps/s of ``G`` runs in one batch, and the routers of one run."""
    env = VecRouterEnv(seeds=list(range(1, g + 1)), max_steps=10 * STEPS, motion=motion, actions="discrete")
    rng = np.random.default_rng(0)
    shape = env.live.shape

    def act() -> np.ndarray:
        wish = rng.random(shape) < 0.002
        return wish.astype(np.int64) if motion == "builtin" else np.stack([rng.integers(0, 4, shape), wish], -1)

    env.step(act())
    t = time.process_time()
    for _ in range(STEPS // 2):
        env.step(act())
    return g * (STEPS // 2) / (time.process_time() - t), shape[1]


def main() -> None:
    """Print env-steps/s (and agent-steps/s) of each case."""
    print(f"{'case':48s} {'env-steps/s':>12s} {'agent-steps/s':>14s}")
    for name, env in (("agents (agent-assisted-office, 3 agents)", deployment_env(max_steps=10 * STEPS)),
                      ("routers (self-spreading-obstacles-6x6, 30)", router_env(max_steps=10 * STEPS))):
        rate = single(env)
        print(f"{name:48s} {rate:12.0f} {rate * len(env.possible_agents):14.0f}")
    for g in (1, 16, 64, 256):
        for motion in ("policy", "builtin"):
            rate, agents = vector(g, motion)
            print(f"{f'vectorised routers, G = {g:3d}, motion {motion}':48s} {rate:12.0f} {rate * agents:14.0f}")


if __name__ == "__main__":
    main()
