"""Figures of ESM runs in the layout of the ESM paper's Fig. 4 (matplotlib, imported lazily).

(a) closest distance robot-obstacle vs the threshold d, (b) manipulability vs the
approximate optimum μ*, (c) tracking error (log scale).
"""

from __future__ import annotations

import io

import numpy as np


def plot_runs(runs, mu_opt=None, title: str = ""):
    """A 3-panel figure (Fig. 4 layout) of one or more :class:`drake_mh.reactive.esm.ESMRun` s.

    Args:
        runs: an ``ESMRun`` or a sequence of them (one line per run, labelled by solver).
        mu_opt: the approximate optimum: a number, or an array over the runs' time samples.
        title: figure title.

    Returns:
        The matplotlib ``Figure``.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    runs = [runs] if hasattr(runs, "t") else list(runs)
    fig, axes = plt.subplots(3, 1, figsize=(7.0, 7.5), sharex=True)
    for run in runs:
        label = f"{run.solver} ({run.budget})" if run.budget else run.solver
        axes[0].plot(run.t, run.min_distance, label=label)
        axes[1].plot(run.t, run.mu, label=label)
        axes[2].semilogy(run.t, np.maximum(run.error, 1e-17), label=label)
    if runs:
        axes[0].axhline(runs[0].threshold, color="r", ls="--", label=f"threshold d = {runs[0].threshold} m")
    if mu_opt is not None:
        mu_line = np.broadcast_to(np.asarray(mu_opt, dtype=float), runs[0].t.shape) if runs else mu_opt
        axes[1].plot(runs[0].t, mu_line, "b:", label="approximate optimum μ*")
    axes[0].set_ylabel("closest distance [m]")
    axes[1].set_ylabel("manipulability μ")
    axes[2].set_ylabel("tracking error [m]")
    axes[2].set_xlabel("t [s]")
    for ax, tag in zip(axes, "abc"):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
        ax.set_title(f"({tag})", loc="left", fontsize=9)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def figure_png(runs, mu_opt=None, title: str = "") -> bytes:
    """:func:`plot_runs` rendered as PNG bytes (for ``Case.attach``)."""
    import matplotlib.pyplot as plt

    fig = plot_runs(runs, mu_opt, title)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return buf.getvalue()
