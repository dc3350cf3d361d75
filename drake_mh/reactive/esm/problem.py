"""One ESM control step: feasible set (eqs. (6)-(9), (11)) and vectorized objective (eq. (10)).

:func:`build_step` turns the state at ``t - Δt`` (joint angles ``θ_prev``, obstacles with
their velocities, Drake's exact closest points) into an :class:`ESMStep`:

* the box of eq. (11): ``max(θ⁻, θ_prev - q̇_max Δt) <= θ <= min(θ⁺, θ_prev + q̇_max Δt)``;
* one obstacle inequality (eq. (9)) per (movable link, obstacle) pair, written in θ as
  ``A θ <= c`` with ``A_k = δ_k = -u_kᵀ J_M,k``, ``c_k = (Y V_k - V0_k) Δt + δ_k θ_prev``.

Critical points (eqs. (4)-(5)). ``Scene.distances`` (Drake's exact signed distance, where the
paper used FCL) gives the closest points of every collision geometry of every link to every
obstacle. Every such pair gives a row, not only the global argmin of eq. (5): a Panda link is
a union of convex capsules (eq. (4)'s ``conv(L_l)`` per piece), and the paper notes that the
critical point jumping between links lets the distance enter the threshold; measured here,
one row per link (its closest capsule only) let another capsule of the same link cross the
threshold by 6 mm in one step. Rows far from the obstacle are inactive (``V`` saturates at
1/2), so extra rows cost little. ``u`` is Drake's unit normal from the obstacle towards the
link (``(M - N)/||M - N||`` when apart, still defined in penetration).

Jacobian of M (eq. (8)): column j = ``ζ_j × (M - o_j)`` for the revolute joints j between the
world and M's link, with axes ``ζ_j`` and origins ``o_j`` from ``Robot.batch.moving_frames``
(compiled from the plant); :mod:`drake_mh.reactive.esm.verify` checks it against Drake.

Constraint handling (how a member violating the inequality is treated):

* ``"reject"`` (eq. (19)): a candidate that violates eq. (9) (or the box) gets ``F = +inf``.
  With a greedy algorithm (AMNN/ARO) this is exactly eq. (19)-(20): the agent keeps
  ``θ_i(l)``. Infeasible points are never returned.
* ``"repair"``: the candidate is evaluated at ``repair(x)``, its projection by cyclic
  projections onto the half-spaces and the box (:func:`drake_mh.reactive.esm.kernels.repair`);
  the optimizer keeps ``x`` (Baldwinian repair) and the step returns ``repair(best x)``.
  A candidate that cannot be repaired (empty feasible set) gets ``+inf``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import InvalidArgument, InvalidConfiguration
from drake_mh.reactive.esm import kernels
from drake_mh.reactive.esm.config import CONSTRAINT_HANDLINGS, ESMConfig


@dataclass(frozen=True)
class ObstacleRow:
    """One obstacle inequality (eq. (9)) ``δ (θ - θ_prev) / Δt <= rhs``.

    Attributes:
        link: robot link carrying the critical point M.
        obstacle: obstacle name (N lies on it).
        distance: exact signed distance ``||M - N||`` [m] at ``θ_prev``.
        p_WM: critical point on the link, in W [m] ``(3,)``.
        p_WN: critical point on the obstacle, in W [m] ``(3,)``.
        u_W: unit vector from N towards M ``(3,)``.
        v_WN: obstacle velocity ``Ṅ`` [m/s] ``(3,)``.
        delta: ``δ = -uᵀ J_M`` ``(nq,)`` [m/rad].
        V: ``(1/(1 + exp(-|D|)) - 1/2) sgn(D)`` with ``D = distance - d - buffer`` (eq. (9)).
        V0: ``uᵀ Ṅ`` [m/s] (eq. (9)).
        rhs: right-hand side ``Y V - V0`` [m/s], ``Y V`` limited by the safeguard.
    """

    link: str
    obstacle: str
    distance: float
    p_WM: np.ndarray
    p_WN: np.ndarray
    u_W: np.ndarray
    v_WN: np.ndarray
    delta: np.ndarray
    V: float
    V0: float
    rhs: float


@dataclass(frozen=True)
class ESMStep:
    """Feasible set and objective data of one control step.

    Attributes:
        theta_prev: ``θ(t - Δt)`` ``(nq,)`` [rad].
        r_d: target position ``(3,)`` [m].
        lower, upper: the box of eq. (11) ``(nq,)`` [rad].
        A, c: obstacle inequalities in θ, ``A θ <= c``, ``A (K, nq)``, ``c (K,)`` [m].
        rows: the :class:`ObstacleRow` behind each row of ``A``.
        fixed_rows: pairs on links no joint moves (dropped; their distance is still reported).
        config: the :class:`ESMConfig`.
        relaxed_rows: rows no configuration in the box satisfies (e.g. the obstacle pressing
            on a link that can only spin about its symmetry axis); their bound is relaxed to
            ``min_box δθ + ρ (max_box δθ - min_box δθ)``, ρ = ``config.unsatisfiable_relax``:
            retreat along ``u`` nearly as fast as the velocity box allows.
    """

    theta_prev: np.ndarray
    r_d: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    A: np.ndarray
    c: np.ndarray
    rows: tuple[ObstacleRow, ...]
    fixed_rows: tuple[ObstacleRow, ...]
    config: ESMConfig = field(default_factory=ESMConfig)
    relaxed_rows: tuple[ObstacleRow, ...] = ()

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` for :func:`drake_mh.optim.minimize`."""
        return self.lower, self.upper

    def feasible(self, X) -> np.ndarray:
        """``(P,)`` bool: rows of ``X (P, nq)`` inside the box and satisfying eq. (9)."""
        X = np.ascontiguousarray(X, dtype=float).reshape(-1, self.lower.size)
        out = np.empty(len(X), dtype=np.bool_)
        kernels.feasible(X, self.A, self.c, self.lower, self.upper, self.config.feasibility_tol, out)
        return out

    def violation(self, X) -> np.ndarray:
        """``(P,)`` largest violation of eq. (9) in velocity units ``δ θ̇ - rhs`` [m/s] (<= 0: ok)."""
        X = np.asarray(X, dtype=float).reshape(-1, self.lower.size)
        if not len(self.c):
            return np.full(len(X), -np.inf)
        return ((X @ self.A.T - self.c) / self.config.dt).max(axis=1)

    def repair(self, X) -> tuple[np.ndarray, np.ndarray]:
        """Projects rows of ``X`` onto the feasible set; returns ``(X_repaired, feasible)``."""
        Xr = np.array(X, dtype=float, ndmin=2, copy=True, order="C")
        ok = np.empty(len(Xr), dtype=np.bool_)
        cfg = self.config
        kernels.repair(Xr, self.A, self.c, self.lower, self.upper, cfg.repair_sweeps,
                           cfg.feasibility_tol, ok)
        return Xr, ok


