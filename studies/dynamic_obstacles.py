"""Dynamic obstacles: reactive control of the Panda among moving obstacles.

Part ``"esm"`` (this file so far): the ESM paper's scheme (eqs. (6)-(11)) on its two
scenarios, solved every Δt = 0.028 s by AMNN (ARO layers, eqs. (12)-(21)), other
``drake_mh.optim`` metaheuristics with the same evaluation budget, and a velocity-level QP
(OSQP) with the same constraints. Every accepted step is checked with Drake (joint and
velocity limits, the obstacle inequality with Drake's Jacobians); the exact clearance is
measured with Drake's signed distance after the obstacles move.

Metrics per case: closest distance (min) and samples below the threshold, the certified
clearance of the whole executed motion (between the samples too, the obstacles moving:
``ESMRun.motion_min_clearance``; success requires it), tracking error
(final, and steady state = median over the samples where no obstacle row is active),
manipulability against the approximate optimum μ* (multi-start SLSQP with the flange
pinned), steps per second (1 / median compute time of a step: distance query + rows +
solve), and the ratio of the step time to the QP baseline's, measured in the same process
right after the case.

Weights: ``h1`` is a grid value (h2 = 1). At the paper's target the exact minimizer of
``e + 1/μ`` (h1 = h2 = 1) lies 3.8 cm off the target (``||∇_r(1/μ*)|| = 2.39 > h1``), so
scenario 1 uses h1 = 10 (pins the flange, same optimum μ*); h1 = 1 is run for AMNN to show
the drift. In scenario 2 the cube pushes the arm to μ ≈ 0.04-0.07 where ``∇(1/μ)`` is steep:
with h1 = 10 the ESM optimum leaves the path by up to 0.3 m (AMNN finds F = 10.3 there, the
QP's on-path solution has F = 25.6), so scenario 2 uses h1 = 100.

Part ``"framework"``: the framework paper's regenerating follower (§3.4, Algorithms 1-2) on
its Table 3 scenario (seed000_6dof, 50-point path, a sphere moved from (0.2, 0.2, 0.6) to
(0.1, 0.15, 0.4) while the arm runs), scenario ``table3``, and ``table3_cut`` where the
obstacle is also moved onto the path (§3.4.2 re-planning of the 3·nC points); any IK method
(:func:`drake_mh.reactive.follower.scenario.run_framework_scenario`), and
``table3_cut_spread``: the same with the continuity repair ``FollowerConfig(spread_step=0.3)``
(neighbours of a branch switch solved again; not in the paper). Metrics: points
regenerated (and re-solved by the repair), regeneration time per event, largest joint step
(plan vs executed), exact clearance at the points, the certified clearance of the executed
motion between them (the follower executes only certified motions and detours where a straight
joint-space line is not certified: detours taken, their cost; success requires the certified
motion), and Drake's exact distance at 4 samples per straight piece for comparison.

Run: ``drake-mh study dynamic_obstacles [--quick]`` or ``python studies/dynamic_obstacles.py``.
Full grid (138 cases): 41 min on 2 shared cores at load ~5 (the 105 framework cases 19 min,
``--first-by h1,rep`` runs them first); ``--quick``: ~35 s.
"""

from __future__ import annotations

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.report.summary import cell, finished, group_by, markdown_table, median, values

LAYERS, AGENTS = 1000, 128                   # the paper's AMNN budget per control step, every solver
QUICK_LAYERS, QUICK_AGENTS = 100, 32
OTHER_METHODS = ("pso", "de", "e3gsa")
SEEDS, QUICK_SEEDS = 3, 1
DURATION = {"self_motion": 4.5, "tracking": 15.0}
QUICK_DURATION = {"self_motion": 4.5, "tracking": 6.0}
OPTIMUM_SAMPLE = 0.5                         # [s] between μ* samples on a moving target
H1 = {"self_motion": 10.0, "tracking": 100.0}  # tracking weight per scenario (module docstring)


def _solver(method: str, layers: int, agents: int):
    from drake_mh.reactive import AMNN, MetaheuristicSolver, QPBaseline

    if method == "amnn":
        return AMNN(layers=layers, agents=agents)
    if method == "qp":
        return QPBaseline()
    return MetaheuristicSolver(method, budget=(layers + 1) * agents, pop_size=agents)


