"""drake_mh's optimizers against mealpy and NiaPy on the CEC 2017 functions, same run.

Grid (full): CEC 2017 F1, F3, F4, F5 (as ``studies/optimizer_benchmark.py``, the
same shift/rotation data), D = 10, shifted, 10 replicates, budget 10 000 D, box [-100, 100]^D.
Algorithms: PSO, DE, GA, WOA, ABC, GSA of drake_mh (default parameters), two of its
documented variants (``woa_greedy``: mealpy's WOA; ``de_F1``: ``de`` with ``F = 1.0``, NiaPy's
default weight), and the same-named ones of mealpy 3.0.3 (``OriginalPSO``, ``OriginalDE``,
``BaseGA``, ``OriginalWOA``, ``OriginalABC``; mealpy has no GSA) and NiaPy 2.7.1
(``ParticleSwarmAlgorithm``, ``DifferentialEvolution``, ``GeneticAlgorithm``,
``ArtificialBeeColonyAlgorithm``, ``GravitationalSearchAlgorithm``; NiaPy has no WOA), each at
its library's default parameters but drake_mh's population size (ABC: 20 food sources
everywhere) and with mealpy's ``epoch`` (its run length, which its WOA's
``a = 2 - 2 epoch / max_epoch`` reads) set to the generations the budget allows. Quick
(``--quick``): F5, D = 10, 1 replicate, budget 100 D.

Evaluations are counted by *our* wrapper around the objective, not by the libraries: the
wrapper stops a run (it raises, caught here) on the evaluation after the budget, so no library
gets more than ``budget`` evaluations (mealpy's ABC checks its ``max_fe`` only once per
generation and would overshoot; ``over_budget`` records whether a library asked for more), and,
as ``optimizer_benchmark`` does for ours (CEC 2017 protocol), as soon as the error is <= 1e-8
(reported as 0). The peers evaluate one vector per call (their interface); ours a population.

Per (function, replicate, algorithm) the three libraries run back to back, the order reversed
on every other replicate, so they share the machine's load. Wall time, process CPU time, the
time spent in the objective and the 1-minute load average are recorded per run; the summary
gives per cell the median error and the median time per run and, per algorithm, the ratios of
wall and of CPU time theirs / ours from the same cases, with the CPU model; then, per function,
a Wilcoxon rank-sum test (two-sided) of each of our entries against each peer of its algorithm
on the final error, with Holm's correction over all the tests of the table (the runs are
independent samples: the libraries share a seed number, not a random stream, so nothing pairs
them). A peer that is not installed is left out with a line in the summary. NiaPy comes with
the extra ``peers``; mealpy 3.0.3 pins numpy <= 1.26 and is not in it:
``pip install --no-deps mealpy==3.0.3 pandas`` runs with numpy 2.

Run: ``drake-mh study optimizer_peers [--quick]`` or ``python studies/optimizer_peers.py [--quick]``;
``--first-by rep`` keeps a stopped run balanced (its summary uses the complete replicates only).
The full grid is 720 cases, almost all of the time in the peers: 75-110 minutes on 2 shared
cores at a 1-minute load of 1.3-8 (about 10 cases a minute at load < 2).
"""

from __future__ import annotations

import importlib.util
import math
import time

import numpy as np

from drake_mh.optim import get_method, minimize
from drake_mh.optim.testfunctions import cec2017
from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import load_average
from drake_mh.study.report.summary import cell, cpu_and_load, finished, group_by, markdown_table, mean, median, values

SUCCESS_ERROR = 1e-8          # CEC 2017: errors at or below 1e-8 are reported as 0 (as optimizer_benchmark)

ALGORITHMS = ("pso", "de", "ga", "woa", "abc", "gsa")
LIBRARIES = ("drake_mh", "mealpy", "niapy")
#: drake_mh's entries, label -> (algorithm, method, hyper-parameters): the defaults and the
#: documented variants that match a peer's (docs/optimizers.md)
OURS = {"pso": ("pso", "pso", {}), "de": ("de", "de", {}), "de_F1": ("de", "de", {"F": 1.0}),
        "ga": ("ga", "ga", {}), "woa": ("woa", "woa", {}), "woa_greedy": ("woa", "woa_greedy", {}),
        "abc": ("abc", "abc", {}), "gsa": ("gsa", "gsa", {})}
