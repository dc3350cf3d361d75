"""The TOPP-RA solve of ``retime(method="toppra")``: its stage rows, and two solvers of them.

:func:`stage_rows` builds the problem toppra receives from our constraints: the velocity bound
on ``x = ṡ²`` at every gridpoint, and velocity, acceleration and torque rows ``a u + b x + c``
(``u = s̈``, constant on each gridpoint interval) at interior check points of every interval.
:func:`solve_sd` solves it, from rest to rest, with the compiled core's ``topp_ra`` (Pham & Pham,
"A new approach to time-optimal path parameterization based on reachability analysis", IEEE T-RO
2018: controllable sets backwards, the greedy largest ``s̈`` forwards, every stage's 2-variable LP
by Seidel's algorithm: the ``toppra`` package's ``TOPPRA`` with its ``seidel`` solver, ported to
C++, ``cpp/topp.hpp``) where the core is built, else with the ``toppra`` package itself (the
reference: ``backend="toppra"`` picks it anywhere).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from drake_mh._support.native import compiled_core
from drake_mh.errors import InvalidArgument
from drake_mh.trajectories.dynamics import batch_dynamics

__all__ = ["StageRows", "stage_rows", "solve_sd", "solve_spline", "BACKENDS"]

BACKENDS = ("auto", "compiled", "toppra")
"""``"compiled"``: the core's ``topp_ra``; ``"toppra"``: the package; ``"auto"``: the core where built."""

_X_CAP = 1e16
"""the velocity bound's cap on ``x = ṡ²`` where ``p'(s) = 0`` (toppra's ``INFTY``)."""
_LIMIT_CAP = 1e12
"""stand-in for an undeclared (infinite) limit in the rows (finite rows for the LPs)."""


class StageRows(NamedTuple):
    """Stage ``i``'s constraints in ``u = s̈`` on ``[s_i, s_{i+1}]`` and ``x_i = ṡ(s_i)²``.

    ``|a[i, k] u + b[i, k] x + c[i, k]| <= lims`` (elementwise, ``m`` quantities per check point
    ``k``) and ``x <= x_max[i]``.

    Attributes:
        gridpoints: ``(N+1,)`` path parameters ``s_i``, increasing.
        a, b, c: ``(N+1, F, m)`` row coefficients at the ``F`` check points of each interval.
        lims: ``(m,)`` bounds (squared velocity limits, acceleration and torque limits).
        x_max: ``(N+1,)`` bound on ``x_i`` from the velocity limits at the gridpoints, or None
            where velocity is not enforced.
    """

    gridpoints: np.ndarray
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    lims: np.ndarray
    x_max: np.ndarray | None

    def canonical(self):
        """The rows as the seidel solver stacks them: ``A u + B x + C <= 0``, each ``(N+1, F 2 m)``,
        per check point its ``+`` rows then its ``-`` rows (toppra's ``F = [I; -I]``, ``g = [lims;
        lims]``); and the bounds ``x_lo, x_hi (N+1,)`` (``±inf``: none)."""
        N1, F, m = self.a.shape
        A = np.concatenate([self.a, -self.a], axis=2).reshape(N1, 2 * F * m)
        B = np.concatenate([self.b, -self.b], axis=2).reshape(N1, 2 * F * m)
        C = np.concatenate([self.c - self.lims, -self.c - self.lims], axis=2).reshape(N1, 2 * F * m)
        if self.x_max is None:
            x_lo, x_hi = np.full(N1, -np.inf), np.full(N1, np.inf)
        else:
            x_lo, x_hi = np.zeros(N1), self.x_max
        return A, B, C, x_lo, x_hi