def _sigmoid_term(D: float) -> float:
    """``V = (1/(1 + exp(-|D|)) - 1/2) sgn(D)`` of eq. (9)."""
    return float((1.0 / (1.0 + np.exp(-abs(D))) - 0.5) * np.sign(D))


def point_jacobian(robot, theta, link: str, p_WM, frames=None) -> np.ndarray:
    """Translational Jacobian ``J_M (3, nq)`` of a point M fixed on ``link`` (eq. (8)).

    Column j is ``ζ_j × (M - o_j)`` (revolute) or ``ζ_j`` (prismatic) for the joints between
    the world and the link; joint axes ``ζ_j`` and origins ``o_j`` come from the batched
    kernel ``robot.batch.moving_frames`` (compiled from the Drake plant).

    Args:
        robot: the robot.
        theta: ``(nq,)`` [rad].
        link: the link carrying M.
        p_WM: ``(3,)`` [m].
        frames: ``robot.batch.moving_frames(theta[None])`` if already computed.
    """
    from drake_mh.kinematics import PRISMATIC

    chain = robot.batch.chain
    R, o = robot.batch.moving_frames(np.asarray(theta, dtype=float)[None]) if frames is None else frames
    anchor = chain.body_anchor[link][0]
    J = np.zeros((3, robot.nq))
    if anchor < 0:
        return J
    p = np.asarray(p_WM, dtype=float)
    k = np.flatnonzero(chain.ancestors[anchor])
    z = R[0, k, :, 2]                                               # (m, 3) joint axes in W
    cols = np.where((chain.kind[k] == PRISMATIC)[:, None], z, np.cross(z, p - o[0, k]))
    J[:, chain.qidx[k]] = cols.T
    return J