SIGNIFICANCE = 0.05          # family-wise level of the Holm-corrected rank-sum tests
#: the peers' classes per algorithm (None: the library has no such algorithm)
MEALPY = {"pso": ("swarm_based.PSO", "OriginalPSO"), "de": ("evolutionary_based.DE", "OriginalDE"),
          "ga": ("evolutionary_based.GA", "BaseGA"), "woa": ("swarm_based.WOA", "OriginalWOA"),
          "abc": ("swarm_based.ABC", "OriginalABC"), "gsa": None}
NIAPY = {"pso": "ParticleSwarmAlgorithm", "de": "DifferentialEvolution", "ga": "GeneticAlgorithm",
         "woa": None, "abc": "ArtificialBeeColonyAlgorithm", "gsa": "GravitationalSearchAlgorithm"}


def installed(library: str) -> bool:
    """Whether a peer library can be imported (``drake_mh`` always)."""
    return library == "drake_mh" or importlib.util.find_spec(library) is not None


def has(library: str, algorithm: str) -> bool:
    """Whether ``library`` is installed and offers ``algorithm``."""
    table = {"mealpy": MEALPY, "niapy": NIAPY}.get(library)
    return installed(library) and (table is None or table[algorithm] is not None)


class _Stop(Exception):
    """Raised by :class:`Counted` to end a peer's run (budget spent or target reached)."""


class Counted:
    """The objective as the peers see it: one vector per call, counted and cut at the budget.

    Args:
        f: the vectorized test function ``f(X (P, D)) -> (P,)``.
        budget: evaluations allowed; the call after them raises :class:`_Stop`.
        target: stop (raise) as soon as a value is <= ``target``.
    """

    def __init__(self, f, budget: int, target: float):
        self.f, self.budget, self.target = f, budget, target
        self.nfe, self.best, self.over_budget, self.f_time = 0, np.inf, False, 0.0

    def __call__(self, x) -> float:
        if self.nfe >= self.budget:
            self.over_budget = True
            raise _Stop
        t0 = time.perf_counter()
        value = float(self.f(np.asarray(x, dtype=float).reshape(1, -1))[0])
        self.f_time += time.perf_counter() - t0
        self.nfe += 1
        self.best = min(self.best, value)
        if value <= self.target:
            raise _Stop
        return value


