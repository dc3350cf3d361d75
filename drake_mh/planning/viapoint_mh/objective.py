"""The via-point motion objective: the ABC paper's fitness on K via configurations, batched.

Decision vector of one individual (``D`` values, box bounds; see :class:`ViaPointMotion`):

* ``linear`` (default): the ``K`` via configurations ``(K, nq)`` inside the joint limits; the
  motion is the piecewise-linear joint-space path ``q_start -> via_1 -> ... -> via_K -> goal``
  (exactly what :func:`drake_mh.planning.verify_motion` certifies);
* ``polynomial``: the ABC paper's design vector (§III, eqs. 21-23) for n joints: via angles
  ``(K, nq)`` (joint limits), via velocities ``(K, nq)`` (``±min(π/4, v_max)`` rad/s, eq. 22),
  segment times ``(K + 1,)`` ([0.1, 8] s, eq. 23); the motion is the 4th/5th-order via-point
  polynomial (:func:`drake_mh.trajectories.viapoint.segment_coefficients`), *returned as its
  dense samples*: the verified motion is the polyline through them, and every fitness term is
  computed on that same polyline;
* with several goal configurations ``G > 1``, one more value in ``[0, G)`` picks the goal (its
  floor): our reading of the paper's "posture of the final configuration (n - m parameters)",
  the redundancy at the goal, for goals given as configurations (a pose goal arrives as the
  collision-free IK answers of :func:`drake_mh.planning.goal_configurations`).

Fitness (ABC paper eq. 18, ``β = [1, 2, 2, 1]``, and eq. 20), per individual, on ``S`` samples
per segment (``M = (K + 1) S + 1`` configurations, ends included):

    f_f = β1 f_ot + β2 f_q + β3 f_c + β4 t_T,        f = f_f / f_ob,   f_ob = 1 / (1 + κ Π)

* ``f_q`` [rad]: total joint travel ``Σ_j Σ_k |Δq_j|`` (exact for the linear path);
* ``f_c``: end-effector path length, polyline of the samples' Drake-compiled FK, in
  ``length_unit`` (default 1 m: the 2R paper's foot unit, :mod:`drake_mh.trajectories.viapoint`,
  belongs to its 1-ft links, not to an arbitrary arm);
* ``t_T`` [s]: linear: ``Σ_segments max_j T_j``, ``T_j`` the rest-to-rest time of joint j over
  its ``|Δq_j|`` under its velocity and acceleration limits (trapezoid or triangle profile) — the
  duration of a motion that stops at every via point, a stand-in for the retimed duration
  (which :func:`verify_motion` measures afterwards); polynomial: ``Σ T_i`` (the paper's);
* ``f_ot``: torque excess. Polynomial: the paper's ``Σ_j ∫ max(0, |τ_j| - τ_max,j) dt``
  [N·m·s] with the inverse dynamics of the polynomial (gravity included). Linear: the path has
  no timing — the retimer (toppra, torque rows) slows down until dynamic torques fit — so the
  only torque excess no timing removes is the gravity torque of holding a configuration:
  ``Σ_k w_k Σ_j max(0, |g_j(q_k)| - τ_max,j)`` [N·m·rad], ``w_k`` the joint-space length of the
  sample interval, on every ``torque_stride``-th sample;
* ``Π`` [m·rad], the collision penalty of ``f_ob``: per sample interval ``k`` and constraint
  ``c`` (each link against every obstacle; each checked link pair), the *certified* lower bound
  of the clearance over the whole interval ``l_kc = (V_kc + V_k+1,c - Λ_kc) / 2`` with
  ``Λ_kc = Σ_j reach[c, j] |Δq_kj|`` (the bound :mod:`drake_mh.scene.segments` certifies with,
  values ``V`` from the sphere model's per-link clearances,
  :meth:`~drake_mh.scene.batch.CollisionModel.clearances`, population × samples in one call),
  then ``Π = Σ_k (|Δq_k| + 1e-3) Σ_c max(0, d_c - l_kc)`` with ``d_c`` the problem's clearance
  (or self-clearance) plus ``margin``. So ``Π = 0`` implies that the polyline keeps
  ``clearance + margin`` at *every* configuration, not only at the samples (a thin shelf board
  between two samples is seen), and ``f = f_f`` for any such motion, as in the paper. The
  weighting by the joint distance travelled (not by time, as in the 2R implementation) keeps
  a fast swing through an obstacle from being cheap;
* polynomial mode adds the joint-limit excess of the samples [rad] to ``Π`` (the polynomial
  may overshoot between via points; the returned samples are clipped into the limits, and the
  fitness is computed on the clipped polyline).

Everything is vectorized over the population: one ``clearances`` call, one FK call (and one
inverse-dynamics call) per evaluation of ``P`` individuals; no Python loop over individuals.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument

TRAJECTORIES = ("linear", "polynomial")

VIA_VELOCITY_BOUND = np.pi / 4
"""[rad/s] ABC paper eq. (22): via joint velocities in ``±π/4`` (capped at each joint's limit)."""

TIME_BOUNDS = (0.1, 8.0)
"""[s] ABC paper eq. (23): each segment's duration."""


@dataclass(frozen=True)
class ViaPointMotionConfig:
    """Options of the via-point motion planners (``mh_<optimizer>``), with their defaults.

    Attributes:
        n_via: ``K``, via configurations between the start and the goal (2: a detour around
            one obstacle needs one corner, a shelf often two; measured in docs/planning_viapoint.md).
        trajectory: ``"linear"`` (piecewise-linear path through the via points) or
            ``"polynomial"`` (the ABC paper's 4th/5th-order via-point polynomials, returned as
            their dense samples).
        samples: ``S``, samples per segment for the fitness (and, polynomial, the returned
            waypoints per segment).
        weights: ``(β1, β2, β3, β4)`` of ``f_ot, f_q, f_c, t_T`` (ABC paper: ``[1, 2, 2, 1]``).
        length_unit: unit of ``f_c`` [m].
        kappa: ``κ`` of ``f_ob = 1 / (1 + κ Π)`` [1/(m·rad)].
        margin: [m] added to the problem's clearances inside the penalty only, so the best
            individual keeps a little room and certifies (the certificate uses the problem's).
        torque_stride: linear mode: gravity torque on every this-many-th sample (0: never).
        pop_size: population size (``None``: the optimizer's default for the dimension).
        init: ``"straight"``: part of the first population (``seed_fraction``) lies around the
            straight line to each goal (evenly spaced via points, Gaussian noise of
            ``seed_sigma`` rad), the rest uniform in the box; ``"uniform"``: all uniform.
        seed_fraction, seed_sigma: see ``init``.
        warm_start: name of a registered motion method (``"rrt_connect"``) whose path seeds
            ``warm_fraction`` of the first population (its via points, resampled to ``K``, and
            noisy copies with ``warm_sigma`` rad); ``None``: cold start. It plans within the
            run's deadline and with the run's ``budget`` in its own unit (tree nodes).
        warm_fraction, warm_sigma: see ``warm_start``.
        stall: stop early when the best fitness improved by less than ``1e-4`` (relative)
            during the last ``stall`` × budget evaluations and the best individual's penalty
            is 0 (0: never; the run then uses the whole budget).
        candidates: individuals of the final population (best first) certified before giving
            up on the population.
        certify_extra: [m] the planner accepts a path certified with this much more than the
            problem's clearances (``verify_motion`` certifies the retimed trajectory between its
            samples with up to about 1 mm more: a path certified at exactly the clearance can
            fail there).
        repair: when none of them is certified, re-plan each blocked segment with one more via
            point (same optimizer, the budget left over, up to ``repair_rounds`` times).
        repair_rounds: see ``repair``.
        repair_fraction: share of the budget kept back for the repair (when no repair is
            needed it is simply not used).
    """

    n_via: int = 2
    trajectory: str = "linear"
    samples: int = 32
    weights: tuple = (1.0, 2.0, 2.0, 1.0)
    length_unit: float = 1.0
    kappa: float = 1e4
    margin: float = 0.01
    torque_stride: int = 8
    pop_size: int | None = None
    init: str = "straight"
    seed_fraction: float = 0.25
    seed_sigma: float = 0.3
    warm_start: str | None = None
    warm_fraction: float = 0.5
    warm_sigma: float = 0.05
    stall: float = 0.25
    candidates: int = 8
    certify_extra: float = 0.002
    repair: bool = True
    repair_rounds: int = 2
    repair_fraction: float = 0.2

    def __post_init__(self):
        def integer(name, low):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
                raise InvalidArgument(f"{name} must be an integer >= {low}, got {v!r}")

        def number(name, low, high=np.inf, open_low=False):
            v = getattr(self, name)
            ok = isinstance(v, (int, float, np.number)) and not isinstance(v, bool) and np.isfinite(v)
            if not ok or v < low or v > high or (open_low and v == low):
                raise InvalidArgument(f"{name} must be a number in {'(' if open_low else '['}{low}, {high}], got {v!r}")

        integer("n_via", 1), integer("samples", 2), integer("torque_stride", 0)
        integer("candidates", 1), integer("repair_rounds", 0)
        if self.trajectory not in TRAJECTORIES:
            raise InvalidArgument(f"trajectory must be one of {TRAJECTORIES}, got {self.trajectory!r}")
        if self.init not in ("straight", "uniform"):
            raise InvalidArgument(f"init must be 'straight' or 'uniform', got {self.init!r}")
        w = np.asarray(self.weights, dtype=float) if not isinstance(self.weights, str) else np.zeros(0)
        if w.shape != (4,) or not np.all(np.isfinite(w)) or np.any(w < 0):
            raise InvalidArgument(f"weights must be 4 numbers >= 0 (β1..β4 of f_ot, f_q, f_c, t_T), "
                                  f"got {self.weights!r}")
        object.__setattr__(self, "weights", tuple(float(x) for x in w))
        number("length_unit", 0, open_low=True), number("kappa", 0), number("margin", 0)
        number("seed_fraction", 0, 1), number("seed_sigma", 0), number("warm_fraction", 0, 1)
        number("warm_sigma", 0), number("repair_fraction", 0, 0.9), number("stall", 0, 1)
        number("certify_extra", 0)
        if self.pop_size is not None:
            integer("pop_size", 2)
        if self.warm_start is not None and not isinstance(self.warm_start, str):
            raise InvalidArgument(f"warm_start must be a motion method name or None, got {self.warm_start!r}")


def rest_to_rest_time(distance: np.ndarray, v_max: np.ndarray, a_max: np.ndarray) -> np.ndarray:
    """[s] shortest rest-to-rest time over ``distance >= 0`` under ``v_max``, ``a_max``
    (trapezoid, or triangle when the limit speed is not reached), elementwise; an infinite
    limit drops out (both infinite: 0)."""
    d = np.abs(distance)
    with np.errstate(divide="ignore", invalid="ignore"):
        triangle = 2.0 * np.sqrt(d / a_max)
        trapezoid = d / v_max + v_max / a_max
        reach = v_max * v_max / a_max  # distance at which the speed limit is reached
        t = np.where(d >= reach, trapezoid, triangle)
        t = np.where(np.isinf(a_max), d / v_max, t)
    return np.nan_to_num(t, nan=0.0, posinf=0.0)


_GRAVITY_SCREEN: dict = {}


def gravity_may_exceed(robot, samples: int = 4096) -> bool:
    """Whether the gravity torque can come near a joint's effort limit: ``False`` when it stays
    below 80 % of every limit at ``samples`` random configurations (seed 0), cached per robot.
    A screen, not a bound: the linear mode then skips its gravity term (``f_ot = 0``, the
    verification's retiming still certifies the torques)."""
    key = id(robot)
    hit = _GRAVITY_SCREEN.get(key)
    if hit is not None and hit[0] is robot:
        return hit[1]
    from drake_mh.trajectories.dynamics import batch_dynamics

    Q = robot.random_configurations(samples, 0)
    zero = np.zeros_like(Q)
    g = batch_dynamics(robot).inverse_dynamics(Q, zero, zero)
    effort = np.asarray(robot.effort_limits, dtype=float)
    out = bool(np.any(np.abs(g) >= 0.8 * effort))
    _GRAVITY_SCREEN[key] = (robot, out)
    return out


class ViaPointMotion:
    """Vectorized fitness ``f(X (P, D)) -> (P,)`` of K via points from ``q_start`` to ``goals``.

    Args:
        robot, scene: the problem's robot and scene.
        q_start: ``(nq,)`` start (at rest).
        goals: ``(G, nq)`` goal configurations (any one).
        clearance, self_clearance: the problem's required clearances [m].
        config: :class:`ViaPointMotionConfig`.
        frame: end-effector frame for ``f_c`` (``None``: the robot's).
        n_via: overrides ``config.n_via`` (the repair plans single segments with 1).
    """

    def __init__(self, robot, scene, q_start, goals, clearance: float, self_clearance: float,
                 config: ViaPointMotionConfig, frame: str | None = None, n_via: int | None = None):
        self.robot, self.scene, self.config, self.frame = robot, scene, config, frame
        self.q_start = np.asarray(q_start, dtype=float).copy()
        self.goals = np.atleast_2d(np.asarray(goals, dtype=float)).copy()
        self.K = int(config.n_via if n_via is None else n_via)
        self.nq = robot.nq
        self.polynomial = config.trajectory == "polynomial"
        self.S = int(config.samples)
        model = scene.collision_model
        self._model = model
        self._obstacles = scene.obstacle_arrays
        self._n_obstacles = len(self._obstacles[0])
        self._reach_T = np.ascontiguousarray(model.reach.T)  # (nq, G + P)
        required = np.r_[np.full(model.num_links, clearance), np.full(model.num_pairs, self_clearance)]
        self._required = required + config.margin
        self._fine_below = float(np.max(self._required, initial=0.0)) + 0.05
        self._check_collisions = self._n_obstacles > 0 or model.num_pairs > 0
        lower, upper = robot.lower, robot.upper
        rows = [np.c_[lower, upper]] * self.K
        if self.polynomial:
            v = np.minimum(VIA_VELOCITY_BOUND, robot.velocity_limits)
            rows += [np.c_[-v, v]] * self.K + [np.array([TIME_BOUNDS] * (self.K + 1))]
        self.n_goals = len(self.goals)
        if self.n_goals > 1:
            rows.append(np.array([[0.0, float(self.n_goals)]]))
        self.bounds = np.vstack(rows)
        effort = np.asarray(robot.effort_limits, dtype=float)
        self._torque = (config.weights[0] > 0 and effort.shape == (self.nq,) and np.all(effort > 0)
                        and (self.polynomial or (config.torque_stride > 0 and gravity_may_exceed(robot))))
        self._effort = effort

    @property
    def dimension(self) -> int:
        return len(self.bounds)

    # --- design vector <-> motion ---------------------------------------------------------------

    def goal_index(self, X) -> np.ndarray:
        """``(P,)`` goal picked by each individual."""
        X = np.atleast_2d(X)
        if self.n_goals == 1:
            return np.zeros(len(X), dtype=np.int64)
        return np.clip(np.floor(X[:, -1]).astype(np.int64), 0, self.n_goals - 1)

    def waypoints(self, X) -> np.ndarray:
        """``(P, K + 2, nq)``: start, the K via configurations, the chosen goal."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        P, K, nq = len(X), self.K, self.nq
        W = np.empty((P, K + 2, nq))
        W[:, 0] = self.q_start
        W[:, 1:K + 1] = X[:, :K * nq].reshape(P, K, nq)
        W[:, K + 1] = self.goals[self.goal_index(X)]
        return W

    def encode(self, via: np.ndarray, goal: int = 0) -> np.ndarray:
        """``(D,)`` design vector with via configurations ``(K, nq)`` and goal index ``goal``
        (polynomial: via velocities 0, segment times the rest-to-rest times of the segments)."""
        via = np.asarray(via, dtype=float).reshape(self.K, self.nq)
        parts = [via.ravel()]
        if self.polynomial:
            W = np.vstack([self.q_start, via, self.goals[goal]])
            T = rest_to_rest_time(np.diff(W, axis=0), self.robot.velocity_limits,
                                  self.robot.acceleration_limits).max(axis=1) * 1.5
            parts += [np.zeros(self.K * self.nq), np.clip(T, *TIME_BOUNDS)]
        if self.n_goals > 1:
            parts.append([goal + 0.5])
        return np.clip(np.concatenate(parts), self.bounds[:, 0], self.bounds[:, 1])

    def samples(self, X) -> dict:
        """The sampled motion of every individual: ``Q (P, M, nq)`` (what is certified and
        returned), and for the polynomial ``t (P, M)``, ``qd``, ``qdd`` and the limit excess."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        W = self.waypoints(X)
        P, K, nq, S = len(X), self.K, self.nq, self.S
        if not self.polynomial:
            u = np.arange(S) / S
            D = np.diff(W, axis=1)  # (P, K + 1, nq)
            Q = W[:, :-1, None, :] + u[None, None, :, None] * D[:, :, None, :]
            Q = np.concatenate([Q.reshape(P, (K + 1) * S, nq), W[:, -1:]], axis=1)
            return {"Q": Q, "W": W}
        from drake_mh.trajectories.viapoint import evaluate, segment_coefficients

        k = K * nq
        qv, vv, T = W[:, 1:K + 1], X[:, k:2 * k].reshape(P, K, nq), X[:, 2 * k:2 * k + K + 1]
        coeffs = segment_coefficients(self.q_start, qv, vv, W[:, -1], T)
        t, q, qd, qdd = evaluate(coeffs, T, S + 1)  # S + 1 per segment, ends included (doubled)
        keep = np.r_[np.ones(S + 1, bool)[:-1], False]  # drop each segment's end: the next one starts there
        keep = np.tile(keep, K + 1)
        keep[-1] = True
        t, q, qd, qdd = t[:, keep], q[:, keep], qd[:, keep], qdd[:, keep]
        q[:, -1] = W[:, -1]  # the goal exactly (the quintic reaches it up to rounding)
        lower, upper = self.robot.lower, self.robot.upper
        excess = (np.maximum(q - upper, 0.0) + np.maximum(lower - q, 0.0)).sum(axis=(1, 2))
        return {"Q": np.clip(q, lower, upper), "W": W, "t": t, "qd": qd, "qdd": qdd, "T": T,
                "q_raw": q, "limit_excess": excess}

    def path(self, x) -> np.ndarray:
        """``(M, nq)`` waypoints of one individual: the via points (linear; zero-length
        segments dropped) or the polynomial's samples (polynomial)."""
        s = self.samples(x)
        if self.polynomial:
            Q = s["Q"][0]
        else:
            Q = s["W"][0]
        keep = np.r_[True, np.any(np.abs(np.diff(Q, axis=0)) > 0, axis=1)]
        keep[-1] = True
        Q = Q[keep]
        if len(Q) > 2 and not np.any(np.abs(Q[-1] - Q[-2]) > 0):
            Q = np.delete(Q, -2, axis=0)
        return Q

    # --- fitness --------------------------------------------------------------------------------

    def terms(self, X) -> dict[str, np.ndarray]:
        """Every term ``(P,)`` of the fitness of ``X (P, D)`` (module docstring)."""
        cfg = self.config
        s = self.samples(X)
        Q = s["Q"]
        P, M, nq = Q.shape
        flat = Q.reshape(-1, nq)
        dQ = np.diff(Q, axis=1)  # (P, M - 1, nq)
        step = np.sqrt(np.einsum("pkj,pkj->pk", dQ, dQ))  # (P, M - 1) joint-space interval lengths
        absd = np.abs(dQ)
        f_q = absd.sum(axis=(1, 2))
        p = self.robot.batch.positions(flat, self.frame).reshape(P, M, 3)
        dp = np.diff(p, axis=1)
        f_c = np.sqrt(np.einsum("pkx,pkx->pk", dp, dp)).sum(axis=1) / cfg.length_unit
        robot = self.robot
        if self.polynomial:
            t_T = s["T"].sum(axis=1)
        else:
            seg = np.abs(np.diff(s["W"], axis=1))  # (P, K + 1, nq)
            t_T = rest_to_rest_time(seg, robot.velocity_limits, robot.acceleration_limits).max(axis=2).sum(axis=1)
        f_ot = np.zeros(P)
        if self._torque:
            from drake_mh.trajectories.dynamics import batch_dynamics

            dyn = batch_dynamics(robot)
            if self.polynomial:
                tau = dyn.inverse_dynamics(s["q_raw"].reshape(-1, nq), s["qd"].reshape(-1, nq),
                                           s["qdd"].reshape(-1, nq)).reshape(P, M, nq)
                excess = np.maximum(np.abs(tau) - self._effort, 0.0).sum(axis=2)
                f_ot = np.trapezoid(excess, s["t"], axis=1)
            else:
                stride = cfg.torque_stride
                Qs = Q[:, ::stride]
                zero = np.zeros((Qs.shape[0] * Qs.shape[1], nq))
                g = dyn.inverse_dynamics(Qs.reshape(-1, nq), zero, zero).reshape(P, -1, nq)
                excess = np.maximum(np.abs(g) - self._effort, 0.0).sum(axis=2)  # (P, ceil(M / stride))
                weight = np.add.reduceat(np.r_[step.T, np.zeros((1, P))], np.arange(0, M, stride), axis=0).T
                f_ot = (excess * weight[:, :excess.shape[1]]).sum(axis=1)
        b = cfg.weights
        f_f = b[0] * f_ot + b[1] * f_q + b[2] * f_c + b[3] * t_T
        penalty = np.zeros(P)
        min_bound = np.full(P, np.inf)
        if self._check_collisions:
            QT = np.ascontiguousarray(flat.T)
            V = self._model.clearances(QT, self._obstacles, per_obstacle=False,
                                       fine_below=self._fine_below).reshape(P, M, -1)
            lam = absd @ self._reach_T  # (P, M - 1, C)
            low = 0.5 * (V[:, 1:] + V[:, :-1] - lam)
            short = np.maximum(self._required - low, 0.0).sum(axis=2)  # (P, M - 1)
            penalty = ((step + 1e-3) * short).sum(axis=1)
            min_bound = (low - (self._required - cfg.margin)).min(axis=(1, 2))
        if self.polynomial:
            penalty = penalty + s["limit_excess"]
        f_ob = 1.0 / (1.0 + cfg.kappa * penalty)
        return {"f_ot": f_ot, "f_q": f_q, "f_c": f_c, "t_T": t_T, "f_f": f_f, "penalty": penalty,
                "f_ob": f_ob, "fitness": f_f / f_ob, "min_bound": min_bound}

    def __call__(self, X) -> np.ndarray:
        """The objective ``f(X (P, D)) -> (P,)``."""
        return self.terms(X)["fitness"]
