"""Via-point polynomial trajectories and their fitness (the ABC paper, Savsani & Jhala).

Trajectory (ABC paper §III, eqs. 4-17, after Kazem et al. 2008): the motion from the start
``θ_0`` through ``mp`` via points to the goal ``θ_g`` is ``mp + 1`` polynomial segments in the
segment-local time ``t ∈ [0, T_i]``:

* segments ``i = 0 .. mp-1``: 4th order, eq. (4), with ``θ(0) = θ_i``, ``θ'(0) = θ'_i``,
  ``θ''(0) = θ''_i`` (eqs. 5, 7, 9) and ``θ(T_i) = θ_{i+1}``, ``θ'(T_i) = θ'_{i+1}`` (eqs. 6, 8);
  the acceleration reached at the via point, eq. (10), starts the next segment, so the
  acceleration is continuous at every via point;
* the last segment: 5th order, eq. (11), from the last via point's position, velocity and
  acceleration to ``θ_g`` at rest, ``θ'(T) = θ''(T) = 0`` (eqs. 12-17).

The motion starts at rest (``θ'_0 = θ''_0 = 0``). Solving the end conditions in closed form
(``Δ``: position still to go, ``Δv``, ``Δa``: velocity / acceleration still to change):

    quartic:  a3 = (4Δ - Δv T) / T³,  a4 = (Δv T - 3Δ) / T⁴
    quintic:  b3 = (20Δ - 8Δv T + Δa T²) / (2T³),  b4 = (-30Δ + 14Δv T - 2Δa T²) / (2T⁴),
              b5 = (12Δ - 6Δv T + Δa T²) / (2T⁵)

Design vector (the paper's §III end and eqs. 21-24): via joint angles ``(mp, n)``, via joint
velocities ``(mp, n)``, segment times ``(mp + 1,)``; the final redundant posture (``n - m``
parameters) is absent for the 2R arm, whose goal at full reach has one IK solution
(docs/robots.md).

Fitness, eq. (18): ``f_f = β1 f_ot + β2 f_q + β3 f_c + β4 t_T`` with ``β = [1, 2, 2, 1]``, and
``f = f_f / f_ob`` with obstacles (eq. 20). The paper takes ``f_ot`` and ``f_ob`` from a
reference we do not have; our definitions (:class:`ViaPointFitness`):

* ``f_ot = Σ_j ∫ max(0, |τ_j(t)| - τ_max,j) dt`` [N·m·s], torque excess over the limit
  integrated in time (trapezoid on the samples), torques from the plant-compiled RNEA with
  gravity (:class:`~drake_mh.trajectories.dynamics.BatchDynamics`);
* ``f_q = Σ_j ∫ |θ'_j| dt`` [rad], the total joint travel (as the total variation of the
  samples, ``Σ_j Σ_k |Δθ_j|``: exact wherever a joint does not turn back between samples);
* ``f_c``: length of the end-effector path (polyline through the samples) in ``length_unit``
  (default 0.3048 m = 1 ft, see :class:`ViaPointFitness`);
* ``t_T = Σ_i T_i`` [s];
* ``f_ob = 1 / (1 + κ Π)`` with ``Π = Σ_k Δt_k max(0, d_safe - d_k)`` [m·s]: ``d_k`` is a
  lower bound of the arm-obstacle clearance over the sample interval k,
  ``min(d(t_k), d(t_k+1)) - ½ Σ_j r_j |q_j(t_k+1) - q_j(t_k)|`` (a point of the arm moves at
  most ``Σ r_j |Δq_j|`` between samples, ``r_j`` the arm's reach from joint j), with ``d`` from
  the robot's sphere model (never more than the exact distance). ``f_ob = 1`` for a
  collision-free motion, so ``f = f_f`` there and the free and obstacle fitnesses compare term
  by term; a fast swing through an obstacle between two samples is still penalized.

The fitness only penalizes; :meth:`ViaPointProblem.certify_motion` *certifies* a result's whole
motion (every instant, not samples): the polynomials are replaced by chords between dense
samples, each chord certified by :meth:`drake_mh.scene.Scene.certify_path` with the clearance
raised by how far the arm can be from the chord's configuration (``h²/8 · max|θ''|`` per joint
over the chord's interval, exact Taylor bound of the cubic ``θ''``, times each link's reach per
joint from the plant).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import PPoly

from drake_mh.errors import InvalidArgument

__all__ = ["segment_coefficients", "viapoint_trajectory", "ViaPointFitness", "ViaPointProblem"]


def segment_coefficients(q0, qv, vv, qg, T) -> list[np.ndarray]:
    """Polynomial coefficients of every segment, vectorized over a population.

    Args:
        q0: ``(n,)`` start joint angles [rad] (at rest).
        qv: ``(P, mp, n)`` via joint angles [rad].
        vv: ``(P, mp, n)`` via joint velocities [rad/s].
        qg: ``(n,)`` or ``(P, n)`` goal joint angles [rad] (reached at rest).
        T: ``(P, mp + 1)`` segment durations [s], > 0.

    Returns:
        ``mp + 1`` arrays; segment i's is ``(P, deg + 1, n)`` with the coefficient of ``t^k``
        at index k (lowest power first): degree 4 for the via segments, 5 for the last.
    """
    qv, vv, T = np.asarray(qv, float), np.asarray(vv, float), np.asarray(T, float)
    P, mp, n = qv.shape
    qg = np.broadcast_to(np.asarray(qg, float), (P, n))
    pos = np.broadcast_to(np.asarray(q0, float), (P, n))
    vel = np.zeros((P, n))
    acc = np.zeros((P, n))
    out = []
    for i in range(mp):
        h = T[:, i:i + 1]
        dq = qv[:, i] - pos - vel * h - 0.5 * acc * h ** 2
        dv = vv[:, i] - vel - acc * h
        a3 = (4.0 * dq - dv * h) / h ** 3
        a4 = (dv * h - 3.0 * dq) / h ** 4
        out.append(np.stack([pos, vel, 0.5 * acc, a3, a4], axis=1))
        pos, vel = qv[:, i], vv[:, i]
        acc = acc + 6.0 * a3 * h + 12.0 * a4 * h ** 2  # eq. (10): 2 a2 + 6 a3 T + 12 a4 T²
    h = T[:, mp:mp + 1]
    dq = qg - pos - vel * h - 0.5 * acc * h ** 2
    dv = -vel - acc * h
    da = -acc
    b3 = (20.0 * dq - 8.0 * dv * h + da * h ** 2) / (2.0 * h ** 3)
    b4 = (-30.0 * dq + 14.0 * dv * h - 2.0 * da * h ** 2) / (2.0 * h ** 4)
    b5 = (12.0 * dq - 6.0 * dv * h + da * h ** 2) / (2.0 * h ** 5)
    out.append(np.stack([pos, vel, 0.5 * acc, b3, b4, b5], axis=1))
    return out


def viapoint_trajectory(q0, qv, vv, qg, T, joint_names=()):
    """One via-point trajectory as a :class:`~drake_mh.trajectories.trajectory.Trajectory`.

    Args:
        q0, qg: ``(n,)`` start and goal [rad]; qv, vv: ``(mp, n)`` via angles / velocities;
        T: ``(mp + 1,)`` segment durations [s].
    """
    from drake_mh.trajectories.trajectory import Trajectory

    coeffs = segment_coefficients(q0, np.asarray(qv, float)[None], np.asarray(vv, float)[None],
                                  qg, np.asarray(T, float)[None])
    n = len(np.asarray(q0))
    c = np.zeros((6, len(coeffs), n))  # PPoly: highest power first
    for i, seg in enumerate(coeffs):
        k = seg.shape[1]
        c[6 - k:, i] = seg[0][::-1]
    breaks = np.r_[0.0, np.cumsum(np.asarray(T, float))]
    return Trajectory(PPoly(c, breaks), None, tuple(joint_names), "viapoint", {})


def evaluate(coeffs, T, K: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sample every individual's trajectory at ``K`` uniform times in each segment (ends included).

    Per-segment sampling keeps short segments as finely resolved as long ones (a uniform grid
    over the whole motion let an optimizer hide a 0.1 s swing through an obstacle between two
    samples). Segment ends appear twice (zero-width intervals, harmless for the integrals).

    Returns:
        ``t (P, S K)`` [s], ``q, qd, qdd (P, S K, n)``, ``S = mp + 1`` segments.
    """
    starts = np.concatenate([np.zeros((T.shape[0], 1)), np.cumsum(T, axis=1)[:, :-1]], axis=1)
    u = np.linspace(0.0, 1.0, K)
    ts, qs, qds, qdds = [], [], [], []
    for i, c in enumerate(coeffs):
        tl = (T[:, i:i + 1] * u[None, :])[:, :, None]  # (P, K, 1) local time
        v0 = v1 = v2 = 0.0
        for k in range(c.shape[1] - 1, -1, -1):  # Horner on the value and its derivatives
            v2 = v2 * tl + 2.0 * v1
            v1 = v1 * tl + v0
            v0 = v0 * tl + c[:, None, k, :]
        ts.append(starts[:, i:i + 1] + tl[:, :, 0])
        qs.append(v0), qds.append(v1), qdds.append(v2)
    return (np.concatenate(ts, axis=1), np.concatenate(qs, axis=1), np.concatenate(qds, axis=1),
            np.concatenate(qdds, axis=1))