def stage_rows(robot, spline, gridpoints: np.ndarray, vmax, amax, tmax, fractions, *,
               velocity_bound: bool = True) -> StageRows:
    """Velocity, acceleration and torque rows at ``fractions`` of every gridpoint interval.

    toppra's interpolation discretization checks the second-order constraint
    ``a(s) u + b(s) x + c(s)`` at both ends of each interval, with ``x(s) = x_i + 2 u (s - s_i)``
    (constant ``s̈ = u``). The same linear rows in ``(u_i, x_i)`` hold at any ``σ`` inside:
    ``[a(σ) + 2 (σ - s_i) b(σ)] u_i + b(σ) x_i + c(σ)``. Checking at ``fractions`` of each
    interval shrinks what can be missed between check points (the certification and, if
    needed, a time scaling catch the rest). Velocity: ``a = 0``, ``b = p'²``, ``c = 0`` against
    ``v_max²``; acceleration: ``a = p'``, ``b = p''``, ``c = 0``; torque: ``a = M p'``,
    ``b = M p'' + C(p, p') p'``, ``c = g`` (gravity included). The last stage (``s_N``) has its
    own point only.

    The velocity bound at the gridpoints (``velocity_bound``) is toppra's ``JointVelocityConstraint``
    bound ``x_i <= min_j vmax_j² / p_j'(s_i)²`` (capped at 1e16).

    Args:
        robot: dynamics (torque rows).
        spline: the joint path ``p(s)`` (scipy ``PPoly``-like, ``spline(s, nu)``).
        gridpoints: ``(N+1,)`` increasing path parameters.
        vmax, amax, tmax: ``(nq,)`` velocity [rad/s], acceleration [rad/s²], torque [N·m] limits;
            a quantity gets rows where any of its limits is finite.
        fractions: ``(F,)`` check points in ``[0, 1]`` of every interval.
        velocity_bound: add the bound on ``x`` at the gridpoints.
    """
    vmax, amax, tmax = (np.asarray(x, dtype=float) for x in (vmax, amax, tmax))
    use_vel, use_acc, use_tau = (bool(np.any(np.isfinite(x))) for x in (vmax, amax, tmax))
    lims = np.minimum(np.r_[vmax ** 2 if use_vel else [], amax if use_acc else [],
                            tmax if use_tau else []], _LIMIT_CAP)
    phi = np.asarray(fractions, dtype=float)
    gp = np.asarray(gridpoints, dtype=float)
    N1, m = len(gp), len(lims)
    h = np.r_[np.diff(gp), 0.0]  # stage N: only its own point
    sig = gp[:, None] + phi[None, :] * h[:, None]  # (N+1, F)
    sig[:, phi == 0.0] = gp[:, None]
    sig[:-1, phi == 1.0] = gp[1:, None]  # an interval's end is the next gridpoint, exactly
    S, back = np.unique(sig, return_inverse=True)  # each point once (ends are shared by two stages)
    Ps, Pss = spline(S, nu=1), spline(S, nu=2)
    A, B, C = [], [], []
    if use_vel:
        A.append(np.zeros_like(Ps)), B.append(Ps ** 2), C.append(np.zeros_like(Ps))
    if use_acc:
        A.append(Ps), B.append(Pss), C.append(np.zeros_like(Ps))
    if use_tau:
        a, b, c = batch_dynamics(robot).path_coefficients(spline(S), Ps, Pss)
        A.append(a), B.append(b), C.append(c)
    A, B, C = ([x[back.ravel()] for x in X] for X in (A, B, C))  # per (stage, fraction) again
    if m:
        A, B, C = (np.hstack(x) for x in (A, B, C))  # (N1 F, m)
    else:
        A = B = C = np.zeros((N1 * len(phi), 0))
    off = (2.0 * (sig - gp[:, None])).ravel()[:, None]
    x_max = None
    if velocity_bound:
        ps = np.abs(spline(gp, nu=1))
        with np.errstate(divide="ignore"):
            x_max = np.minimum(np.min(np.where(ps > 0, vmax ** 2 / ps ** 2, np.inf), axis=1), _X_CAP)
    return StageRows(gp, (A + off * B).reshape(N1, len(phi), m), B.reshape(N1, len(phi), m),
                     C.reshape(N1, len(phi), m), lims, x_max)


def solve_sd(rows: StageRows, spline, backend: str = "auto") -> tuple[np.ndarray | None, str]:
    """Path speeds ``ṡ (N+1,)`` at the gridpoints, from rest to rest, time-optimal for ``rows``.

    Args:
        rows: the stage rows (:func:`stage_rows`).
        spline: the joint path (the ``toppra`` package wants it; the compiled solver does not).
        backend: one of :data:`BACKENDS`.

    Returns:
        ``(sd, solver)``: ``sd`` None where the rows admit no parameterization (an empty
        controllable set, a start that cannot be controlled, or a forward pass that fails after
        toppra's retries); ``solver`` ``"compiled"`` or ``"toppra"``, the one that answered.

    Raises:
        InvalidArgument: an unknown backend, or ``"compiled"`` where the core is not built.
    """
    if backend not in BACKENDS:
        raise InvalidArgument(f"backend must be one of {BACKENDS}, got {backend!r}")
    core = compiled_core() if backend != "toppra" else None
    if backend == "compiled" and core is None:
        raise InvalidArgument("backend='compiled' needs the compiled core (pip install -e .; and "
                              "DRAKE_MH_COMPILED_CORE not 0): use backend='toppra' or 'auto'")
    if core is not None:
        stage, xs, _, _ = core.topp_ra(rows.gridpoints, *rows.canonical())
        return (np.sqrt(xs) if stage < 0 else None), "compiled"
    sd = _package_sd(rows, spline)
    return (None if sd is None or np.isnan(sd).any() else sd), "toppra"