def _optimum(robot, scenario, t: np.ndarray) -> np.ndarray:
    """μ* at every sample time (fixed target: one multi-start; moving: sampled + interpolated)."""
    from drake_mh.reactive import optimal_manipulability, optimal_manipulability_along

    targets = np.array([scenario.target(ti) for ti in t])
    if np.allclose(targets, targets[0]):
        mu, _ = optimal_manipulability(robot, targets[0], starts=32, theta_hint=scenario.theta0)
        return np.full(len(t), mu)
    ts = np.arange(0.0, t[-1] + OPTIMUM_SAMPLE, OPTIMUM_SAMPLE)
    mus, _ = optimal_manipulability_along(robot, [scenario.target(x) for x in ts], theta_start=scenario.theta0,
                                          starts=16, restarts=2)
    return np.interp(t, ts, mus)


FRAMEWORK_METHODS = ("e3gsa", "pso", "gsa", "woa", "bat", "ao", "hybrid")
QUICK_FRAMEWORK_METHODS = ("e3gsa",)
FRAMEWORK_SEEDS = 5                          # the moved sphere meets the arm on some IK branches only
SPREAD_STEP = 0.3                            # [rad] continuity repair of scenario table3_cut_spread


def run(case: Case) -> dict:
    """One case: an ESM closed-loop run (part "esm") or a framework follower run."""
    if case["part"] == "framework":
        return run_framework(case)
    return run_esm_case(case)


def run_framework(case: Case) -> dict:
    """The framework paper's scenario with one IK method (part "framework")."""
    from drake_mh.reactive.follower.scenario import PATH_EVENT, run_framework_scenario

    from drake_mh.reactive.follower import FollowerConfig

    scenario = case["scenario"]
    event = PATH_EVENT if scenario.startswith("table3_cut") else None
    config = FollowerConfig(spread_step=SPREAD_STEP if scenario.endswith("_spread") else None)
    # seed = replicate: every method and scenario variant of replicate r solves the same IK
    # seeds, so table3_cut and table3_cut_spread start from the same plan (paired comparison)
    record = run_framework_scenario(case["method"], seed=int(case["rep"]), path_event=event, config=config)
    record.pop("seed", None)  # the runner records the case seed itself
    record.pop("method", None)
    record.setdefault("nfe", 0)
    return record


def run_esm_case(case: Case) -> dict:
    """One ESM closed-loop run (part "esm")."""
    import drake_mh
    from drake_mh.reactive import ESMConfig, QPBaseline, get_scenario, run_esm
    from drake_mh.reactive.esm.plots import figure_png

    robot = drake_mh.load_robot("panda")
    durations = QUICK_DURATION if case.quick else DURATION
    config = ESMConfig(h1=float(case["h1"]))
    scenario = get_scenario(case["scenario"], config=config, duration=durations[case["scenario"]])
    solver = _solver(case["method"], *((QUICK_LAYERS, QUICK_AGENTS) if case.quick else (LAYERS, AGENTS)))
    result = run_esm(robot, scenario, solver, seed=case.seed)
    reference = run_esm(robot, scenario, QPBaseline(), seed=0, verify=False)   # same process, right after

    mu_opt = _optimum(robot, scenario, result.t)
    ratio = result.mu / mu_opt
    free = np.concatenate([[True], result.active_rows == 0])       # samples with no active obstacle row
    settled = result.t >= 0.5
    steady = free & settled
    first_active = np.flatnonzero(result.active_rows > 0)
    t_contact = result.t[first_active[0] + 1] if len(first_active) else np.inf
    before = settled & (result.t < t_contact)                      # settled, before the first contact
    checks_ok = bool(np.nanmax(result.joint_violation) <= 1e-9 and np.nanmax(result.velocity_violation) <= 1e-7
                     and np.nanmax(result.inequality_violation) <= 1e-6)
    step_time = float(np.median(result.step_time))
    qp_time = float(np.median(reference.step_time))
    record = {
        "success": bool(checks_ok and result.threshold_violations == 0 and result.motion_certified),
        "motion_certified": bool(result.motion_certified),
        "motion_min_clearance": float(result.motion_min_clearance),
        "motion_first_failure": int(result.motion_first_failure),
        "error": float(np.median(result.error[steady])) if steady.any() else float(result.error[-1]),
        "time": step_time,
        "nfe": int(np.median(result.nfe)),
        "budget": result.budget,
        "min_distance": float(np.min(result.min_distance)),
        "threshold": config.threshold,
        "threshold_violations": result.threshold_violations,
        "checks_ok": checks_ok,
        "max_inequality_violation": float(np.nanmax(result.inequality_violation)),
        "max_jacobian_error": float(np.nanmax(result.jacobian_error)),
        "final_error": float(result.error[-1]),
        "max_error_settled": float(np.max(result.error[settled])),
        "mu_final": float(result.mu[-1]),
        "mu_opt_final": float(mu_opt[-1]),
        "mu_ratio_final": float(ratio[-1]),
        "mu_ratio_steady": float(np.median(ratio[steady])) if steady.any() else float("nan"),
        "mu_ratio_before_contact": float(np.median(ratio[before])) if before.any() else float("nan"),
        "error_before_contact": float(np.max(result.error[before])) if before.any() else float("nan"),
        "t_first_contact": float(t_contact),
        "mu_ratio_min": float(np.min(ratio)),
        "steps_per_second": 1.0 / step_time,
        "mean_step_time": float(np.mean(result.step_time)),
        "max_step_time": float(np.max(result.step_time)),
        "solve_time": float(np.median(result.solve_time)),
        "qp_step_time": qp_time,
        "ratio_to_qp": step_time / qp_time,
        "solver_infeasible_steps": int(np.sum(~result.solver_feasible)),
        "relaxed_steps": int(np.sum(result.relaxed_rows > 0)),
        # time series (Fig. 4): small, kept for every case
        "series_t": result.t,
        "series_min_distance": result.min_distance,
        "series_mu": result.mu,
        "series_mu_opt": mu_opt,
        "series_error": result.error,
        "series_step_time": result.step_time,
    }
    if case["rep"] == 0:
        record["traj_t"] = result.t
        record["traj_q"] = result.theta
        title = f"{case['scenario']}, {case['method']} ({result.budget}), h1 = {case['h1']:g}"
        case.attach("fig4.png", figure_png(result, mu_opt, title))
    return record


