"""``mh_<optimizer>``: metaheuristic via-point trajectory optimization as a motion planner.

One run (:func:`plan`):

1. **First population** (``pop_size`` individuals of :class:`~.objective.ViaPointMotion`): with
   ``warm_start`` (e.g. ``"rrt_connect"``), that planner's path, its via points resampled to
   ``K`` (its own corners when it has at most ``K``, split at the middle of its longest
   segments up to ``K``, so the polyline is kept exactly; else points at equal joint-space arc
   length), and noisy copies fill ``warm_fraction`` of it; with ``init="straight"``, evenly
   spaced via points on the straight line to each goal and noisy copies fill
   ``seed_fraction``; the rest is uniform in the box (the optimizer's own initialization).
2. **Ask/tell** with the chosen optimizer of :mod:`drake_mh.optim` on the batched fitness
   until the budget (minus ``repair_fraction``), the deadline, or a stall with a
   collision-free best.
3. **Certification**: the best individual and the next best of the final population
   (``candidates``, best first) are certified as piecewise-linear motions (all their segments
   in one :meth:`~drake_mh.scene.Scene.certify_segments` call) with ``certify_extra`` (2 mm)
   above the problem's clearances (the verification certifies the *retimed* trajectory between
   its samples with up to about a millimetre more: a path certified at exactly the clearance
   can fail there); the first certified is returned.
4. **Repair** when none is: each segment of the best individual not certified (with
   ``certify_extra``) is re-planned as a one-via-point problem between its ends with the same
   optimizer and the budget left, and the path is certified again (``repair_rounds`` times at
   most).
5. When still not certified, the best individual's path is returned anyway, and
   :func:`~drake_mh.planning.verify_motion` reports it as not certified (never hidden).

**The deadline** bounds the whole run: with one, each generation is evaluated in chunks of
about :data:`CHUNK_SECONDS` and the deadline checked between them (a generation cut short is
told to the optimizer as it is, and the run stops); repair starts only before the deadline, and
past it the best candidates' one batched certification is all that is left to do. ``plan``
returns within :data:`DEADLINE_SLACK` of the deadline, also where one generation takes longer than
the timeout (about 1.3 s on the meshed Panda).

``info`` carries the evaluations used (``nfe``, never more than ``budget``), generations, the
best individual's fitness terms, which candidate was certified, the repair and the warm start.
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.planning.viapoint_mh.objective import ViaPointMotion, ViaPointMotionConfig

DEFAULT_BUDGET = 6000
"""Fitness evaluations when ``solve_motion`` gets no budget (one evaluation = one individual)."""

_CONFIG_FIELDS = frozenset(ViaPointMotionConfig.__dataclass_fields__)


def _split_options(options: dict, optimizer: str | None = None) -> tuple[ViaPointMotionConfig, dict]:
    """``(config, the optimizer's hyper-parameters)`` of ``solve_motion``'s keywords.

    Raises:
        InvalidArgument: a bad config, or an option that is neither a config field nor a
            hyper-parameter of ``optimizer`` (the message lists both).
    """
    config = options.pop("config", None)
    if config is not None and not isinstance(config, ViaPointMotionConfig):
        raise InvalidArgument(f"config must be a ViaPointMotionConfig, got {type(config).__name__}")
    fields = {k: options.pop(k) for k in list(options) if k in _CONFIG_FIELDS}
    if config is None:
        config = ViaPointMotionConfig(**fields)
    elif fields:
        import dataclasses

        config = dataclasses.replace(config, **fields)
    if optimizer is not None and options:  # the rest: the optimizer's hyper-parameters
        import dataclasses

        from drake_mh.optim import get_method

        known = sorted(f.name for f in dataclasses.fields(get_method(optimizer).Config))
        unknown = sorted(set(options) - set(known))
        if unknown:
            raise InvalidArgument(f"mh_{optimizer}: unknown option(s) {unknown}; options are the via-point fields "
                                  f"{sorted(_CONFIG_FIELDS | {'config'})} and {optimizer}'s hyper-parameters {known}")
    return config, options


def resample_via(path: np.ndarray, K: int) -> np.ndarray:
    """``(K, nq)`` via configurations of a path ``(M, nq)`` from its start to its goal (step 1 of
    the module docstring)."""
    path = np.asarray(path, dtype=float)
    inner = path[1:-1]
    if len(inner) <= K:
        W = list(path)
        while len(W) - 2 < K:  # split the longest segment in the middle: the polyline is unchanged
            lengths = [np.linalg.norm(b - a) for a, b in zip(W[:-1], W[1:])]
            i = int(np.argmax(lengths))
            W.insert(i + 1, 0.5 * (W[i] + W[i + 1]))
        return np.asarray(W[1:-1])
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))]
    targets = s[-1] * np.arange(1, K + 1) / (K + 1)
    return np.stack([np.interp(targets, s, path[:, j]) for j in range(path.shape[1])], axis=1)


def _warm_method(name: str):
    """The registered planner named ``name`` for a warm start (not an ``mh_*``)."""
    from drake_mh.errors import UnknownMethod
    from drake_mh.planning.solve import get_motion_method

    if not isinstance(name, str) or name.startswith("mh_"):
        raise InvalidArgument(f"warm_start must name another family of planner (e.g. 'rrt_connect'), not {name!r}")
    try:
        return get_motion_method(name)
    except UnknownMethod as exc:
        raise InvalidArgument(f"warm_start: {exc}") from None


def _warm_path(problem, goals, rng, deadline, budget: int, name: str) -> tuple[np.ndarray | None, dict]:
    """The warm-start planner's path, within the deadline and ``budget`` of its own unit (tree nodes)."""
    function = _warm_method(name)
    start = time.perf_counter()
    child = np.random.default_rng(rng.integers(2 ** 63))
    path, info = function(problem, goals, child, deadline, budget)
    out = {"method": name, "time": time.perf_counter() - start, "found": path is not None}
    if path is not None:
        path = np.asarray(path, dtype=float)
        out["waypoints"] = int(len(path))
        out["certified"] = bool(problem.scene.certify_path(path, problem.clearance, problem.self_clearance).certified)
    return path, out


def _first_population(objective: ViaPointMotion, config: ViaPointMotionConfig, pop_size: int, rng,
                      warm: np.ndarray | None) -> np.ndarray | None:
    """The seeded rows of the first population (the optimizer fills the rest uniformly)."""
    rows = []
    lo, hi = objective.bounds[:, 0], objective.bounds[:, 1]
    K, nq = objective.K, objective.nq
    via_part = np.arange(K * nq)

    def noisy(x, count, sigma):
        out = np.repeat(x[None], count, axis=0)
        out[1:, via_part] += rng.normal(0.0, sigma, size=(count - 1, K * nq))
        return np.clip(out, lo, hi)

    if warm is not None and config.warm_fraction > 0:
        goal = int(np.argmin(np.max(np.abs(objective.goals - warm[-1]), axis=1)))
        x = objective.encode(resample_via(warm, K), goal)
        rows.append(noisy(x, max(1, int(round(config.warm_fraction * pop_size))), config.warm_sigma))
    if config.init == "straight" and config.seed_fraction > 0:
        G = objective.n_goals
        count = max(G, int(round(config.seed_fraction * pop_size)))
        u = np.arange(1, K + 1) / (K + 1)
        for g in range(G):
            via = objective.q_start + u[:, None] * (objective.goals[g] - objective.q_start)
            rows.append(noisy(objective.encode(via, g), max(1, count // G), config.seed_sigma))
    if not rows:
        return None
    X0 = np.vstack(rows)
    return X0[:pop_size]


CHUNK_SECONDS = 0.05
"""[s] with a deadline, a generation is evaluated in chunks of about this duration (sized from
the measured time per individual; the first chunk has :data:`FIRST_CHUNK` individuals), and
the deadline is checked between chunks: a generation of the meshed Panda (40 individuals, 778
spheres) took 1.3 s, and checking only between generations overran a 10 s timeout by 1 s."""
FIRST_CHUNK = 4
DEADLINE_SLACK = 0.5
"""[s] documented bound on how far past its deadline :func:`plan` may return: one chunk
(:data:`CHUNK_SECONDS`, or one individual where that is longer) plus the certification of the
final candidates (one batched call: 0.07-0.15 s on the meshed Panda, ~10 ms on the capsule
Panda) on an unloaded machine; the tests allow this much."""


def _evaluate(objective: ViaPointMotion, X: np.ndarray, deadline, pace: list) -> dict:
    """``objective.terms`` of ``X``, or of its first rows when the deadline passes (module
    docstring of :data:`CHUNK_SECONDS`); ``pace[0]``: seconds per individual, updated. Rows are
    evaluated independently, so chunks give the same values as one call."""
    if deadline is None or len(X) <= 1:
        return objective.terms(X)
    parts = []
    done = 0
    while done < len(X):
        size = FIRST_CHUNK if not np.isfinite(pace[0]) else max(1, int(CHUNK_SECONDS / max(pace[0], 1e-9)))
        start = time.perf_counter()
        part = objective.terms(X[done:done + size])
        n = len(part["fitness"])
        pace[0] = (time.perf_counter() - start) / n
        parts.append(part)
        done += n
        if time.perf_counter() > deadline:
            break
    if len(parts) == 1:
        return parts[0]
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def _optimize(objective: ViaPointMotion, optimizer: str, budget: int, rng, deadline, config, params,
              x0_warm: np.ndarray | None) -> dict:
    """Steps 1-2 of the module docstring on one objective; the final population, best first."""
    from drake_mh.optim import get_method

    cls = get_method(optimizer)
    D = objective.dimension
    pop_size = config.pop_size or cls.default_pop_size(D)
    pop_size = max(pop_size, cls.min_pop_size)
    X0 = _first_population(objective, config, pop_size, rng, x0_warm)
    opt = cls(objective.bounds, budget=budget, seed=rng, pop_size=pop_size, x0=X0, **params)
    best_f, best_penalty, improved_at, generations = np.inf, np.inf, 0, 0
    patience = config.stall * budget
    best_terms, best_seen = {}, np.inf
    last_X, last_F = None, None
    reason = "budget"
    pace = [np.inf]  # seconds per individual, measured
    while not opt.done:
        X = opt.ask()
        X = X[:opt.budget - opt.nfe]
        terms = _evaluate(objective, X, deadline, pace)
        F = terms["fitness"]
        X = X[:len(F)]  # a generation cut by the deadline: what was evaluated (told, then stop)
        opt.tell(X, F)
        generations += 1
        i = int(np.argmin(F))
        if F[i] < best_seen:
            best_seen, best_terms = float(F[i]), {k: float(v[i]) for k, v in terms.items()}
        if F[i] < best_f * (1.0 - 1e-4):
            best_f, best_penalty, improved_at = float(F[i]), float(terms["penalty"][i]), opt.nfe
        if last_X is None or len(X) >= len(last_X):
            last_X, last_F = X.copy(), F.copy()
        if deadline is not None and time.perf_counter() > deadline:
            reason = "deadline"
            break
        if patience and opt.nfe - improved_at >= patience and best_penalty == 0.0 and not opt.done:
            reason = "stall"
            break
    result = opt.result()
    Xs = np.vstack([result.x[None], last_X])
    Fs = np.r_[result.f, last_F]
    if result.population is not None and result.population_f is not None:
        Xs = np.vstack([Xs, result.population])
        Fs = np.r_[Fs, result.population_f]
    order = np.argsort(Fs, kind="stable")
    Xs, Fs = Xs[order], Fs[order]
    _, first = np.unique(np.round(Xs, 12), axis=0, return_index=True)
    keep = np.sort(first)
    return {"X": Xs[keep], "F": Fs[keep], "nfe": int(opt.nfe), "generations": generations, "stop": reason,
            "pop_size": pop_size, "best_terms": best_terms}


def _certify_candidates(problem, objective: ViaPointMotion, X: np.ndarray, count: int, extra: float = 0.0):
    """Index of the first individual of ``X[:count]`` whose path is certified with ``extra`` [m]
    above the problem's clearances (None if none is), the paths, the blocked segments of each."""
    paths = [objective.path(x) for x in X[:count]]
    QA = np.vstack([P[:-1] for P in paths])
    QB = np.vstack([P[1:] for P in paths])
    cert = problem.scene.certify_segments(QA, QB, problem.clearance + extra, problem.self_clearance + extra)
    ok = cert.certified
    start = 0
    first = None
    blocked = []
    for i, P in enumerate(paths):
        n = len(P) - 1
        seg = ok[start:start + n]
        blocked.append(np.flatnonzero(~seg))
        if first is None and np.all(seg):
            first = i
        start += n
    return first, paths, blocked


def _repair(problem, path: np.ndarray, blocked: np.ndarray, optimizer: str, budget: int, rng, deadline,
            config: ViaPointMotionConfig, params: dict) -> tuple[np.ndarray, int, int]:
    """Re-plan each blocked segment of ``path`` with one via point; returns the new path, the
    evaluations used and the segments re-planned."""
    if budget < 2 or not len(blocked):
        return path, 0, 0
    share = max(2, budget // len(blocked))
    used = 0
    pieces = []
    blocked = set(int(b) for b in blocked)
    for i in range(len(path) - 1):
        pieces.append(path[i][None])
        if i not in blocked or used + 2 > budget or (deadline is not None and time.perf_counter() > deadline):
            continue
        sub = ViaPointMotion(problem.robot, problem.scene, path[i], path[i + 1][None], problem.clearance,
                             problem.self_clearance, config, problem.frame, n_via=1)
        run = _optimize(sub, optimizer, min(share, budget - used), rng, deadline, config, params, None)
        used += run["nfe"]
        first, paths, _ = _certify_candidates(problem, sub, run["X"], config.candidates, config.certify_extra)
        pieces.append(paths[0 if first is None else first][1:-1])
    pieces.append(path[-1][None])
    return np.vstack(pieces), used, len(blocked)


_PREPARED: dict = {}


def prepare(problem, optimizer: str | None = None, **options) -> None:
    """Compile what a run needs (sphere-model clearances, FK, the gravity screen, certified
    segments) by one small untimed evaluation, once per robot, trajectory kind and process,
    start ``optimizer`` once (its library's import: cma's first run took 0.7 s), and, with
    ``warm_start``, prepare that planner too
    (:func:`~drake_mh.planning.solve.prepare_motion_method`); ``solve_motion`` calls it with the
    run's options before the clock starts.

    Raises:
        InvalidArgument: bad options (the same as :func:`plan` would raise).
    """
    config, _ = _split_options(dict(options), optimizer)
    key = (id(problem.robot), config.trajectory)
    if _PREPARED.get(key) is not problem.robot:
        robot = problem.robot
        objective = ViaPointMotion(robot, problem.scene, problem.q_start, problem.q_start[None], 0.0, 0.0,
                                   ViaPointMotionConfig(n_via=1, samples=2, trajectory=config.trajectory))
        objective.terms(np.repeat(objective.bounds.mean(axis=1)[None], 2, axis=0))
        problem.scene.certify_segments(problem.q_start, problem.q_start)
        _PREPARED[key] = robot
    if optimizer is not None and ("optimizer", optimizer) not in _PREPARED:
        from drake_mh.optim import get_method

        cls = get_method(optimizer)
        size = max(2, cls.min_pop_size)
        cls(np.array([[0.0, 1.0]] * 2), budget=size, seed=0, pop_size=size).ask()
        _PREPARED[("optimizer", optimizer)] = True
    if config.warm_start is not None:
        from drake_mh.planning.solve import prepare_motion_method

        prepare_motion_method(_warm_method(config.warm_start), problem)


def plan(problem, goals, rng, deadline, budget, *, optimizer: str, **options):
    """Plan with via-point trajectory optimization (module docstring); ``options``: the fields
    of :class:`~.objective.ViaPointMotionConfig` (or ``config=``) and the optimizer's
    hyper-parameters."""
    config, params = _split_options(dict(options), optimizer)
    budget = DEFAULT_BUDGET if budget is None else int(budget)
    info = {"optimizer": optimizer, "n_via": config.n_via, "trajectory": config.trajectory, "budget": budget}
    warm = None
    if config.warm_start is not None:
        warm, info["warm_start"] = _warm_path(problem, goals, rng, deadline, budget, config.warm_start)
    objective = ViaPointMotion(problem.robot, problem.scene, problem.q_start, goals, problem.clearance,
                               problem.self_clearance, config, problem.frame)
    reserve = int(budget * config.repair_fraction) if config.repair and config.repair_rounds else 0
    main_budget = max(1, budget - reserve)
    run = _optimize(objective, optimizer, main_budget, rng, deadline, config, params, warm)
    info.update(nfe=run["nfe"], generations=run["generations"], stop=run["stop"], pop_size=run["pop_size"],
                dimension=objective.dimension)
    info["best"] = run["best_terms"]
    first, paths, blocked = _certify_candidates(problem, objective, run["X"], config.candidates,
                                                config.certify_extra)
    info["candidate"] = first
    if first is not None:
        info["certified_by_planner"] = True
        return paths[first], info
    path = paths[0]
    info["best_blocked_segments"] = [int(b) for b in blocked[0]]
    left = budget - run["nfe"]
    rounds = 0
    extra = config.certify_extra
    while config.repair and rounds < config.repair_rounds and left >= 2 \
            and (deadline is None or time.perf_counter() < deadline):
        cert = problem.scene.certify_path(path, problem.clearance + extra, problem.self_clearance + extra)
        bad = np.flatnonzero(~cert.segments.certified)
        if not len(bad):
            break
        path, used, _ = _repair(problem, path, bad, optimizer, left, rng, deadline, config, params)
        left -= used
        info["nfe"] += used
        rounds += 1
    info["repair_rounds"] = rounds
    if not rounds and deadline is not None and time.perf_counter() > deadline:
        info["certified_by_planner"] = False  # not certified with certify_extra; no time left to ask more
        info["note"] = "the deadline passed before a certified candidate was found; returned for the verification"
        return path, info
    certified = bool(problem.scene.certify_path(path, problem.clearance, problem.self_clearance).certified)
    info["certified_by_planner"] = certified
    if not certified:
        info["note"] = ("the best individual (and the next best of the final population) is not certified "
                        "collision-free; returned for the verification to report")
    return path, info
