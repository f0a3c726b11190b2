#!/usr/bin/env python3
"""The paper's Fig. 2(b) scenario written the way a user would write it in plain Python:
Dong & You's PI-like law on a Dubins robot, circular field 20*exp(-0.1*|p|), level 10,
v = 0.5 m/s, kp = 10, ki = 1, c1 = 0.2, c2 = 1, dt = 0.01 s, 600 s, RK4 with the turn rate held,
backward-difference derivative, start (10, 0, -pi/2). The same model and numbers as isotrack's
built-in default, for a side-by-side speed measurement (see BENCHMARKS.md).

    python3 benches/python/dubins_peer.py          # prints the final error and the time
"""
import math
import time


def run(duration_s=600.0, dt=0.01):
    i0, k, level = 20.0, 0.1, 10.0
    v, kp, ki, c1, c2 = 0.5, 10.0, 1.0, 0.2, 1.0
    x, y, th = 10.0, 0.0, -math.pi / 2
    sigma = 0.0
    prev_eps = None
    n = int(round(duration_s / dt))
    eps = 0.0
    for _ in range(n + 1):
        s = i0 * math.exp(-k * math.hypot(x, y))
        eps = s - level
        if prev_eps is None:  # first sample: no derivative yet, nothing to integrate
            e = c1 * math.tanh(eps / c2)
        else:
            e = (eps - prev_eps) / dt + c1 * math.tanh(eps / c2)
            sigma += e * dt
        prev_eps = eps
        omega = kp * e + ki * sigma
        # RK4 with omega held: heading is linear in time, position by Simpson's rule.
        h1 = (math.cos(th), math.sin(th))
        h2 = (math.cos(th + 0.5 * omega * dt), math.sin(th + 0.5 * omega * dt))
        h4 = (math.cos(th + omega * dt), math.sin(th + omega * dt))
        x += v * dt / 6.0 * (h1[0] + 4.0 * h2[0] + h4[0])
        y += v * dt / 6.0 * (h1[1] + 4.0 * h2[1] + h4[1])
        th += omega * dt
    return n, eps


if __name__ == "__main__":
    t0 = time.perf_counter()
    steps, eps = run()
    dt = time.perf_counter() - t0
    print(f"{steps} steps in {dt:.3f} s = {steps / dt / 1e6:.3f} M steps/s; final eps = {eps:.3e}")