def build_step(robot, scene, theta_prev, r_d, config: ESMConfig | None = None, pairs=None) -> ESMStep:
    """Builds the feasible set of one control step at ``θ_prev`` (eqs. (6)-(9), (11)).

    Args:
        robot: the :class:`drake_mh.robot.Robot`.
        scene: :class:`drake_mh.scene.Scene` with the obstacles at time ``t - Δt`` (their
            ``velocity_W`` is ``Ṅ``).
        theta_prev: ``θ(t - Δt)`` ``(nq,)`` [rad], within the joint limits.
        r_d: target position ``(3,)`` [m] at time t.
        config: :class:`ESMConfig` (default: the paper's values).
        pairs: ``scene.distances(theta_prev)`` if already computed.

    Returns:
        The :class:`ESMStep`.

    Raises:
        InvalidConfiguration: ``θ_prev`` outside the joint limits, bad shapes.
    """
    cfg = ESMConfig() if config is None else config
    theta_prev = robot.check_q(theta_prev, "theta_prev")
    r_d = np.asarray(r_d, dtype=float).reshape(-1)
    if r_d.shape != (3,) or not np.all(np.isfinite(r_d)):
        raise InvalidArgument(f"r_d must be a finite 3-vector [m]; got {r_d!r}")
    if not robot.within_limits(theta_prev, tol=1e-9):
        raise InvalidConfiguration(
            "theta_prev lies outside the joint limits; eq. (11) needs a feasible previous "
            "configuration: start from a configuration within robot.lower/robot.upper", "theta_prev")
    step_max = cfg.velocity_scale * robot.velocity_limits * cfg.dt
    lower = np.maximum(robot.lower, theta_prev - step_max)
    upper = np.minimum(robot.upper, theta_prev + step_max)
    # a configuration exactly on a limit would give an empty box for the optimizers' lower < upper
    upper = np.maximum(upper, lower + 1e-12)

    if pairs is None:
        pairs = scene.distances(theta_prev)
    closest = [pair for pair in pairs if not pair.is_self]
    rows, fixed = [], []
    obstacles = scene.obstacles
    frames = robot.batch.moving_frames(theta_prev[None]) if closest else None
    d_constraint = cfg.threshold + cfg.buffer
    for pair in closest:
        link, other = pair.link, pair.other
        v_WN = np.asarray(obstacles[other].velocity_W, dtype=float)
        u = np.asarray(pair.nhat_W, dtype=float)
        J_M = point_jacobian(robot, theta_prev, link, pair.p_W_link, frames)
        delta = -u @ J_M
        D = pair.distance - d_constraint
        V = _sigmoid_term(D)
        YV = cfg.Y * V
        if cfg.step_fraction is not None:
            YV = float(np.sign(D) * min(abs(YV), cfg.step_fraction * abs(D) / cfg.dt))
        V0 = float(u @ v_WN)
        row = ObstacleRow(link, other, pair.distance, np.asarray(pair.p_W_link), np.asarray(pair.p_W_other),
                          u, v_WN, delta, V, V0, YV - V0)
        (rows if np.linalg.norm(delta) > cfg.fixed_link_tol else fixed).append(row)
    relaxed = []
    if rows:
        A = np.ascontiguousarray([r.delta for r in rows])
        c = np.array([r.rhs * cfg.dt for r in rows]) + A @ theta_prev
        # a row that no θ in the box satisfies is relaxed to "retreat nearly as fast as the box allows"
        low = np.minimum(A * lower, A * upper).sum(axis=1)     # min over the box of A_k θ
        high = np.maximum(A * lower, A * upper).sum(axis=1)
        bad = c < low + cfg.feasibility_tol
        c[bad] = low[bad] + cfg.unsatisfiable_relax * (high[bad] - low[bad])
        relaxed = [rows[i] for i in np.flatnonzero(bad)]
    else:
        A = np.zeros((0, robot.nq))
        c = np.zeros(0)
    return ESMStep(theta_prev, r_d, lower, upper, A, c, tuple(rows), tuple(fixed), cfg, tuple(relaxed))


class ESMObjective:
    """Vectorized ESM objective ``F(X (P, nq)) -> (P,)`` of one step, with constraint handling.

    One ``robot.batch.fk_jacobian`` call and one compiled kernel per population.

    Args:
        robot: the robot (its end-effector frame is the tracked point).
        step: the :class:`ESMStep`.
        handling: ``"reject"`` or ``"repair"`` (module docstring).
    """

    def __init__(self, robot, step: ESMStep, handling: str = "reject"):
        if handling not in CONSTRAINT_HANDLINGS:
            raise InvalidArgument(f"constraint handling must be one of {CONSTRAINT_HANDLINGS}; got {handling!r}")
        self.robot = robot
        self.step = step
        self.handling = handling
        self.nfe = 0

    def values(self, X) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unconstrained ``(F, e, μ)`` of each row of ``X`` (no feasibility test)."""
        T, J = self.robot.batch.fk_jacobian(X)
        n = len(T)
        F, e, mu = np.empty(n), np.empty(n), np.empty(n)
        cfg = self.step.config
        kernels.esm_values(T, J, self.step.r_d, float(cfg.h1), float(cfg.h2), F, e, mu)
        return F, e, mu

    def __call__(self, X: np.ndarray) -> np.ndarray:
        if self.handling == "repair":
            X, ok = self.step.repair(X)
        else:
            ok = self.step.feasible(X)
        F = self.values(X)[0]
        F[~ok] = np.inf
        self.nfe += len(F)
        return F

    def resolve(self, x) -> np.ndarray:
        """The configuration a candidate stands for: ``repair(x)`` under ``"repair"``, else ``x``."""
        x = np.asarray(x, dtype=float)
        return self.step.repair(x)[0][0] if self.handling == "repair" else x.copy()