def _cases(quick: bool) -> list[dict]:
    seeds = range(QUICK_SEEDS if quick else SEEDS)
    methods = ("amnn", "pso", "qp") if quick else ("amnn", *OTHER_METHODS, "qp")
    cases = []
    for scenario in ("self_motion", "tracking"):
        for method in methods:
            if quick and scenario == "tracking" and method == "pso":
                continue
            cases += [{"part": "esm", "scenario": scenario, "h1": H1[scenario], "method": method, "rep": r}
                      for r in seeds]
    cases += [{"part": "esm", "scenario": "self_motion", "h1": 1.0, "method": "amnn", "rep": r} for r in seeds]
    for scenario in ("table3", "table3_cut", "table3_cut_spread"):
        for method in (QUICK_FRAMEWORK_METHODS if quick else FRAMEWORK_METHODS):
            cases += [{"part": "framework", "scenario": scenario, "h1": 0.0, "method": method, "rep": r}
                      for r in range(QUICK_SEEDS if quick else FRAMEWORK_SEEDS)]
    return cases


def _lowest(rows: list[dict], key: str, spec: str = ".3f") -> str:
    """The smallest finite value of ``key`` over the seeds ("-" when none)."""
    found = values(rows, key)
    return cell(found.min() if found.size else None, spec)


def _framework_table(records: list[dict]) -> list[str]:
    """Medians per (scenario, method) of the framework follower runs."""
    rows = []
    for (scenario, method), group in group_by(records, "scenario", "method").items():
        ok = finished(group)
        if not ok:
            rows.append([scenario, method, len(group), "raised"] + [""] * 9)
            continue

        def med(key):
            return median(r.get(key, np.nan) for r in ok)

        def total(key):
            return sum(r.get(key, 0) for r in ok)

        rows.append([scenario, method, len(ok), f"{sum(bool(r['success']) for r in ok)}/{len(ok)}",
                     f"{med('points_regenerated'):.0f} (+{med('points_spread'):.0f})", f"{med('time'):.3f}",
                     f"{med('max_step_plan'):.2f} -> {med('max_step_executed'):.2f}",
                     f"{_lowest(ok, 'min_distance_executed')} / {_lowest(ok, 'motion_min_clearance')} / "
                     f"{_lowest(ok, 'min_distance_swept')}",
                     sum(not r.get("motion_certified", False) for r in ok),
                     f"{total('detours_found')} / {total('detours_failed')} ({total('detour_vias')}, "
                     f"{total('detour_time'):.2f}, {total('detour_extra_length'):.2f})",
                     sum(bool(r.get("halted")) for r in ok), _lowest(ok, "clearance_at_move"),
                     _lowest(ok, "min_distance_after_move")])
    return ["Framework follower (part framework): medians over seeds, except success, the clearances "
            "(minimum over seeds) and the detour counts (sums over seeds). Clearance at the points: Drake's "
            "exact distance (refined capsule-box/cylinder pairs); of the motion: certified lower bound over "
            "every configuration of the executed motion between the points, detours included (sphere model, "
            "tolerance 1 mm), over the runs whose motion is certified (the others counted); sampled: Drake "
            "at 4 interior samples per straight piece. Detours: motions between two points whose straight "
            "joint-space line was not certified, found / not found (vias inserted, search time, extra "
            "joint-space length summed over seeds).", ""] + markdown_table(
        ["scenario", "method", "runs", "success", "points regenerated (+ spread)", "regeneration time [s]",
         "largest joint step plan -> executed [rad]", "min clearance at points / of the motion (certified) / sampled [m]",
         "motion not certified", "detours found / not found (vias, time [s], extra [rad])", "halted",
         "clearance of the configuration held when the move is seen, against the new position [m]",
         "min clearance after it [m]"], rows)


