"""Proximal policy optimisation (Stable-Baselines3) on isotrack's vector environment: 16 runs of
the paper's field stepped in Rust per call, SB3's `VecEnv` API through `isotrack.gym.SB3VecEnv`.

    pip install "./python[examples]" stable-baselines3    # from the repository root (brings torch)
    python examples/python/train_sb3.py [timesteps]        # default 100 000 steps

Prints the mean episode return before and after training (the same seeds for both), each
episode a 60 s run at 10 Hz (600 steps). The policy sees only (eps_m, deps_m).
"""

from __future__ import annotations

import sys

import numpy as np

import isotrack
from isotrack.gym import SB3VecEnv


def mean_return(model, env, seed: int) -> float:
    """Mean undiscounted return of one episode per run, the policy acting deterministically."""
    env.seed(seed)
    obs = env.reset()
    total = np.zeros(env.num_envs)
    alive = np.ones(env.num_envs, dtype=bool)
    while alive.any():
        action, _ = model.predict(obs, deterministic=True)
        obs, reward, done, _ = env.step(action)
        total += np.where(alive, reward, 0.0)
        alive &= ~done
    return float(total.mean())


def main(timesteps: int = 100_000, num_envs: int = 16, seed: int = 0) -> dict:
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor

    scenario = (
        isotrack.Scenario.default()
        .set("sim.duration_s", 60.0)
        .set("sensor.rate_hz", 10.0)
        .set("sensor.noise_std", 0.01)
    )
    env = VecMonitor(SB3VecEnv(scenario, num_envs=num_envs))
    model = PPO("MlpPolicy", env, seed=seed, device="cpu", verbose=0)
    before = mean_return(model, env, seed=1000)
    model.learn(total_timesteps=timesteps)
    after = mean_return(model, env, seed=1000)
    print(f"mean return over {num_envs} runs: {before:.1f} before, {after:.1f} after {timesteps} steps")
    return {"before": before, "after": after}


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 100_000)
