"""Report figures: convergence curves, box plots, joint trajectories.

matplotlib is imported inside the functions (object-oriented ``Figure`` API, rendered
with the Agg canvas), so importing drake_mh never imports it and no display is needed.
"""

from __future__ import annotations

import io
import logging
import warnings
from dataclasses import dataclass

import numpy as np

from drake_mh.study.report.data import ReportData, method_of

logger = logging.getLogger(__name__)

MAX_PANELS = 6


@dataclass(frozen=True)
class FigureFile:
    """A rendered figure.

    Attributes:
        name: file stem (``figures/<name>.png``).
        png: PNG bytes.
        caption: one sentence.
    """

    name: str
    png: bytes
    caption: str


def _figure(width: float, height: float):
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=100, layout="constrained")


def _render(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()


def _colors(methods: list[str]) -> dict[str, str]:
    # tab10, then darker tones: 16 methods before a colour repeats (12 optimizers in one study)
    cycle = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf",
             "#000000", "#393b79", "#637939", "#8c6d31", "#843c39", "#7b4173"]
    return {m: cycle[i % len(cycle)] for i, m in enumerate(methods)}


def best_so_far_on_grid(nfe: np.ndarray, best: np.ndarray, grid: np.ndarray, lower_is_better: bool) -> np.ndarray:
    """Samples a best-so-far history on an nfe grid (step function; NaN before the first point).

    Args:
        nfe: ``(K,)`` non-decreasing function-evaluation counts.
        best: ``(K,)`` objective values at those counts (made monotone here).
        grid: ``(G,)`` counts to sample at.
        lower_is_better: orientation of ``best``.

    Returns:
        ``(G,)`` best-so-far values.
    """
    nfe = np.asarray(nfe, dtype=float).ravel()
    best = np.asarray(best, dtype=float).ravel()
    count = min(nfe.size, best.size)
    nfe, best = nfe[:count], best[:count]
    monotone = np.fmin.accumulate(best) if lower_is_better else np.fmax.accumulate(best)
    index = np.searchsorted(nfe, grid, side="right") - 1
    out = np.full(grid.shape, np.nan)
    valid = index >= 0
    out[valid] = monotone[index[valid]]
    return out


