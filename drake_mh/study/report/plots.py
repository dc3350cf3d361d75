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
    if data.fields.panels or data.fields.group_by:
        panel_keys = tuple(data.fields.panels or data.fields.group_by)
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
        shown = []
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
            shown.append(stack[np.isfinite(stack)])
            ax.plot(grid, median, color=colors[method], label=f"{method} (n={len(curves)})")
            ax.fill_between(grid, q25, q75, color=colors[method], alpha=0.2, linewidth=0)
        readable_axis(ax, np.array([low, top]) if top / low > 50 else np.array([1.0]), axis="x")
        readable_axis(ax, np.concatenate(shown) if shown else np.array([]))
        ax.set_xlabel("function evaluations")
        ax.set_ylabel("best so far")
        ax.set_title(", ".join(f"{k} = {v}" for k, v in zip(panel_keys, panel)) if panel_keys else data.name,
                     fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    caption = "Best-so-far objective vs function evaluations: median (line) and interquartile range (band) over cases."
    return FigureFile("convergence", _render(fig), caption)


#: fewer cases than this per method and panel are drawn as points (a box of 1-4 values says little)
STRIP_BELOW = 5
#: widest figure [in] (at 100 dpi: about the report's page width)
MAX_FIGURE_WIDTH = 16.0
#: box-plot panels at most (groups x metrics); the others are left out (the table has them all)
MAX_BOX_PANELS = 24


def _plain_tick(value: float, _pos=None) -> str:
    """A log-axis tick as a plain number: ``0.001``, ``20``, ``1e+05``."""
    if value == 0 or not np.isfinite(value):
        return "0"
    magnitude = abs(value)
    return f"{value:.0e}" if magnitude >= 1e5 or magnitude < 1e-3 else f"{value:g}"


def linear_tick_labels(locs) -> list[str]:
    """Labels of linear-axis ticks ``locs``, with just the digits that tell them apart:
    ``21.10128, 21.1013, 21.10132``; ``0.3`` (float noise rounded away); ``2e-16``."""
    locs = np.asarray(locs, dtype=float)
    finite = locs[np.isfinite(locs)]
    if finite.size == 0:
        return ["" for _ in locs]
    steps = np.diff(np.unique(finite))
    step = float(steps.min()) if steps.size else max(abs(float(finite[0])), 1.0)
    top = float(np.max(np.abs(finite)))
    if top >= 1e6 or (0 < top < 1e-3):
        digits = max(0, int(np.floor(np.log10(top))) - int(np.floor(np.log10(step))))
        return [("0" if v == 0 else f"{v:.{digits}e}") for v in locs]
    decimals = max(0, -int(np.floor(np.log10(step) + 1e-9)))
    return [f"{v:.{decimals}f}" for v in locs]


class _LinearFormatter:
    """matplotlib formatter around :func:`linear_tick_labels` (built lazily: no import at load)."""

    @staticmethod
    def make():
        from matplotlib.ticker import Formatter

        class LinearFormatter(Formatter):
            def set_locs(self, locs):
                locs = list(locs)
                self._labels = dict(zip(locs, linear_tick_labels(locs)))

            def __call__(self, x, pos=None):
                labels = getattr(self, "_labels", {})
                return labels.get(x, linear_tick_labels([x])[0])

        return LinearFormatter()


def readable_axis(ax, values: np.ndarray, axis: str = "y") -> None:
    """Log scale when positive values span more than a decade, else linear; plain tick labels.

    Log ticks read ``0.01, 0.1, 1`` (no ``2.1×10¹`` minor labels); linear ticks are full
    numbers (``21.1004``, ``2e-16``), never an offset or a common factor at the axis' end.
    """
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    target = ax.yaxis if axis == "y" else ax.xaxis
    if values.size and np.all(values > 0) and values.max() / values.min() > 10:
        (ax.set_yscale if axis == "y" else ax.set_xscale)("log")
        target.set_major_locator(LogLocator(base=10, numticks=8))
        target.set_major_formatter(FuncFormatter(_plain_tick))
        target.set_minor_formatter(NullFormatter())
    else:
        target.set_major_formatter(_LinearFormatter.make())


def _draw_categories(ax, categories: list, rng: np.random.Generator) -> int:
    """Box plots, or points where a category has fewer than :data:`STRIP_BELOW` values.

    Args:
        ax: the axes.
        categories: ``[(label, values (n,), colour), ...]`` in x order.
        rng: jitter of the points.

    Returns:
        How many categories were drawn as points.
    """
    boxes = [(i + 1, v) for i, (_, v, _) in enumerate(categories) if v.size >= STRIP_BELOW]
    if boxes:
        ax.boxplot([v for _, v in boxes], positions=[p for p, _ in boxes], widths=0.6, showfliers=True)
    strips = 0
    for i, (_, v, colour) in enumerate(categories):
        if v.size < STRIP_BELOW:
            strips += 1
            x = i + 1 + (rng.uniform(-0.12, 0.12, v.size) if v.size > 1 else np.zeros(1))
            ax.scatter(x, v, s=30, color=colour, edgecolor="black", linewidth=0.5, zorder=3)
    ax.set_xticks(range(1, len(categories) + 1), [c[0] for c in categories])
    ax.set_xlim(0.4, len(categories) + 0.6)
    readable_axis(ax, np.concatenate([c[1] for c in categories]))
    ax.tick_params(axis="x", labelrotation=30 if len(categories) > 3 else 0, labelsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    return strips


def box_figure(data: ReportData) -> FigureFile | None:
    """Time and error per method over the cases that did not raise: box plots, or the points
    themselves (strip plot) where a method has fewer than :data:`STRIP_BELOW` cases.

    One panel per metric and group (``fields.group_by``): instances of a different kind are
    not pooled. When every group has a single method (a benchmark over N), the groups share
    one panel per metric, side by side. Times are shown in s, ms or µs, whichever suits.
    """
    from drake_mh.study.report.units import time_unit, with_unit

    fields = data.fields
    metrics = []
    if data.has_field(fields.time):
        unit, factor = time_unit(data.values(data.records, fields.time))
        metrics.append((fields.time, with_unit(fields.time, unit), factor))
    if data.has_field(fields.error):
        metrics.append((fields.error, with_unit(fields.error, fields.error_unit), 1.0))
    if not metrics:
        return None
    groups = data.by_group()
    colors = _colors(data.methods)
    side_by_side = len(groups) > 1 and all(len(data.by_method(r)) == 1 for r in groups.values())
    panels = []  # (axis label, title, categories)
    for field_name, label, factor in metrics:
        if side_by_side:
            categories = [(data.group_label(g), data.values(r, field_name) * factor, colors[method_of(r[0], fields)])
                          for g, r in groups.items()]
            methods = sorted({method_of(r[0], fields) for r in groups.values()})
            panels.append((label, ", ".join(methods), [c for c in categories if c[1].size]))
            continue
        for group, records in groups.items():
            categories = [(m, data.values(r, field_name) * factor, colors[m]) for m, r in data.by_method(records).items()]
            panels.append((label, data.group_label(group), [c for c in categories if c[1].size]))
    panels = [p for p in panels if p[2]]
    if not panels:
        return None
    left_out = max(0, len(panels) - MAX_BOX_PANELS)
    panels = panels[:MAX_BOX_PANELS]
    most = max(len(p[2]) for p in panels)
    width = max(3.4, 1.0 + 0.55 * most)
    columns = len(panels) if side_by_side or len(groups) == 1 else min(len(groups), 4)
    columns = max(1, min(columns, int(MAX_FIGURE_WIDTH // width)))  # legible when shown 1300 px wide
    rows = -(-len(panels) // columns)
    fig = _figure(width * columns, 3.3 * rows)
    axes = fig.subplots(rows, columns, squeeze=False).ravel()
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    rng = np.random.default_rng(0)  # jitter only; fixed so that the figure is reproducible
    strips = 0
    for ax, (label, title, categories) in zip(axes, panels):
        strips += _draw_categories(ax, categories, rng)
        ax.set_ylabel(label)
        if title:
            ax.set_title(title, fontsize=10)
    caption = "Distribution per method over cases that did not raise (box: quartiles, whiskers: 1.5 IQR"
    caption += f"; fewer than {STRIP_BELOW} cases: every case as a point)." if strips else ")."
    if data.group_keys:
        caption += (f" One column per {' x '.join(data.group_keys)}." if side_by_side
                    else f" One panel per {' x '.join(data.group_keys)}.")
    if left_out:
        caption += f" {left_out} more panels left out (see the table)."
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