@dataclass(frozen=True)
class ViaPointFitness:
    """Weights and definitions of the ABC paper's fitness, eqs. (18) and (20).

    Attributes:
        weights: ``(β1, β2, β3, β4)`` for ``f_ot, f_q, f_c, t_T``; the paper's ``[1, 2, 2, 1]``.
        samples: time samples per segment for the integrals (uniform in each segment).
        length_unit: unit of ``f_c`` [m]. Default 1 ft: the paper's Table 1 lengths are in the
            units of its 1-ft links (its Cartesian length 3.1403 ≈ π is a quarter circle of
            radius 2 links), so ``f_c`` keeps the paper's weight against ``f_q`` and ``t_T``.
        kappa: obstacle penalty gain κ [1/(m·s)] in ``f_ob = 1 / (1 + κ Π)``.
        clearance: ``d_safe`` [m], the clearance below which the penalty starts.
    """

    weights: tuple[float, float, float, float] = (1.0, 2.0, 2.0, 1.0)
    samples: int = 64
    length_unit: float = 0.3048
    kappa: float = 1e4
    clearance: float = 0.0


@dataclass(frozen=True)
class ViaPointProblem:
    """The ABC paper's trajectory problem as a vectorized objective for :func:`drake_mh.minimize`.

    Attributes:
        robot: the robot (``planar2r`` in the paper).
        q_start, q_goal: ``(n,)`` start and goal [rad] (at rest); copied.
        n_via: number of via points ``mp`` (1 in the paper).
        angle_bounds: via joint-angle range [rad] (eq. 21: ±π).
        velocity_bounds: via joint-velocity range [rad/s] (eq. 22: ±π/4).
        time_bounds: segment-time range [s] (eq. 23: [0.1, 8]).
        obstacles: ``((centre_W (3,), radius), ...)`` spheres [m]; for the planar arm a sphere
            centred in the plane of motion is the paper's circle.
        fitness: :class:`ViaPointFitness`.
    """

    robot: object
    q_start: tuple
    q_goal: tuple
    n_via: int = 1
    angle_bounds: tuple[float, float] = (-np.pi, np.pi)
    velocity_bounds: tuple[float, float] = (-np.pi / 4, np.pi / 4)
    time_bounds: tuple[float, float] = (0.1, 8.0)
    obstacles: tuple = ()
    fitness: ViaPointFitness = field(default_factory=ViaPointFitness)

    def __post_init__(self):
        n = self.robot.nq
        for name in ("q_start", "q_goal"):
            try:  # numpy raises ValueError on ragged nested lists; a complex value would lose its imaginary part
                v = None if np.iscomplexobj(getattr(self, name)) else np.array(getattr(self, name), dtype=float)
            except (TypeError, ValueError):
                v = None
            if v is None or v.shape != (n,) or not np.all(np.isfinite(v)):
                raise InvalidArgument(f"{name} must be {n} finite joint angles, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)  # a copy: the caller's array may change later
        if int(self.n_via) < 1:
            raise InvalidArgument(f"n_via must be >= 1, got {self.n_via}")
        if self.time_bounds[0] <= 0:
            raise InvalidArgument(f"segment times must be positive: time_bounds {self.time_bounds}")

    # --- design vector -------------------------------------------------------------------------

    @property
    def dimension(self) -> int:
        """``2 mp n + mp + 1``: 6 for the paper's 2R arm with one via point."""
        return 2 * self.n_via * self.robot.nq + self.n_via + 1

    @property
    def bounds(self) -> np.ndarray:
        """``(D, 2)`` box of eqs. (21)-(23) in design-vector order."""
        k = self.n_via * self.robot.nq
        rows = [self.angle_bounds] * k + [self.velocity_bounds] * k + [self.time_bounds] * (self.n_via + 1)
        return np.array(rows, dtype=float)

    def decode(self, X) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(P, D)`` design vectors -> via angles ``(P, mp, n)``, velocities ``(P, mp, n)``, times ``(P, mp+1)``."""
        X = np.atleast_2d(np.asarray(X, float))
        mp, n = self.n_via, self.robot.nq
        k = mp * n
        return X[:, :k].reshape(-1, mp, n), X[:, k:2 * k].reshape(-1, mp, n), X[:, 2 * k:]

    # --- fitness --------------------------------------------------------------------------------

    def terms(self, X) -> dict[str, np.ndarray]:
        """Every fitness term ``(P,)`` for a population ``X (P, D)`` (see the module docstring)."""
        from drake_mh.trajectories.dynamics import batch_dynamics

        qv, vv, T = self.decode(X)
        P = T.shape[0]
        cfg = self.fitness
        coeffs = segment_coefficients(self.q_start, qv, vv, self.q_goal, T)
        t, q, qd, qdd = evaluate(coeffs, T, cfg.samples)
        n = self.robot.nq
        Q = q.reshape(-1, n)
        tau = batch_dynamics(self.robot).inverse_dynamics(Q, qd.reshape(-1, n), qdd.reshape(-1, n))
        tau = tau.reshape(P, -1, n)
        excess = np.maximum(np.abs(tau) - self.robot.effort_limits, 0.0).sum(axis=2)
        f_ot = np.trapezoid(excess, t, axis=1)
        f_q = np.abs(np.diff(q, axis=1)).sum(axis=(1, 2))  # Σ_j Σ_k |Δq_j| -> ∫ |θ'_j| dt
        p = self.robot.batch.fk(Q)[:, :3, 3].reshape(P, -1, 3)
        dp = np.diff(p, axis=1)
        f_c = np.sqrt(np.einsum("pkx,pkx->pk", dp, dp)).sum(axis=1) / cfg.length_unit
        t_T = T.sum(axis=1)
        b = cfg.weights
        f_f = b[0] * f_ot + b[1] * f_q + b[2] * f_c + b[3] * t_T
        out = {"f_ot": f_ot, "f_q": f_q, "f_c": f_c, "t_T": t_T, "f_f": f_f,
               "max_torque_ratio": np.max(np.abs(tau) / self.robot.effort_limits, axis=(1, 2))}
        if self.obstacles:
            d = self._clearance(Q).reshape(P, -1)
            swept = 0.5 * (np.abs(np.diff(q, axis=1)) * self._reach).sum(axis=2)  # (P, M-1)
            d_int = np.minimum(d[:, 1:], d[:, :-1]) - swept
            penetration = (np.diff(t, axis=1) * np.maximum(cfg.clearance - d_int, 0.0)).sum(axis=1)
            out["f_ob"] = 1.0 / (1.0 + cfg.kappa * penetration)
            out["min_clearance"] = d.min(axis=1)
            out["fitness"] = f_f / out["f_ob"]
        else:
            out["fitness"] = f_f
        return out

    def __call__(self, X) -> np.ndarray:
        """The objective ``f(X (P, D)) -> (P,)`` for :func:`drake_mh.minimize`."""
        return self.terms(X)["fitness"]

    @property
    def _scene(self):
        """Drake scene with the obstacles (exact checks), built once."""
        scene = self.__dict__.get("_scene_cache")
        if scene is None:
            from drake_mh.scene import Scene, Sphere

            scene = Scene(self.robot)
            for i, (centre, radius) in enumerate(self.obstacles):
                scene.add(f"obstacle{i}", Sphere(float(radius)), np.asarray(centre, float))
            object.__setattr__(self, "_scene_cache", scene)
        return scene

    def _clearance(self, Q) -> np.ndarray:
        """``(N,)`` sphere-model clearance to the spherical obstacles [m] (<= the exact distance,
        penetration depth included: :meth:`Scene.batch_min_distance`)."""
        return self._scene.batch_min_distance(Q)

    @property
    def _reach(self) -> np.ndarray:
        """``(n,)`` upper bound of the distance from joint j's origin to any point of the arm [m]."""
        reach = self.__dict__.get("_reach_cache")
        if reach is None:
            robot = self.robot
            Q = np.vstack([robot.home, robot.random_configurations(32, 0)])
            centres = self._scene.sphere_centres(Q)
            radii = self._scene.sphere_model.radii
            reach = np.zeros(robot.nq)
            for q, c in zip(Q, centres):
                robot.plant.SetPositions(robot.plant_context, q)
                for name in robot.joint_names:
                    joint = robot.plant.GetJointByName(name)
                    o = joint.frame_on_child().CalcPoseInWorld(robot.plant_context).translation()
                    j = joint.velocity_start()
                    reach[j] = max(reach[j], float(np.max(np.linalg.norm(c - o, axis=1) + radii)))
            object.__setattr__(self, "_reach_cache", reach)
        return reach

    def trajectory(self, x):
        """The :class:`~drake_mh.trajectories.trajectory.Trajectory` of one design vector ``x (D,)``."""
        qv, vv, T = self.decode(x)
        return viapoint_trajectory(self.q_start, qv[0], vv[0], self.q_goal, T[0], self.robot.joint_names)

    def certify_motion(self, x, clearance: float = 0.0, tolerance: float = 1e-3, max_margin: float = 1e-3,
                       samples: int = 16) -> dict:
        """Certify the whole motion of ``x (D,)`` collision-free (module docstring).

        Each polynomial segment is cut into chords at ``samples`` uniform times, doubled until
        the bound on the distance of the arm from the chords (``margin``) is at most
        ``max_margin`` [m]; the chords are certified with ``clearance + margin``, so the motion
        keeps ``clearance`` at every instant.

        Args:
            x: ``(D,)`` design vector.
            clearance: [m] required at every instant (default 0: collision-free).
            tolerance: [m] of the reported lower bound.
            max_margin: [m] largest accepted chord margin.
            samples: initial chords per polynomial segment.

        Returns:
            ``{"motion_certified": bool, "motion_min_clearance": certified lower bound [m] (NaN
            if not certified, inf without obstacles), "motion_failure_time": [s] where the first
            chord not certified starts (NaN if none), "motion_failure_reason": str,
            "motion_chords": int, "motion_margin": [m]}``.
        """
        if not self.obstacles:
            return {"motion_certified": True, "motion_min_clearance": float("inf"),
                    "motion_failure_time": float("nan"), "motion_failure_reason": "", "motion_chords": 0,
                    "motion_margin": 0.0}
        scene = self._scene
        pp = self.trajectory(x).path
        d2, d3, d4, d5 = (pp.derivative(k) for k in (2, 3, 4, 5))
        reach = scene.collision_model.reach[:scene.collision_model.num_links]   # (G, nq) [m/rad]
        breaks = pp.x
        k = int(samples)
        while True:
            t = np.unique(np.concatenate([np.linspace(a, b, k + 1) for a, b in zip(breaks[:-1], breaks[1:])]))
            h = np.diff(t)
            m = 0.5 * (t[:-1] + t[1:])
            r = 0.5 * h[:, None]
            # max |θ''| over each chord's interval: Taylor of the cubic θ'' about its middle, exact bound
            acc = np.abs(d2(m)) + r * np.abs(d3(m)) + r ** 2 / 2 * np.abs(d4(m)) + r ** 3 / 6 * np.abs(d5(m))
            deviation = (h[:, None] ** 2 / 8.0) * acc                          # (M, nq) [rad]
            margin = float(np.max(deviation @ reach.T))
            if margin <= max_margin or k >= 1 << 14:
                break
            k *= 2
        Q = pp(t)
        cert = scene.certify_path(Q, float(clearance) + margin, tolerance=tolerance)
        first = cert.first_failure
        return {"motion_certified": bool(cert.certified),
                "motion_min_clearance": float(cert.min_clearance - margin) if cert.certified else float("nan"),
                "motion_failure_time": float(t[first]) if first is not None else float("nan"),
                "motion_failure_reason": "" if first is None else
                f"chord at t = {t[first]:.4f} s: {cert.segments.reason(first)} (chord margin {margin:.2e} m)",
                "motion_chords": int(len(h)), "motion_margin": margin}

    def exact_min_distance(self, x, samples: int = 400) -> float:
        """Smallest exact (Drake) arm-obstacle distance [m] along the trajectory of ``x``."""
        if not self.obstacles:
            return np.inf
        _, Q = self.trajectory(x).sample_uniform(samples)
        return float(self._scene.exact_min_distance(Q).min())
