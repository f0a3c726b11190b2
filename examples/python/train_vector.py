"""A minimal training loop against isotrack's vector environment: no RL library, a (1+1)
evolution strategy on a two-gain policy, 64 environments stepped in Rust per call.

    pip install "./python[examples]"           # from the repository root
    python examples/python/train_vector.py     # about ten seconds

The policy sees only the observation (eps_m, deps_m) (the measured error and its sampled
difference) and commands omega = k1 * deps_m + k2 * tanh(eps_m / c2), the shape of the paper's law
without its integral. Each candidate is scored by the mean return of 64 runs from random starts
(the same seeds for every candidate, so that scores compare); a candidate that scores better
replaces the incumbent. Swap in any learner that speaks Gymnasium's vector API.
"""

from __future__ import annotations

import sys

import numpy as np

import isotrack
from isotrack.gym import IsolineVectorEnv


def evaluate(env: IsolineVectorEnv, gains: np.ndarray, seed: int, c2: float = 1.0) -> float:
    """Mean undiscounted return of one run per sub-environment (runs that end early count up to
    their end: the environment charges leaving the field)."""
    obs, _ = env.reset(seed=seed)
    total = np.zeros(env.num_envs)
    alive = np.ones(env.num_envs, dtype=bool)
    while alive.any():
        omega = gains[0] * obs[:, 1] + gains[1] * np.tanh(obs[:, 0] / c2)
        obs, reward, terminated, truncated, _ = env.step(omega[:, None])
        total += np.where(alive, reward, 0.0)
        alive &= ~(terminated | truncated)
    return float(total.mean())


def main(iterations: int = 40, num_envs: int = 64, duration_s: float = 60.0, seed: int = 0) -> dict:
    # The paper's field and robot, a 60 s episode, a noisy sensor (what makes it a learning task).
    scenario = isotrack.Scenario.default().set("sim.duration_s", duration_s).set("sensor.noise_std", 0.01)
    env = IsolineVectorEnv(scenario, num_envs=num_envs, max_turn_rate_radps=1.0)
    rng = np.random.default_rng(seed)
    gains = np.array([0.5, 0.05])
    best = first = evaluate(env, gains, seed=seed)
    print(f"iteration  0: gains {gains.round(3)}  mean return {best:10.2f}")
    step = 0.5
    for it in range(1, iterations + 1):
        candidate = np.abs(gains + step * rng.normal(size=2) * np.maximum(gains, 0.05))
        score = evaluate(env, candidate, seed=seed)
        if score > best:
            gains, best = candidate, score
            step *= 1.5
        else:
            step *= 0.85
        print(f"iteration {it:2d}: gains {gains.round(3)}  mean return {best:10.2f}")
    return {"first_return": first, "best_return": best, "gains": gains}


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 40)
