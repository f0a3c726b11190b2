"""isotrack from Python in one page: run the paper's Fig. 2(b) scenario, plot the field, the
target isoline and the path with matplotlib, and fly your own controller in the same loop.

    pip install "./python[examples]"       # from the repository root: isotrack, matplotlib, gymnasium
    python examples/python/quickstart.py   # writes quickstart.png

The figure: left, the circular field F = 20 exp(-0.1 |p|) with the target isoline s_d = 10 (a circle
of radius ln(2)/0.1 = 6.93 m) and both paths from (10, 0) m; right, the tracking error of each law.
The paper's PI-like law (integral on) ends on the isoline (error ~1e-14); the P-like law written
below in Python (ki = 0) settles on a slightly larger circle with the closed-form offset
|eps*| = c2 * atanh(v / (kp * c1 * d*)) (docs/BASELINES.md, section 0).
"""

from __future__ import annotations

import math
import sys

import numpy as np

import isotrack


class PLaw:
    """The paper's law without its integral: omega = kp * (deps/dt + c1 * tanh(eps / c2)), with
    eps = s - s_d and deps/dt the backward difference of the samples. It sees only what a
    coordinate-free controller sees: the sample time and the measured value."""

    def __init__(self, level: float, kp: float = 10.0, c1: float = 0.2, c2: float = 1.0):
        self.level, self.kp, self.c1, self.c2 = level, kp, c1, c2
        self.prev = None

    def reset(self) -> None:
        self.prev = None

    def update(self, t_s: float, value: float) -> float:
        eps = value - self.level
        deps = 0.0 if self.prev is None else (eps - self.prev[1]) / (t_s - self.prev[0])
        self.prev = (t_s, eps)
        return self.kp * (deps + self.c1 * math.tanh(eps / self.c2))


def main(out_path: str = "quickstart.png") -> dict:
    """Runs both laws, draws the figure to ``out_path`` and returns the numbers it shows."""
    import matplotlib

    matplotlib.use("Agg")  # a file, no window: works on a server and in CI
    import matplotlib.pyplot as plt

    scenario = isotrack.Scenario.default()  # the paper's Fig. 2(b): s_d = 10, v = 0.5 m/s, 100 Hz
    pi_run = scenario.run()
    p_run = scenario.run(controller=PLaw(level=10.0))

    # The field on a grid, vectorised (NaN where a field has no value).
    xs = np.linspace(-15.0, 15.0, 301)
    X, Y = np.meshgrid(xs, xs)
    F = scenario.field_values(X, Y)

    fig, (ax, ax_err) = plt.subplots(1, 2, figsize=(11, 4.8))
    im = ax.pcolormesh(X, Y, F, shading="auto", cmap="viridis")
    fig.colorbar(im, ax=ax, label="field value")
    ax.contour(X, Y, F, levels=[10.0], colors="white", linewidths=2.0, linestyles="--")
    for run, label, color, lw in (
        (p_run, "P law (Python)", "orange", 2.5),
        (pi_run, "paper's PI law (built in)", "red", 1.0),
    ):
        ax.plot(run.trace["x_m"], run.trace["y_m"], color=color, lw=lw, label=label)
        ax_err.semilogy(run.trace["t_s"], np.abs(run.trace["error"]) + 1e-16, color=color, label=label)
    ax.plot([10.0], [0.0], "ko", label="start")
    ax.set(xlabel="x (m)", ylabel="y (m)", title="Field, isoline s_d = 10 (dashed) and paths", aspect="equal")
    ax.legend(loc="lower left", fontsize=8)
    ax_err.set(xlabel="t (s)", ylabel="|s - s_d|", title="Tracking error")
    ax_err.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_path, dpi=110)
    plt.close(fig)

    # The P law's closed-form offset: d* solves c1*tanh((F(d) - s_d)/c2) + v/(kp*d) = 0.
    def g(d: float) -> float:
        return 0.2 * math.tanh(20 * math.exp(-0.1 * d) - 10.0) + 0.5 / (10.0 * d)

    lo, hi = math.log(2.0) / 0.1, 60.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if g(mid) > 0 else (lo, mid)
    closed_form = 20 * math.exp(-0.1 * lo) - 10.0
    numbers = {
        "pi_steady_max_abs_error": pi_run.summary["steady_state_max_abs_error"],
        "p_steady_mean_error": p_run.summary["steady_state_mean_error"],
        "p_closed_form_error": closed_form,
    }
    for k, v in numbers.items():
        print(f"{k:>26}: {v:.6g}")
    print(f"figure: {out_path}")
    return numbers


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "quickstart.png")
