"""Batched inverse dynamics (gravity included) compiled from a Drake plant.

Time parameterization and certification need joint torques at hundreds of path samples, and
the ABC via-point study at population x time samples (20,000 evaluations x 100 samples per
run). Drake's ``CalcInverseDynamics`` costs ~13 µs per call from Python (measured, Panda), so
:class:`BatchDynamics` runs the recursive Newton-Euler algorithm (RNEA) vectorized over ``N``
samples, in the compiled core (C++, :mod:`drake_mh._support.native`) where it is built, else
compiled with numba, instead. Nothing is typed per robot: the kinematic tree comes from
:func:`drake_mh.kinematics.compile_chain` (joint frames and axes read from Drake) and the
masses, centres of mass and rotational inertias from each body's
``default_spatial_inertia()``; welded bodies are lumped onto their moving ancestor. The
result is tested against :meth:`drake_mh.robot.Robot.inverse_dynamics` (Drake, with gravity).

Equations (world frame, ``N`` samples at once), for a moving frame ``k`` with parent ``p``,
origin ``o_k``, joint axis ``z_k``, ``r = o_k - o_p``:

    revolute:  ω_k = ω_p + z_k q̇_k,  α_k = α_p + z_k q̈_k + ω_p × z_k q̇_k,
               a_k = a_p + α_p × r + ω_p × (ω_p × r)
    prismatic: ω_k = ω_p,  α_k = α_p,
               a_k = a_p + α_p × r + ω_p × (ω_p × r) + 2 ω_p × z_k q̇_k + z_k q̈_k

with ``a_world = -g`` (gravity as a base acceleration). Per lumped body (mass m, centre of mass
offset c, inertia I_o about o_k): ``f = m (a_k + α × c + ω × (ω × c))``,
``n = I_o α + ω × I_o ω + m c × a_k``; forces are summed from the leaves inwards
(``N_p += N_k + r × F_k``) and ``τ_k = z_k · N_k`` (revolute) or ``z_k · F_k`` (prismatic).
"""

from __future__ import annotations

import functools
import weakref

import numba
import numpy as np

from drake_mh._support.native import compiled_core
from drake_mh.errors import InvalidArgument, UnsupportedModel
from drake_mh.kinematics import PRISMATIC, compile_chain

__all__ = ["BatchDynamics", "batch_dynamics"]

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def batch_dynamics(robot) -> BatchDynamics:
    """The :class:`BatchDynamics` of ``robot``, compiled on first use and cached per robot object."""
    dyn = _CACHE.get(robot)
    if dyn is None:
        dyn = _CACHE[robot] = BatchDynamics(robot)
    return dyn


def _lumped_inertias(plant, chain):
    """Mass ``(F,)``, centre of mass ``(F, 3)`` and inertia about the origin ``(F, 3, 3)`` per frame."""
    from pydrake.multibody.tree import BodyIndex

    F = len(chain.parent)
    mass = np.zeros(F)
    first = np.zeros((F, 3))  # Σ m c, in the moving frame
    inertia = np.zeros((F, 3, 3))  # about the moving frame's origin, in the moving frame
    for i in range(1, plant.num_bodies()):
        body = plant.get_body(BodyIndex(i))
        anchor, X_AB = chain.body_anchor[body.name()]
        if anchor < 0:  # welded to the world: never moves
            continue
        M = body.default_spatial_inertia()
        m = M.get_mass()
        if m == 0.0:
            continue
        R, p = X_AB[:3, :3], X_AB[:3, 3]
        c_B = np.asarray(M.get_com(), dtype=float)
        I_Bo = M.CalcRotationalInertia().CopyToFullMatrix3()
        I_cm = I_Bo - m * (c_B @ c_B * np.eye(3) - np.outer(c_B, c_B))  # about Bcm, in B
        c_A = R @ c_B + p
        mass[anchor] += m
        first[anchor] += m * c_A
        inertia[anchor] += R @ I_cm @ R.T + m * (c_A @ c_A * np.eye(3) - np.outer(c_A, c_A))
    com = np.divide(first, mass[:, None], out=np.zeros_like(first), where=mass[:, None] > 0)
    return mass, com, inertia


def _joint_extras(plant, chain) -> tuple[np.ndarray, np.ndarray]:
    """Joint damping ``(nq,)`` [N·m·s/rad] and reflected rotor inertia ``(nq,)`` [kg·m²]."""
    from pydrake.multibody.tree import JointActuatorIndex

    damping = np.zeros(plant.num_velocities())
    reflected = np.zeros(plant.num_velocities())
    for name in chain.joint_names:
        joint = plant.GetJointByName(name)
        damping[joint.velocity_start()] = float(np.asarray(joint.default_damping_vector()).sum())
    for i in range(plant.num_actuators()):
        act = plant.get_joint_actuator(JointActuatorIndex(i))
        if act.joint().num_velocities() == 1:
            reflected[act.joint().velocity_start()] = act.default_reflected_inertia()
    return damping, reflected