def solve_spline(robot, spline, gridpoints: np.ndarray, vmax, amax, tmax, fractions, *,
                 velocity_bound: bool = True, backend: str = "auto") -> tuple[np.ndarray | None, str]:
    """:func:`solve_sd` of :func:`stage_rows` (same arguments): with the compiled core (``"auto"``
    where it is built, ``"compiled"``) the rows are built and solved in one call
    (``spline_topp_ra``: the same rows, evaluated once per point, the torques by its inverse
    dynamics), else built here and solved by the ``toppra`` package. ``(sd, solver)`` as
    :func:`solve_sd`."""
    if backend not in BACKENDS:
        raise InvalidArgument(f"backend must be one of {BACKENDS}, got {backend!r}")
    core = compiled_core() if backend != "toppra" else None
    if core is None:
        rows = stage_rows(robot, spline, gridpoints, vmax, amax, tmax, fractions, velocity_bound=velocity_bound)
        return solve_sd(rows, spline, backend)
    tmax = np.asarray(tmax, dtype=float)
    ints, floats = batch_dynamics(robot).packed if np.any(np.isfinite(tmax)) else (None, None)
    arrays = (np.ascontiguousarray(x, dtype=float) for x in (spline.c, spline.x, gridpoints, vmax, amax, tmax, fractions))
    stage, xs = core.spline_topp_ra(*arrays, bool(velocity_bound), ints, floats)
    return (np.sqrt(xs) if stage < 0 else None), "compiled"


class _ToppraPath:
    """toppra's geometric-path interface over a scipy spline (``AbstractGeometricPath``)."""

    def __init__(self, spline):
        self.spline = spline
        self.dof = spline.c.shape[2]
        self.path_interval = np.array([spline.x[0], spline.x[-1]])
        self.waypoints = (spline.x, spline(spline.x))

    def __call__(self, s, order=0):
        return self.spline(s, nu=order)

    def eval(self, s):
        return self.spline(s)

    def evald(self, s):
        return self.spline(s, nu=1)

    def evaldd(self, s):
        return self.spline(s, nu=2)

    @property
    def duration(self):
        return self.path_interval[1] - self.path_interval[0]


def _package_sd(rows: StageRows, spline) -> np.ndarray | None:
    """The ``toppra`` package's ``TOPPRA`` (seidel solver) on ``rows``: one ``xbound`` constraint
    for the velocity bound, one constraint object per check point (toppra's seidel wrapper
    multiplies each object's ``F`` with its rows, and one object with every row made OpenBLAS go
    multi-threaded, many times slower on a loaded machine)."""
    import toppra.algorithm as algo
    from toppra.constraint import DiscretizationType, LinearConstraint

    N1, F, m = rows.a.shape

    class _Bound(LinearConstraint):
        def __init__(self):
            super().__init__()
            self.dof = spline.c.shape[2]

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            xbound = np.column_stack([np.zeros(N1), rows.x_max])
            return None, None, None, None, None, None, xbound

    class _Rows(LinearConstraint):
        def __init__(self, k):
            super().__init__()
            self.k = k
            self.dof = spline.c.shape[2]
            self.identical = True
            self.discretization_type = DiscretizationType.Interpolation

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            F_k = np.vstack([np.eye(m), -np.eye(m)])
            return (rows.a[:, self.k], rows.b[:, self.k], rows.c[:, self.k], F_k,
                    np.r_[rows.lims, rows.lims], None, None)

    cons = ([_Bound()] if rows.x_max is not None else []) + ([_Rows(k) for k in range(F)] if m else [])
    instance = algo.TOPPRA(cons, _ToppraPath(spline), gridpoints=rows.gridpoints, solver_wrapper="seidel",
                           parametrizer="ParametrizeConstAccel")
    _, sd, _ = instance.compute_parameterization(0.0, 0.0)
    return sd
