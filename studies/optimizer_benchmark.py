"""Optimizer benchmark: every drake_mh optimizer on a CEC 2017 subset, shifted and unshifted.

Grid (full): CEC 2017 F1, F3, F4, F5, F9, F10 (``drake_mh.optim.testfunctions.cec2017``:
official shift/rotation data with the ``bench`` extra, seeded data otherwise) x D in
{10, 30} x shift in {shifted (the CEC optimum), unshifted (same rotation, optimum at the
origin = box centre)} x 12 methods x 30 replicates, budget 10 000 D evaluations (CEC
practice), box [-100, 100]^D, every method at its default population and parameters.
Quick (``--quick``): F4 and F5, D = 10, 3 replicates, budget 1 000 D.

CEC 2017 protocol: a run stops at the budget or as soon as its error f - f* is <= 1e-8, and
such errors are reported as 0. Per case the record holds the final error, success (error
<= 1e-8), the best-so-far error history, the run time and the optimizer's own overhead
per generation of P evaluations (objective time subtracted). The runner's report gives
median / IQR tables, Friedman ranks, Wilcoxon-Holm tests and median / IQR convergence
curves, one panel per function, dimension and shift (``Fields.panels``); the summary below
gives per-function tables (shifted functions), Friedman ranks and Wilcoxon signed-rank tests
against the best-ranked method (Holm-corrected, Derrac et al. 2011), convergence milestones,
the centre-bias ratio of Kudela (2022) and the
overhead table (P = 50, D = 7, target <= 50 us).

Run: ``drake-mh study optimizer_benchmark [--quick] [--workers N]`` or
``python studies/optimizer_benchmark.py [--quick]``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from drake_mh.optim import available_methods, get_method, minimize
from drake_mh.optim.testfunctions import cec2017, official_cec2017_data
from drake_mh.study import Case, Fields, Study
from drake_mh.study.report.stats import holm
from drake_mh.study.report.summary import group_by, markdown_table, median, median_iqr, values

FUNCTIONS = [1, 3, 4, 5, 9, 10]
QUICK_FUNCTIONS = [4, 5]
SUCCESS_ERROR = 1e-8          # CEC reports errors below 1e-8 as 0
HISTORY_POINTS = 120          # history resampled to at most this many points
OVERHEAD_TARGET_US = 50.0     # per generation, P = 50, D = 7, objective excluded
MILESTONES = (0.01, 0.1, 0.5, 1.0)


def problem(number: int, dim: int, shift: str):
    """The CEC 2017 function; ``unshifted`` moves its optimum to the origin (box centre)."""
    f = cec2017(number, dim, seed=0)
    if shift == "unshifted":
        from dataclasses import replace

        f = replace(f, name=f.name + "_unshifted", shift=np.zeros(dim))
    return f


def _resample(history: np.ndarray, n: int) -> np.ndarray:
    if len(history) <= n:
        return history
    idx = np.unique(np.geomspace(1, len(history), n).astype(int) - 1)
    return history[idx]


def _cec_error(error: float) -> float:
    """CEC 2017 reporting: an error at or below 1e-8 counts as 0."""
    return 0.0 if error <= SUCCESS_ERROR else error


def run(case: Case) -> dict:
    """One optimizer run on one function instance."""
    dim = int(case["dim"])
    f = problem(int(case["function"]), dim, case["shift"])
    t_f = [0.0]

    def timed(X):
        t0 = time.perf_counter()
        F = f(X)
        t_f[0] += time.perf_counter() - t0
        return F

    method = case["method"]
    budget = int(case["budget_per_dim"]) * dim
    # CEC 2017 protocol: a run stops at MaxFES or when the error drops below 1e-8, and errors
    # below 1e-8 are reported as 0
    res = minimize(timed, f.bounds, method=method, budget=budget, seed=case.seed, target=f.f_opt + SUCCESS_ERROR)
    error = _cec_error(float(f.error(res.f)))
    hist = _resample(res.history, HISTORY_POINTS)
    pop = get_method(method).default_pop_size(dim)
    milestones = {}
    for q in MILESTONES:   # best-so-far error after a fraction q of the budget (scalars for the summary)
        i = np.searchsorted(res.history[:, 0], q * budget, side="right") - 1
        milestones[f"error_at_{int(100 * q)}pct"] = _cec_error(float(res.history[max(i, 0), 1] - f.f_opt))
    return {
        **milestones,
        "success": error <= SUCCESS_ERROR,
        "error": error,
        "time": res.time,
        "nfe": res.nfe,
        "nit": res.nit,
        "overhead_us": (res.time - t_f[0]) / (res.nfe / pop) * 1e6,
        "pop_size": pop,
        "cec_data": "official" if official_cec2017_data(dim) else "generated",
        "history_nfe": hist[:, 0],
        "history_best": np.maximum(hist[:, 1] - f.f_opt, 0.0),
    }


# --- summary -------------------------------------------------------------------------------


def _ok(records):
    return [r for r in records if r.get("status", "ok") == "ok" and r.get("error") is not None]


def error_matrix(records, dim: int, shift: str):
    """Errors as a (blocks, methods) matrix; blocks = (function, rep) with all methods present."""
    methods = [m for m in available_methods() if any(r["method"] == m for r in records)]
    cells: dict[tuple, dict[str, float]] = {}
    for r in records:
        if r["dim"] == dim and r["shift"] == shift:
            cells.setdefault((r["function"], r["rep"]), {})[r["method"]] = r["error"]
    blocks = sorted(k for k, v in cells.items() if all(m in v for m in methods))
    E = np.array([[cells[b][m] for m in methods] for b in blocks], dtype=float).reshape(len(blocks), len(methods))
    return E, methods, blocks


def ranking_table(records, dim: int) -> list[str]:
    """Friedman mean ranks and Wilcoxon-Holm against the best method (shifted functions).

    Wilcoxon's ``zero_method="zsplit"`` keeps the blocks where two methods tie (both reach the
    CEC floor of 0), which are frequent here."""
    from scipy import stats

    E, methods, blocks = error_matrix(records, dim, "shifted")
    if len(blocks) < 2 or len(methods) < 2:
        return [f"(D = {dim}: not enough complete blocks for rank statistics)"]
    mean_rank = stats.rankdata(E, axis=1).mean(axis=0)
    try:
        chi2, p_f = stats.friedmanchisquare(*E.T)
    except ValueError:
        chi2, p_f = float("nan"), float("nan")
    best = int(np.argmin(mean_rank))
    p = np.ones(len(methods))
    for j in range(len(methods)):
        if j != best and np.any(E[:, j] != E[:, best]):
            p[j] = stats.wilcoxon(E[:, j], E[:, best], zero_method="zsplit").pvalue
    p_adj = np.insert(holm(np.delete(p, best)), best, np.nan)
    rows = [[methods[j], f"{mean_rank[j]:.2f}",
             "best" if j == best else f"{p_adj[j]:.1e}" + (" (n.s.)" if p_adj[j] > 0.05 else "")]
            for j in np.argsort(mean_rank)]
    return [f"D = {dim}, shifted: Friedman chi2 = {chi2:.1f}, p = {p_f:.1e} over {len(blocks)} blocks "
            f"(function x replicate); Wilcoxon signed-rank vs best ({methods[best]}), Holm-corrected",
            ""] + markdown_table(["method", "mean rank", "p (Holm) vs best"], rows)


def _errors(cells: dict, method: str, dim: int, shift: str, function: int) -> list[float]:
    return [r["error"] for r in cells.get((method, dim, shift, function), [])]


def _geomean(x) -> float:
    return math.exp(np.mean(np.log(x)))


def _dimension_tables(recs, cells, dim, methods, functions) -> list[str]:
    """Error tables (shifted and unshifted), ranks, convergence milestones, centre bias and the
    in-run overhead at one dimension."""
    out: list[str] = []
    for shift in ("shifted", "unshifted"):
        out += ["", f"### Error f - f*, median [IQR], D = {dim}, {shift}", ""] + markdown_table(
            ["method"] + [f"F{k}" for k in functions],
            [[m] + [median_iqr(_errors(cells, m, dim, shift, k), ".2e", ".1e") for k in functions] for m in methods])
    out += ["", "### Ranks", ""] + ranking_table(recs, dim)
    rows = []
    for m in methods:  # milestones: median error at fractions of the budget, geometric mean over functions
        row = [m]
        for q in MILESTONES:
            key = f"error_at_{int(100 * q)}pct"
            per_f = [max(median(values(cells.get((m, dim, "shifted", k), []), key)), 0.0) for k in functions]
            per_f = [v for v in per_f if v == v]
            row.append(f"{_geomean(np.asarray(per_f) + 1e-12):.2e}" if per_f else "-")
        rows.append(row)
    out += ["", f"### Convergence, D = {dim}, shifted: median over functions x replicates of the "
            "best-so-far error at a fraction of the budget (geometric mean over functions)", ""]
    out += markdown_table(["method"] + [f"{int(100 * q)} %" for q in MILESTONES], rows)
    rows = []
    for m in methods:  # centre bias (Kudela 2022): shifted / unshifted median error
        ratios = [max(median(s), SUCCESS_ERROR) / max(median(u), SUCCESS_ERROR) for k in functions
                  if (s := _errors(cells, m, dim, "shifted", k)) and (u := _errors(cells, m, dim, "unshifted", k))]
        if ratios:
            rows.append([m, f"{_geomean(ratios):.2e}", ", ".join(f"F{k}: {x:.1e}" for k, x in zip(functions, ratios))])
    out += ["", f"### Centre bias, D = {dim}: ratio of median errors shifted / unshifted "
            "(geometric mean over functions; errors floored at 1e-8). >> 1: the method is drawn "
            "to the origin (box centre)", ""] + markdown_table(["method", "ratio", "per function"], rows)
    rows = [[m, g[0]["pop_size"], f"{median(values(g, 'overhead_us')):.1f}"]
            for m in methods if (g := [r for r in recs if r["method"] == m and r["dim"] == dim and "overhead_us" in r])]
    out += ["", f"### Optimizer overhead during the runs, D = {dim} (us per generation of P "
            "evaluations, objective excluded; median over cases; runs may share cores)", ""]
    return out + markdown_table(["method", "P", "overhead [us]"], rows)


def _overhead_now(methods) -> list[str]:
    """The stated target, P = 50, D = 7, measured now in this process, serially; each row also
    times the plain-numpy reference generation just before the method, so the ratio is measured
    under the same load (absolute microseconds drift with the machine)."""
    from drake_mh.optim.overhead import measure_overhead, measure_reference_us

    rows, refs = [], []
    for m in methods:
        ref = measure_reference_us(pop_size=50, dim=7)
        us = measure_overhead(m, pop_size=50, dim=7, generations=30 if m == "cmaes" else 200)
        refs.append(ref)
        rows.append([m, f"{us:.1f}", f"{us / ref:.2f}", "yes" if us <= OVERHEAD_TARGET_US else "no"])
    ref_text = f"{median(refs):.1f} us (median over the rows)" if refs else "-"
    return ["", f"### Overhead per generation at P = 50, D = 7 (target <= {OVERHEAD_TARGET_US:g} us; "
            "measured serially while summarizing, median of 3 runs; CMA-ES is pycma)", "",
            "Reference = one plain-numpy generation (draw, scale and clip a (P, D) population, "
            "argmin of a (P,) vector; `drake_mh.optim.overhead.measure_reference_us`), timed just "
            f"before each method with the same protocol: {ref_text}. The ratio travels between "
            "machines better than the microseconds.", ""] + markdown_table(
        ["method", "overhead [us]", "overhead / reference", "target met"], rows)


def summarize(records: list[dict]) -> str:
    """Per-function tables, ranks, convergence milestones, centre bias and overhead."""
    recs = _ok(records)
    cells = group_by(recs, "method", "dim", "shift", "function")
    methods = [m for m in available_methods() if any(r["method"] == m for r in recs)]
    functions = sorted({r["function"] for r in recs})
    out = [f"CEC 2017 shift/rotation data: {', '.join(sorted({r.get('cec_data', '?') for r in recs}))} (official = "
           "organisers' files via the 'bench' extra; generated = seeded stand-ins)"]
    for dim in sorted({r["dim"] for r in recs}):
        out += _dimension_tables(recs, cells, dim, methods, functions)
    text = "\n".join(out + _overhead_now(methods)).strip()
    print(text)
    return text


study = Study(
    name="optimizer_benchmark",
    run=run,
    grid={"function": FUNCTIONS, "dim": [10, 30], "shift": ["shifted", "unshifted"],
          "budget_per_dim": [10_000], "method": available_methods(), "rep": list(range(30))},
    quick_grid={"function": QUICK_FUNCTIONS, "dim": [10], "shift": ["shifted", "unshifted"],
                "budget_per_dim": [1_000], "method": available_methods(), "rep": list(range(3))},
    seed=0,
    fields=Fields(method="method", success="success", time="time", error="error", nfe="nfe",
                  instance=("function", "dim", "shift", "rep"), panels=("function", "dim", "shift"),
                  group_by=("function", "dim", "shift"), error_unit=""),
    description=(
        "All drake_mh optimizers (metaheuristics PSO, BAT, GSA, e3GSA, WOA, AO, GA, ABC, ARO and "
        "the baselines CMA-ES, DE, random search) on a CEC 2017 subset (F1, F3, F4, F5, F9, F10) "
        "with equal evaluation budgets (10 000 D), each function both with its CEC optimum "
        "(shifted) and with the optimum moved to the box centre (unshifted), to measure the "
        "centre bias of Kudela (2022). Error = f - f*; the runner's statistics pool shifted and "
        "unshifted blocks, the summary separates them. The convergence figure has one panel per "
        "function, dimension and shift (median and IQR of the best-so-far error against evaluations)."
    ),
    summarize=summarize,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
