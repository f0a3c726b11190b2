"""The Python package's speed (issue: isotrack from Python). Run from the repository root in the
virtual environment that has the package (`scripts/test-python.sh` makes one in target/pyenv):

    target/pyenv/bin/python benches/python/bench_python.py

It prints, best of several repeats (one core for the engine):
- `Scenario.default().run()`: load + run + the 10 Hz trace as numpy arrays; compare with the
  criterion bench `default_scenario/load_warn_and_run_trace_10hz` (the CLI's in-process work):
  `cargo bench -p isotrack-scenario --bench sweep -- "^default_scenario/"`;
- a Python controller in the loop (100 Hz: every step is a sample), trivial and the paper's P law;
- the vector environment, 256 environments, constant actions and a numpy policy.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

import isotrack
from isotrack.gym import IsolineVectorEnv

os.environ.setdefault("RAYON_NUM_THREADS", "1")


def best_of(f, repeats=7):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


class Hold:
    def update(self, t_s, value):
        return 0.1


class PLaw:
    def __init__(self):
        self.prev = None

    def update(self, t_s, value):
        eps = value - 10.0
        d = 0.0 if self.prev is None else (eps - self.prev[1]) / (t_s - self.prev[0])
        self.prev = (t_s, eps)
        return 10.0 * (d + 0.2 * math.tanh(eps))


def main():
    sc = isotrack.Scenario.default()
    t = best_of(lambda: isotrack.Scenario.default().run())
    print(f"Scenario.default().run() (load, run, 10 Hz trace): {t * 1e3:.2f} ms per 600 s run ({60000 / t / 1e6:.2f} M steps/s)")
    t = best_of(lambda: sc.run(record_rate_hz=0.0))
    print(f"scenario.run(record_rate_hz=0): {t * 1e3:.2f} ms")
    for name, c in (("trivial (returns a constant)", Hold), ("paper's P law", PLaw)):
        t = best_of(lambda: sc.run(record_rate_hz=0.0, controller=c()), repeats=3)
        print(f"Python controller, {name}: {60001 / t / 1e6:.2f} M samples/s ({t:.3f} s per run)")
    n, steps = 256, 2000
    env = IsolineVectorEnv(sc, num_envs=n)
    env.reset(seed=0)
    a = np.full((n, 1), 0.05)

    def constant():
        for _ in range(steps):
            env.step(a)

    t = best_of(constant, repeats=3)
    print(f"IsolineVectorEnv({n}), constant actions: {n * steps / t / 1e6:.2f} M env steps/s")
    obs, _ = env.reset(seed=0)

    def policy():
        o = obs
        for _ in range(steps):
            o = env.step((2.0 * o[:, 1] + 0.5 * np.tanh(o[:, 0]))[:, None])[0]

    t = best_of(policy, repeats=3)
    print(f"IsolineVectorEnv({n}), numpy policy on the observation: {n * steps / t / 1e6:.2f} M env steps/s")


if __name__ == "__main__":
    main()
