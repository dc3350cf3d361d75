"""Figures of a cyclic plan (matplotlib, imported lazily): postures, boundary, 500 cycles.

Consumers only (DESIGN.md principle 6): nothing here is imported by the planner. Each function
returns a matplotlib ``Figure``; :func:`png` turns one into bytes for ``case.attach``.
"""

from __future__ import annotations

import io

import numpy as np

__all__ = ["postures_figure", "cycles_figure", "png"]


def png(fig) -> bytes:
    """The figure as PNG bytes (and closes it)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()


def postures_figure(plan, n_postures: int = 16, boundary=None, title: str = ""):
    """Postures over one period with the path, moving bases and obstacles (the paper's Figs.
    7, 8, 11), and optionally a :class:`~drake_mh.cyclic.problem.Boundary` (Figs. 2a, 3).

    Args:
        plan: a :class:`~drake_mh.cyclic.planner.CyclicPlan`.
        n_postures: arm drawings over one period.
        boundary: optional boundary of one component to draw beside the postures.
        title: figure title.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from drake_mh.cyclic.task import ThreeLinkComponent

    task = plan.task
    ncols = 2 if boundary is not None else 1
    fig, axes = plt.subplots(1, ncols, figsize=(6.5 * ncols, 5.5), squeeze=False)
    ax = axes[0, 0]
    t = np.linspace(0, plan.period, 400)
    for c in task.components:
        if isinstance(c, ThreeLinkComponent):
            p = c.target.position(t)
            ax.plot(p[:, 0], p[:, 1], lw=1.0, ls="-" if c is task.components[-1] else "--")
    for o in task.obstacles:
        ax.add_patch(plt.Circle(o.centre, o.radius, color="0.6", alpha=0.6))
    ts = np.linspace(0, plan.period, n_postures, endpoint=False)
    Q = plan.q(ts)
    colors = plt.cm.viridis(np.linspace(0, 1, n_postures))
    for q, col in zip(Q, colors):
        phi = np.cumsum(q)
        pts = np.vstack([[0.0, 0.0], np.cumsum(np.asarray(task.lengths)[:, None]
                                               * np.stack([np.cos(phi), np.sin(phi)], -1), axis=0)])
        ax.plot(pts[:, 0], pts[:, 1], "-o", color=col, lw=1.2, ms=2)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or f"{task.name}: postures over one period, k = {np.round(plan.ks, 4).tolist()}")
    if boundary is not None:
        bx = axes[0, 1]
        bx.plot(boundary.r, boundary.theta_g_min, "k-", lw=1, label="reachable band (eqs. 13-15)")
        bx.plot(boundary.r, boundary.theta_g_max, "k-", lw=1)
        bx.plot(boundary.r, boundary.shrunk_min, "r--", lw=1, label="shrunk (limits, obstacles)")
        bx.plot(boundary.r, boundary.shrunk_max, "r--", lw=1)
        for lo, hi in boundary.k_intervals:
            bx.axhspan(lo, hi, color="tab:green", alpha=0.2)
        bx.axhline(plan.ks[-1], color="tab:blue", label=f"k = {plan.ks[-1]:.4f}")
        bx.set_xlabel("r = t/T")
        bx.set_ylabel("θg [rad]")
        bx.set_title("local orientation-angle boundary, last component")
        bx.legend(fontsize=7)
    fig.tight_layout()
    return fig


def cycles_figure(pinv_t, pinv_q, pinv_drift, plan_report, plan, lower, upper, first_last: int = 20):
    """The paper's Figs. 12-13: pseudoinverse joint trajectories over all cycles, the
    proposed plan's first and last ``first_last`` cycles, and the drift per cycle of both.

    Args:
        pinv_t, pinv_q: ``(K,)`` [s], ``(K, n)`` [rad] recorded pseudoinverse trajectory.
        pinv_drift: ``(C + 1,)`` ``max |q(cT) - q(0)|`` of the pseudoinverse run [rad].
        plan_report: :class:`~drake_mh.cyclic.verify.CycleReport` of the plan.
        plan: the plan. lower, upper: ``(n,)`` joint limits [rad].
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    T = plan.period
    C = len(pinv_drift) - 1
    fig, axes = plt.subplots(2, 2, figsize=(13, 8))
    ax = axes[0, 0]
    ax.plot(pinv_t / T, pinv_q, lw=0.5)
    ax.set_title(f"pseudoinverse Jacobian, {C} cycles (Fig. 12)")
    ax.set_xlabel("cycle")
    ax.set_ylabel("joint angle [rad]")
    for i in np.flatnonzero(np.asarray(lower) == 0.0):
        ax.axhline(0.0, color="k", lw=0.5, ls=":")
        ax.axhline(upper[i], color="k", lw=0.5, ls=":")
    n = min(first_last, C)
    tf = np.linspace(0, n * T, 40 * n + 1)
    tl = tf + (C - n) * T
    axes[0, 1].plot(tf / T, plan.q(tf), lw=0.7)
    axes[0, 1].set_title(f"proposed, cycles 0-{n} (Fig. 13a)")
    axes[1, 1].plot(tl / T, plan.q(tl), lw=0.7)
    axes[1, 1].set_title(f"proposed, cycles {C - n}-{C} (Fig. 13b)")
    for a in (axes[0, 1], axes[1, 1]):
        a.set_xlabel("cycle")
        a.set_ylabel("joint angle [rad]")
    ax = axes[1, 0]
    cycles = np.arange(C + 1)
    ax.semilogy(cycles[1:], np.maximum(pinv_drift[1:], 1e-17), label="pseudoinverse")
    ax.semilogy(cycles[1:], np.maximum(plan_report.drift[1: C + 1], 1e-17), label="proposed")
    ax.set_xlabel("cycle c")
    ax.set_ylabel("max_j |q_j(cT) - q_j(0)| [rad]")
    ax.set_title("joint-space drift (closure error)")
    ax.legend()
    fig.tight_layout()
    return fig