class BatchDynamics:
    """Vectorized inverse dynamics ``τ = M(q) q̈ + C(q, q̇) q̇ + g(q)`` of a :class:`~drake_mh.robot.Robot`.

    Args:
        robot: the robot; its plant is read once.

    Raises:
        UnsupportedModel: joints other than revolute, prismatic or weld.
    """

    def __init__(self, robot):
        plant = robot.plant
        self.nq = robot.nq
        self.joint_names = list(robot.joint_names)
        self.chain = compile_chain(plant)
        if sorted(self.chain.qidx.tolist()) != list(range(self.nq)):
            raise UnsupportedModel("every joint coordinate must belong to exactly one 1-DOF joint")
        self.mass, self.com, self.inertia = _lumped_inertias(plant, self.chain)
        self.damping, self.reflected = _joint_extras(plant, self.chain)
        self.gravity_W = np.asarray(plant.gravity_field().gravity_vector(), dtype=float)
        self._K_R = np.ascontiguousarray(self.chain.K[:, :3, :3])
        self._K_p = np.ascontiguousarray(self.chain.K[:, :3, 3])

    @functools.cached_property
    def packed(self) -> tuple[np.ndarray, np.ndarray]:
        """The chain and inertias in two flat arrays for the compiled core's searches: ints
        ``(3 F,)`` = parent, kind, qidx; floats ``(25 F + 3 + 2 nq,)`` = K_R ``(F, 3, 3)``,
        K_p ``(F, 3)``, mass ``(F,)``, com ``(F, 3)``, inertia ``(F, 3, 3)``, the base
        acceleration ``-g (3,)``, damping ``(nq,)``, reflected inertia ``(nq,)``."""
        ints = np.concatenate([self.chain.parent, self.chain.kind, self.chain.qidx]).astype(np.int64)
        floats = np.concatenate([self._K_R.ravel(), self._K_p.ravel(), self.mass, self.com.ravel(),
                                 self.inertia.ravel(), -self.gravity_W, self.damping, self.reflected])
        return np.ascontiguousarray(ints), np.ascontiguousarray(floats, dtype=float)

    def inverse_dynamics(self, Q, V, A, gravity: bool = True) -> np.ndarray:
        """Joint torques ``(N, nq)`` [N·m] for states ``Q, V, A`` of shape ``(N, nq)``.

        Args:
            Q, V, A: positions [rad], velocities [rad/s], accelerations [rad/s²], ``(N, nq)``
                (or ``(nq,)``).
            gravity: include ``g(q)`` (as Drake's plant has it); ``False`` gives
                ``M q̈ + C q̇`` (+ damping and rotor inertia terms, which are linear in v and a).

        Raises:
            InvalidArgument: ``Q``, ``V`` and ``A`` not of one shape ``(N, nq)`` or ``(nq,)``.
        """
        Q, V, A = (np.ascontiguousarray(np.atleast_2d(np.asarray(x, dtype=float))) for x in (Q, V, A))
        a_world = -self.gravity_W if gravity else np.zeros(3)
        if not (Q.shape == V.shape == A.shape and Q.ndim == 2 and Q.shape[1] == self.nq):
            raise InvalidArgument(f"inverse_dynamics: Q, V and A must have one shape (N, {self.nq}) or ({self.nq},); "
                                  f"got {Q.shape}, {V.shape}, {A.shape}")
        core = compiled_core()
        arguments = (self.chain.parent, self._K_R, self._K_p, self.chain.kind, self.chain.qidx, self.mass,
                     self.com, self.inertia, a_world, Q, V, A)
        if core is not None:  # the compiled core: nothing compiles at call time
            tau = core.rnea(*arguments)
        else:
            tau = np.empty(Q.shape)
            _rnea(*arguments, tau)
        return tau + self.damping * V + self.reflected * A

    def path_coefficients(self, P, Ps, Pss) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """toppra's second-order coefficients along a path: ``τ = a s̈ + b ṡ² + c``.

        With ``q = p(s)``: ``q̇ = p' ṡ`` and ``q̈ = p' s̈ + p'' ṡ²``, so ``a = M(p) p'``,
        ``b = M(p) p'' + C(p, p') p'``, ``c = g(p)`` (toppra's ``JointTorqueConstraint``
        derivation). Joint damping (linear in ``q̇``, not in ``ṡ²``) is not supported here.

        Args:
            P, Ps, Pss: ``(N, nq)`` path, first and second derivatives at the gridpoints.

        Returns:
            ``a, b, c``, each ``(N, nq)`` [N·m].
        """
        P, Ps, Pss = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (P, Ps, Pss))
        N = P.shape[0]
        zeros = np.zeros_like(P)
        tau = self.inverse_dynamics(np.vstack([P, P, P]), np.vstack([zeros, zeros, Ps]),
                                    np.vstack([zeros, Ps, Pss]))
        c = tau[:N]
        return tau[N:2 * N] - c, tau[2 * N:] - c, c