def _run_mealpy(algorithm: str, counted: Counted, bounds: np.ndarray, pop: int, seed: int) -> None:
    import importlib

    from mealpy import FloatVar

    module, name = MEALPY[algorithm]
    cls = getattr(importlib.import_module(f"mealpy.{module}"), name)
    size = max(pop // 2 if algorithm == "abc" else pop, 5)  # mealpy's ABC: pop_size = food sources
    model = cls(epoch=mealpy_epochs(counted.budget, size), pop_size=size)
    spec = {"bounds": FloatVar(lb=bounds[:, 0], ub=bounds[:, 1]), "minmax": "min", "obj_func": counted,
            "log_to": None}
    try:
        model.solve(spec, termination={"max_fe": counted.budget}, seed=seed)
    except _Stop:
        pass


def mealpy_epochs(budget: int, size: int) -> int:
    """mealpy's ``epoch`` (run length) for a budget: the generations of ``size`` evaluations
    after the initial population. Its WOA reads it (``a = 2 - 2 epoch / max_epoch``); with a
    larger value ``a`` would stay near 2 for the whole budget. The other classes used here do
    not read it, and the wrapper cuts every run at the budget anyway."""
    return int(min(max(math.ceil((budget - size) / size), 1), 100_000))


def _run_niapy(algorithm: str, counted: Counted, bounds: np.ndarray, pop: int, seed: int) -> None:
    import niapy.algorithms.basic as basic
    from niapy.problems import Problem
    from niapy.task import Task

    class Wrapped(Problem):
        def _evaluate(self, x):
            return counted(x)

    algo = getattr(basic, NIAPY[algorithm])(population_size=pop, seed=seed)
    task = Task(problem=Wrapped(dimension=len(bounds), lower=bounds[:, 0], upper=bounds[:, 1]),
                max_evals=counted.budget)
    try:
        algo.run(task)
    except _Stop:
        pass
    if getattr(algo, "exception", None) is not None and not isinstance(algo.exception, _Stop):
        raise algo.exception  # NiaPy keeps exceptions raised outside the main process


def run(case: Case) -> dict:
    """One run of one library's algorithm on one function instance."""
    dim = int(case["dim"])
    f = cec2017(int(case["function"]), dim, seed=0)   # optimizer_benchmark's "shifted" instance
    algorithm, library = case["algorithm"], case["library"]
    budget = int(case["budget_per_dim"]) * dim
    target = f.f_opt + SUCCESS_ERROR
    pop = get_method(algorithm).default_pop_size(dim)   # the same for a variant and the peers
    seed = 1_000 * int(case["rep"]) + int(case["function"])  # the same for every library on a replicate
    bounds = np.asarray(f.bounds, dtype=float)
    load = load_average()
    if library == "drake_mh":
        f_time = [0.0]

        def timed(X):
            t0 = time.perf_counter()
            F = f(X)
            f_time[0] += time.perf_counter() - t0
            return F

        w0, c0 = time.perf_counter(), time.process_time()
        _, method, params = OURS[case["method"]]
        res = minimize(timed, bounds, method=method, budget=budget, seed=seed, target=target, pop_size=pop,
                       **params)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        best, nfe, over, objective = float(res.f), int(res.nfe), False, f_time[0]
    else:
        counted = Counted(f, budget, target)
        runner = _run_mealpy if library == "mealpy" else _run_niapy
        w0, c0 = time.perf_counter(), time.process_time()
        runner(algorithm, counted, bounds, pop, seed)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        best, nfe, over, objective = counted.best, counted.nfe, counted.over_budget, counted.f_time
    error = float(best - f.f_opt)
    error = 0.0 if error <= SUCCESS_ERROR else error
    return {"error": error, "success": error <= SUCCESS_ERROR, "time": wall, "cpu_time": cpu,
            "objective_time": objective, "nfe": nfe, "budget": budget, "over_budget": over,
            "pop_size": pop, "load": load}


def _entries(algorithm: str) -> list[tuple[str, str]]:
    """``(library, method label)`` of one algorithm: our default and variants, then the peers."""
    ours = [("drake_mh", label) for label, (alg, _, _) in OURS.items() if alg == algorithm]
    return ours + [(lib, f"{lib}_{algorithm}") for lib in LIBRARIES[1:] if has(lib, algorithm)]


def _grid(quick: bool) -> list[dict]:
    functions, reps, per_dim = ([5], 1, 100) if quick else ([1, 3, 4, 5], 10, 10_000)
    cases = []
    for rep in range(reps):
        for k in functions:
            for algorithm in ALGORITHMS:
                entries = _entries(algorithm)
                for library, method in (entries if rep % 2 == 0 else entries[::-1]):
                    cases.append({"function": k, "dim": 10, "budget_per_dim": per_dim, "rep": rep,
                                  "method": method, "algorithm": algorithm, "library": library})
    return cases


def _label(record: dict) -> str:
    """A row's name: the library, with our variant's method label where it is not the default."""
    if record["library"] != "drake_mh" or record["method"] == record["algorithm"]:
        return record["library"]
    return f"drake_mh `{record['method']}`"


def rank_sum(ours, theirs) -> tuple[float, float]:
    """Wilcoxon rank-sum (Mann-Whitney U) test of two samples of final errors.

    Returns:
        ``(p, A)``: the two-sided p-value (1 when all values are equal, NaN with an empty
        sample) and Vargha and Delaney's ``A = P(ours < theirs) + P(ours = theirs) / 2``
        (> 0.5: ours tends to lower errors).
    """
    from scipy import stats

    a, b = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    if a.size == 0 or b.size == 0:
        return math.nan, math.nan
    less = np.sum(a[:, None] < b[None, :]) + 0.5 * np.sum(a[:, None] == b[None, :])
    effect = float(less / (a.size * b.size))
    if np.all(np.concatenate([a, b]) == a[0]):
        return 1.0, effect
    return float(stats.mannwhitneyu(a, b, alternative="two-sided").pvalue), effect


def significance(ok: list[dict]) -> list[dict]:
    """Per function and D, each of our entries against each peer of its algorithm.

    Returns:
        One dict per test: ``algorithm, ours, peer, function, dim, n_ours, n_peer, p, A``,
        ``p_holm`` (Holm's step-down correction over the tests of the same function and D, the
        family of one column of the table) and ``p_holm_all`` (over all the returned tests).
    """
    from drake_mh.study.report.stats import holm

    tests = []
    for algorithm in ALGORITHMS:
        mine = [r for r in ok if r["algorithm"] == algorithm]
        ours = sorted({r["method"] for r in mine if r["library"] == "drake_mh"}, key=list(OURS).index)
        peers = [lib for lib in LIBRARIES[1:] if any(r["library"] == lib for r in mine)]
        for label in ours:
            for peer in peers:
                for dim, k in sorted({(r["dim"], r["function"]) for r in mine}):
                    a = [r["error"] for r in mine if (r["method"], r["dim"], r["function"]) == (label, dim, k)]
                    b = [r["error"] for r in mine if (r["library"], r["dim"], r["function"]) == (peer, dim, k)]
                    p, effect = rank_sum(a, b)
                    tests.append({"algorithm": algorithm, "ours": label, "peer": peer, "function": k, "dim": dim,
                                  "n_ours": len(a), "n_peer": len(b), "p": p, "A": effect})
    adjusted = holm(np.array([t["p"] for t in tests], dtype=float)) if tests else []
    for t, q in zip(tests, adjusted):
        t["p_holm_all"] = float(q)
    for cell in {(t["function"], t["dim"]) for t in tests}:
        family = [t for t in tests if (t["function"], t["dim"]) == cell]
        for t, q in zip(family, holm(np.array([t["p"] for t in family], dtype=float))):
            t["p_holm"] = float(q)
    return tests


def _verdict(test: dict) -> str:
    if not math.isfinite(test["p_holm"]):
        return "-"
    effect = f"A {test['A']:.2f}"
    if test["p_holm"] > SIGNIFICANCE:
        return f"n.s. ({test['p_holm']:.2g}, {effect})"
    return f"{'**better**' if test['A'] > 0.5 else 'worse'} ({test['p_holm']:.1e}, {effect})"


def _time_ratios(rows: list[dict], default: dict, ours: bool) -> list[str]:
    """Median over the same (function, replicate) of this entry's wall and CPU time over our
    default entry's ("1" for the default itself)."""
    if ours:
        return ["1", "1"]
    pairs = [(r, default[key]) for r in rows if (key := (r["algorithm"], r["dim"], r["function"], r["rep"])) in default]
    cells = []
    for field in ("time", "cpu_time"):
        x = median([r[field] / base[field] for r, base in pairs if base[field] > 0])
        cells.append(cell(x, f".{0 if x >= 10 else 2}f", "-") + ("x" if x == x else ""))
    return cells


def _table(ok: list[dict], functions: list[int]) -> list[str]:
    default = {(r["algorithm"], r["dim"], r["function"], r["rep"]): r for r in ok
               if r["library"] == "drake_mh" and r["method"] == r["algorithm"]}
    groups = group_by(ok, "algorithm", "library", "method")
    rows = []
    for key in [(a, lib, m) for a in ALGORITHMS for lib, m in _entries(a) if (a, lib, m) in groups]:
        entry = groups[key]
        by_function = group_by(entry, "function")
        rows.append([key[0], _label(entry[0])]
                    + [f"{median(values(g, 'error')):.2e} / {median(values(g, 'time', 1e3)):.0f} ms"
                       if (g := by_function.get(k)) else "-" for k in functions]
                    + [f"{median(values(entry, 'nfe')):.0f}",
                       f"{1e6 * median(r['time'] / max(r['nfe'], 1) for r in entry):.1f}",
                       f"{np.sum([r['cpu_time'] for r in entry]) / np.sum([r['time'] for r in entry]):.2f}"]
                    + _time_ratios(entry, default, key[2] == key[0] and key[1] == "drake_mh"))
    return markdown_table(["algorithm", "library"] + [f"F{k}" for k in functions]
                          + ["nfe (median)", "us / evaluation", "CPU / wall", "wall vs ours", "CPU vs ours"], rows)


def _tests_table(tests: list[dict], functions: list[int], dims: list[int]) -> list[str]:
    def count(key, better):
        return sum(t[key] <= SIGNIFICANCE and (t["A"] > 0.5) == better for t in tests)

    n_min = min(min(t["n_ours"], t["n_peer"]) for t in tests)
    rows = []
    for algorithm in ALGORITHMS:
        for ours, peer in dict.fromkeys((t["ours"], t["peer"]) for t in tests if t["algorithm"] == algorithm):
            for dim in dims:
                found = {t["function"]: t for t in tests if (t["ours"], t["peer"], t["dim"]) == (ours, peer, dim)}
                rows.append([f"`{ours}`" + (f" (D = {dim})" if len(dims) > 1 else ""), peer]
                            + [_verdict(found[k]) if k in found else "-" for k in functions])
    return ["", "Final error, ours against each peer of the algorithm, per function and D: Wilcoxon rank-sum "
            "test (two-sided; runs are independent, nothing pairs them), Holm-corrected over the "
            f"{len(tests) // max(len(functions) * len(dims), 1)} tests of the same function and D (one column), "
            f"level {SIGNIFICANCE}. Cell: **better** / worse (ours has the lower / higher errors) or n.s., "
            "then the Holm p and Vargha-Delaney A = P(ours < peer) + P(tie) / 2 (1: ours below every peer "
            f"run, 0: above every one). Ours significantly better in {count('p_holm', True)}, worse in "
            f"{count('p_holm', False)} of {len(tests)} (Holm over all {len(tests)} tests at once: "
            f"{count('p_holm_all', True)} / {count('p_holm_all', False)}). With {n_min} runs a side the "
            f"smallest possible two-sided p is {2 / math.comb(2 * n_min, n_min):.1e}.", ""] + markdown_table(
        ["ours", "peer"] + [f"F{k}" for k in functions], rows)


def summarize(records: list[dict]) -> str:
    """Median error and time per cell, wall and CPU time ratios theirs / ours on the same cases,
    and rank-sum tests (Holm) of our entries against the peers per function."""
    ok = finished(records)
    if not ok:
        return ""
    cells = {(r["function"], r["dim"], r["method"]) for r in ok}
    per_rep = {rep: {(r["function"], r["dim"], r["method"]) for r in g} for rep, g in group_by(ok, "rep").items()}
    partial = sorted(rep for rep, seen in per_rep.items() if seen != cells)
    if len(partial) < len(per_rep):      # a stopped run (--first-by rep): only complete replicates
        ok = [r for r in ok if r["rep"] not in partial]
    functions = sorted({r["function"] for r in ok})
    dims = sorted({r["dim"] for r in ok})
    reps = len({r["rep"] for r in ok})
    lines = [f"### drake_mh vs mealpy / NiaPy: CEC 2017, shifted, D = {', '.join(map(str, dims))}, "
             f"{reps} replicate(s)", "",
             f"{cpu_and_load(ok, cpu='case_cpu_model', loads=('load',), digits=2)} (mean "
             f"{mean(values(ok, 'load')):.2f}). Budget {ok[0]['budget']} evaluations counted by our wrapper (a run "
             "stops at the budget or at error <= 1e-8, reported as 0). Cells: median error f - f* / median wall time "
             "per run. `wall vs ours`, `CPU vs ours` = median over the cases of (its wall / CPU time / that of our "
             "default entry of the algorithm) on the same function and replicate (a run that reaches the target "
             "early is shorter: `us / evaluation` = median wall time per counted evaluation, objective included).", ""]
    if partial and reps < len(per_rep):
        lines += [f"Left out: replicate(s) {', '.join(map(str, partial))}, not complete (the run was stopped).", ""]
    missing = [lib for lib in LIBRARIES if not installed(lib)]
    if missing:
        lines += [f"Not installed: {', '.join(missing)}; their rows are missing (NiaPy: `pip install -e '.[peers]'`; "
                  "mealpy 3.0.3 pins numpy <= 1.26: `pip install --no-deps mealpy==3.0.3 pandas` keeps numpy 2).", ""]
    over = sorted({r["method"] for r in ok if r.get("over_budget")})
    if over:
        lines += [f"Asked for more than the budget (cut by the wrapper): {', '.join(over)}.", ""]
    lines += _table(ok, functions)
    tests = significance(ok)
    if tests:
        lines += _tests_table(tests, functions, dims)
    text = "\n".join(lines)
    print(text)
    return text


study = Study(
    name="optimizer_peers",
    run=run,
    grid=_grid(quick=False),
    quick_grid=_grid(quick=True),
    seed=0,
    fields=Fields(method="method", success="success", time="time", error="error", nfe="nfe", rank=False,
                  instance=("function", "rep"), group_by=("function",), error_unit="",
                  conditions="10 000 D evaluations counted by our wrapper, stop at error <= 1e-8"),
    description=(
        "drake_mh's PSO, DE, GA, WOA, ABC, GSA against the same-named algorithms of mealpy and NiaPy on "
        "CEC 2017 F1, F3, F4, F5 (shifted, D = 10), evaluations counted and cut by our wrapper, libraries "
        "interleaved per case, wall and CPU time and load average recorded."
    ),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