def _esm_row(part, scenario, h1, method, group: list[dict]) -> list:
    ok = finished(group)
    if not ok:
        return [part, scenario, f"{h1:g}", method, "-", "raised"] + [""] * 11
    bad = sum(not r.get("motion_certified", False) for r in ok)
    med = {k: median(values(ok, k)) for k in ("error_before_contact", "error", "final_error", "mu_ratio_before_contact",
                                              "mu_ratio_steady", "mu_ratio_final", "steps_per_second", "ratio_to_qp")}
    return [part, scenario, f"{h1:g}", method, ok[0]["budget"],
            f"{min(r['min_distance'] for r in ok):.4f} (d={ok[0]['threshold']:g})",
            _lowest(ok, "motion_min_clearance", ".4f") + (f" ({bad} not certified)" if bad else ""),
            sum(r["threshold_violations"] for r in ok), "ok" if all(r["checks_ok"] for r in ok) else "FAIL",
            f"{med['error_before_contact']:.1e}", f"{med['error']:.1e}", f"{med['final_error']:.1e}",
            f"{med['mu_ratio_before_contact']:.4f}", f"{med['mu_ratio_steady']:.4f}", f"{med['mu_ratio_final']:.4f}",
            f"{med['steps_per_second']:.1f}", f"{med['ratio_to_qp']:.1f}"]


def summarize(records: list[dict]) -> str:
    """Table in the spirit of the paper's Fig. 4 numbers, one row per (part, scenario, h1, method)."""
    framework = [r for r in records if r["part"] == "framework"]
    esm = group_by([r for r in records if r["part"] == "esm"], "part", "scenario", "h1", "method")
    lines = [
        "Medians over seeds. d = threshold; min dist = exact clearance at the samples (Drake); certified motion "
        "clearance = certified lower bound over the whole executed motion between the samples (obstacles "
        "moving; success requires it); viol = samples with exact clearance < d (Drake); before contact = "
        "samples from 0.5 s until the first active obstacle row; steady = samples after 0.5 s with no "
        "active obstacle row; μ/μ* against multi-start SLSQP with the "
        "flange pinned; steps/s = 1 / median step compute time; ×QP = step time / QP step time "
        "(same process).", ""] + markdown_table(
        ["part", "scenario", "h1", "method", "budget", "min dist [m]", "certified motion clearance [m]", "viol",
         "checks", "max err before contact [m]", "steady err [m]", "final err [m]", "μ/μ* before contact",
         "μ/μ* steady", "μ/μ* final", "steps/s", "×QP"], [_esm_row(*key, group) for key, group in esm.items()])
    if framework:
        lines += [""] + _framework_table(framework)
    return "\n".join(lines)


study = Study(
    name="dynamic_obstacles",
    run=run,
    grid=_cases(False),
    quick_grid=_cases(True),
    seed=0,
    fields=Fields(method="method", success="success", time="time", error="error", nfe="nfe",
                  instance=("part", "scenario", "h1", "rep"), group_by=("part", "scenario", "h1")),
    description=(
        "Reactive control among moving obstacles on the Panda. Part esm: the ESM paper's scheme "
        "(joint-angle-level step with manipulability, tracking and the velocity-aware obstacle "
        "inequality) on its self-motion and trajectory-tracking scenarios, solved by AMNN, other "
        "metaheuristics at the same evaluation budget and a velocity-level OSQP baseline; every "
        "step verified with Drake. See docs/esm.md. Part framework: the framework paper's regenerating "
        "follower (IK regeneration of colliding points, Algorithm 2 re-planning of path cuts) on its "
        "Table 3 scenario with any IK method. See docs/follower.md."),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