def convergence_figure(data: ReportData) -> FigureFile | None:
    """Median and IQR band of best-so-far vs function evaluations, per method.

    One panel per value combination of ``fields.panels`` (rows of up to 6), else one per value
    of the first instance key when it has 2..6 values, else one panel.
    Returns ``None`` when no record has ``history_nfe`` and ``history_best`` arrays.
    """
    histories = []
    for record in data.records:
        if record.get("status") != "ok" or not record.get("arrays"):
            continue
        arrays = data.store.load_arrays(record)
        if "history_nfe" in arrays and "history_best" in arrays and arrays["history_nfe"].size:
            histories.append((record, arrays["history_nfe"], arrays["history_best"]))
    if not histories:
        return None
    if data.fields.panels:
        panel_keys = tuple(data.fields.panels)
    else:
        panel_keys = (data.instance_keys[0],) if data.instance_keys else ()
        if not 2 <= len({str(r.get(panel_keys[0])) for r, _, _ in histories} if panel_keys else ()) <= MAX_PANELS:
            panel_keys = ()

    def panel_of(record) -> tuple:
        return tuple(record.get(k) for k in panel_keys)

    panel_values = sorted({panel_of(r) for r, _, _ in histories}, key=lambda v: [(str(type(x)), x) for x in v])
    columns = min(len(panel_values), MAX_PANELS)
    rows = -(-len(panel_values) // columns)
    colors = _colors(data.methods)
    fig = _figure(4.2 * columns, 3.4 * rows)
    axes = fig.subplots(rows, columns, squeeze=False).ravel()
    for ax in axes[len(panel_values):]:
        ax.set_visible(False)
    for ax, panel in zip(axes, panel_values):
        chosen = [h for h in histories if panel_of(h[0]) == panel]
        top = max(float(np.max(h[1])) for h in chosen)
        low = max(1.0, min(float(np.min(h[1])) for h in chosen))
        grid = np.unique(np.geomspace(low, top, 200)) if top > low else np.array([low])
        positive = True
        for method in data.methods:
            curves = [
                best_so_far_on_grid(n, b, grid, data.fields.lower_is_better)
                for r, n, b in chosen
                if method_of(r, data.fields) == method
            ]
            if not curves:
                continue
            stack = np.vstack(curves)
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns before first eval
                q25, median, q75 = np.nanpercentile(stack, [25, 50, 75], axis=0)
            positive &= bool(np.all(stack[np.isfinite(stack)] > 0))
            ax.plot(grid, median, color=colors[method], label=f"{method} (n={len(curves)})")
            ax.fill_between(grid, q25, q75, color=colors[method], alpha=0.2, linewidth=0)
        ax.set_xscale("log" if top / low > 50 else "linear")
        if positive:
            ax.set_yscale("log")
        ax.set_xlabel("function evaluations")
        ax.set_ylabel("best so far")
        ax.set_title(", ".join(f"{k} = {v}" for k, v in zip(panel_keys, panel)) if panel_keys else data.name,
                     fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    caption = "Best-so-far objective vs function evaluations: median (line) and interquartile range (band) over cases."
    return FigureFile("convergence", _render(fig), caption)


def box_figure(data: ReportData) -> FigureFile | None:
    """Box plots of time and error per method (cases that did not raise)."""
    panels = [(f, label) for f, label in ((data.fields.time, "time"), (data.fields.error, "error")) if data.has_field(f)]
    if not panels:
        return None
    groups = data.by_method()
    fig = _figure(max(4.0, 1.0 + 0.9 * len(groups)) * len(panels), 3.4)
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    for ax, (field_name, _label) in zip(axes, panels):
        values = [data.values(records, field_name) for records in groups.values()]
        labels = list(groups)
        keep = [i for i, v in enumerate(values) if v.size]
        if not keep:
            continue
        values = [values[i] for i in keep]
        labels = [labels[i] for i in keep]
        ax.boxplot(values, tick_labels=labels, showfliers=True)
        everything = np.concatenate(values)
        if np.all(everything > 0) and everything.max() / everything.min() > 100:
            ax.set_yscale("log")
        ax.set_ylabel(field_name)
        ax.tick_params(axis="x", labelrotation=30, labelsize=8)
        ax.grid(True, axis="y", alpha=0.3)
    caption = "Distribution per method over cases that did not raise (box: quartiles, whiskers: 1.5 IQR)."
    return FigureFile("boxplots", _render(fig), caption)


def trajectory_figure(data: ReportData, per_method: int = 1) -> FigureFile | None:
    """Joint trajectories ``traj_q(traj_t)`` of the first case(s) per method that saved them."""
    chosen = []
    for method, records in data.by_method().items():
        count = 0
        for record in records:
            if count >= per_method or record.get("status") != "ok" or not record.get("arrays"):
                continue
            arrays = data.store.load_arrays(record)
            if "traj_t" in arrays and "traj_q" in arrays:
                chosen.append((method, record, arrays["traj_t"], np.atleast_2d(arrays["traj_q"])))
                count += 1
    if not chosen:
        return None
    chosen = chosen[: MAX_PANELS * 2]
    columns = min(3, len(chosen))
    rows = -(-len(chosen) // columns)
    fig = _figure(4.2 * columns, 3.0 * rows)
    axes = fig.subplots(rows, columns, squeeze=False).ravel()
    for ax, (method, record, t, q) in zip(axes, chosen):
        if q.shape[0] != t.size and q.shape[1] == t.size:
            q = q.T
        for j in range(q.shape[1]):
            ax.plot(t, q[:, j], label=f"q{j + 1}")
        ax.set_title(f"{method}: {record.get('key')}", fontsize=8)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("q [rad]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6, ncol=2)
    for ax in axes[len(chosen) :]:
        ax.set_visible(False)
    return FigureFile("trajectories", _render(fig), "Joint trajectories of example cases (one per method).")