@numba.njit(cache=True, inline="always")
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@numba.njit(cache=True)
def _rnea(parent, KR, Kp, kind, qidx, mass, com, inertia, a_world, Q, V, A, tau):  # pragma: no cover
    """RNEA of the module docstring, one sample at a time (numba; frames in topological order)."""
    F = parent.shape[0]
    R = np.empty((F, 3, 3))
    o = np.empty((F, 3))
    w = np.empty((F, 3))
    dw = np.empty((F, 3))
    acc = np.empty((F, 3))
    force = np.empty((F, 3))
    moment = np.empty((F, 3))
    r = np.empty(3)
    z = np.empty(3)
    t1 = np.empty(3)
    t2 = np.empty(3)
    c = np.empty(3)
    I = np.empty((3, 3))
    eye = np.eye(3)
    zero = np.zeros(3)
    for n in range(Q.shape[0]):
        for k in range(F):
            p = parent[k]
            i = qidx[k]
            q, qd, qdd = Q[n, i], V[n, i], A[n, i]
            Rp = eye if p < 0 else R[p]
            wp = zero if p < 0 else w[p]
            dwp = zero if p < 0 else dw[p]
            ap = a_world if p < 0 else acc[p]
            for a in range(3):
                r[a] = Rp[a, 0] * Kp[k, 0] + Rp[a, 1] * Kp[k, 1] + Rp[a, 2] * Kp[k, 2]
            # R0 = Rp @ KR[k]; z = R0[:, 2]
            cq, sq = np.cos(q), np.sin(q)
            for a in range(3):
                r0 = Rp[a, 0] * KR[k, 0, 0] + Rp[a, 1] * KR[k, 1, 0] + Rp[a, 2] * KR[k, 2, 0]
                r1 = Rp[a, 0] * KR[k, 0, 1] + Rp[a, 1] * KR[k, 1, 1] + Rp[a, 2] * KR[k, 2, 1]
                r2 = Rp[a, 0] * KR[k, 0, 2] + Rp[a, 1] * KR[k, 1, 2] + Rp[a, 2] * KR[k, 2, 2]
                z[a] = r2
                if kind[k] == 1:  # prismatic
                    R[k, a, 0], R[k, a, 1], R[k, a, 2] = r0, r1, r2
                else:
                    R[k, a, 0] = r0 * cq + r1 * sq
                    R[k, a, 1] = -r0 * sq + r1 * cq
                    R[k, a, 2] = r2
            if kind[k] == 1:
                for a in range(3):
                    r[a] += z[a] * q
            # common part: a_k = a_p + dw_p x r + w_p x (w_p x r)
            _cross(dwp, r, t1)
            _cross(wp, r, c)
            _cross(wp, c, t2)
            for a in range(3):
                acc[k, a] = ap[a] + t1[a] + t2[a]
                o[k, a] = (0.0 if p < 0 else o[p, a]) + r[a]
            if kind[k] == 1:
                _cross(wp, z, t1)
                for a in range(3):
                    w[k, a] = wp[a]
                    dw[k, a] = dwp[a]
                    acc[k, a] += 2.0 * t1[a] * qd + z[a] * qdd
            else:
                _cross(wp, z, t1)
                for a in range(3):
                    w[k, a] = wp[a] + z[a] * qd
                    dw[k, a] = dwp[a] + z[a] * qdd + t1[a] * qd
        for k in range(F):
            for a in range(3):
                force[k, a] = 0.0
                moment[k, a] = 0.0
        for k in range(F - 1, -1, -1):
            m = mass[k]
            if m > 0.0:
                for a in range(3):
                    c[a] = R[k, a, 0] * com[k, 0] + R[k, a, 1] * com[k, 1] + R[k, a, 2] * com[k, 2]
                for a in range(3):  # I = R inertia R^T
                    for b in range(3):
                        s = 0.0
                        for e in range(3):
                            for f in range(3):
                                s += R[k, a, e] * inertia[k, e, f] * R[k, b, f]
                        I[a, b] = s
                _cross(w[k], c, t1)
                _cross(w[k], t1, t2)
                _cross(dw[k], c, t1)
                for a in range(3):
                    force[k, a] += m * (acc[k, a] + t1[a] + t2[a])
                for a in range(3):  # t1 = I w, t2 = I dw
                    t1[a] = I[a, 0] * w[k, 0] + I[a, 1] * w[k, 1] + I[a, 2] * w[k, 2]
                    t2[a] = I[a, 0] * dw[k, 0] + I[a, 1] * dw[k, 1] + I[a, 2] * dw[k, 2]
                _cross(w[k], t1, z)
                _cross(c, acc[k], t1)
                for a in range(3):
                    moment[k, a] += t2[a] + z[a] + m * t1[a]
            p = parent[k]
            if kind[k] == 1:
                tau[n, qidx[k]] = R[k, 0, 2] * force[k, 0] + R[k, 1, 2] * force[k, 1] + R[k, 2, 2] * force[k, 2]
            else:
                tau[n, qidx[k]] = R[k, 0, 2] * moment[k, 0] + R[k, 1, 2] * moment[k, 1] + R[k, 2, 2] * moment[k, 2]
            if p >= 0:
                for a in range(3):
                    r[a] = o[k, a] - o[p, a]
                _cross(r, force[k], t1)
                for a in range(3):
                    force[p, a] += force[k, a]
                    moment[p, a] += moment[k, a] + t1[a]
