"""Batched forward kinematics and Jacobians compiled from a Drake plant.

:class:`BatchKinematics` evaluates whole populations of configurations ``Q (N, nq)`` at once:
``fk(Q) -> (N, 4, 4)``, ``jacobian(Q) -> (N, 6, nq)``, ``points(Q) -> (N, S, 3)``. Nothing is
typed per robot: the kinematic tree is *compiled from the plant* — for every joint, the fixed
poses of its parent/child frames and its axis are read from Drake — and the result is checked
against Drake in the tests (<= 1e-10 on random configurations).

Compilation. Each single-DOF joint k gets a *moving frame* ``M̃_k``: the joint's child frame M
rotated so that the joint axis is its z axis. With ``R_a`` a rotation taking z to the axis a,
``X_FM(q) = R_a · Rz(q) · R_aᵀ`` (revolute) or ``R_a · Tz(q) · R_aᵀ`` (prismatic), so

    X_W M̃_k = X_W M̃_parent(k) · K_k · Rz(q_k)        (or · Tz(q_k))

with one constant ``K_k = X_{M̃_parent} P · X_PF · R_a`` per joint (welded links folded in).
Every link is then a constant offset from the moving frame of its nearest moving ancestor
(its *anchor*; -1 = world). Per joint and configuration the kernel does one constant 3x3
rotation product, one rotation about z, and the Jacobian column ``[z_k; z_k × (p_E − o_k)]``.

The kernels (:mod:`drake_mh.kinematics.kernels`) are numba-compiled, vectorized across blocks of
configurations (chosen by measurement, ``studies/bench_kinematics.py``, docs/benchmarks.md:
numpy's per-call overhead dominates at the population sizes metaheuristics use).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from drake_mh._support.native import compiled_core
from drake_mh.kinematics import kernels as _kernels
from drake_mh.errors import FrameNotFound

REVOLUTE, PRISMATIC = 0, 1


@dataclass(frozen=True)
class CompiledChain:
    """The kinematic tree of a plant as flat arrays (moving frames in topological order).

    Attributes:
        parent: ``(F,)`` index of each moving frame's parent moving frame, -1 for the world.
        K: ``(F, 4, 4)`` constant transform from the parent moving frame to frame k at q_k = 0.
        kind: ``(F,)`` ``REVOLUTE`` or ``PRISMATIC``.
        qidx: ``(F,)`` index of the joint's coordinate in ``q``.
        ancestors: ``(F, F)`` bool, ``ancestors[k, j]``: frame j lies on the path world -> k
            (inclusive).
        joint_names: ``(F,)`` joint names.
        body_anchor: link name -> (anchor frame index, ``X_AB (4, 4)``).
    """

    parent: np.ndarray
    K: np.ndarray
    kind: np.ndarray
    qidx: np.ndarray
    ancestors: np.ndarray
    joint_names: tuple
    body_anchor: dict


def _axis_to_z_rotation(axis: np.ndarray) -> np.ndarray:
    """A rotation ``R_a`` with ``R_a @ [0, 0, 1] = axis`` (axis is a unit vector)."""
    z = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def _homogeneous(R: np.ndarray, p=None) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = R
    if p is not None:
        T[:3, 3] = p
    return T


def compile_chain(plant) -> CompiledChain:
    """Read joint frames and axes from a finalized ``MultibodyPlant`` into a :class:`CompiledChain`.

    Raises:
        drake_mh.errors.UnsupportedModel: a joint that is not revolute, prismatic or weld.
    """
    from pydrake.multibody.tree import JointIndex

    from drake_mh.errors import UnsupportedModel

    joints = [plant.get_joint(JointIndex(i)) for i in range(plant.num_joints())]
    by_parent: dict[int, list] = {}
    for joint in joints:
        by_parent.setdefault(int(joint.parent_body().index()), []).append(joint)

    world = int(plant.world_body().index())
    body_anchor = {plant.world_body().name(): (-1, np.eye(4))}
    anchor_of = {world: (-1, np.eye(4))}
    parent, K, kind, qidx, names = [], [], [], [], []
    stack = [world]
    while stack:  # depth-first from the world: parents are compiled before children
        body = stack.pop()
        for joint in by_parent.get(body, []):
            anchor, X_AP = anchor_of[body]
            X_PF = joint.frame_on_parent().GetFixedPoseInBodyFrame().GetAsMatrix4()
            X_CM = joint.frame_on_child().GetFixedPoseInBodyFrame().GetAsMatrix4()
            X_MC = np.linalg.inv(X_CM)
            child = int(joint.child_body().index())
            jtype = joint.type_name()
            if jtype == "weld":
                X_FM = joint.X_FM().GetAsMatrix4()
                anchor_of[child] = (anchor, X_AP @ X_PF @ X_FM @ X_MC)
            elif jtype in ("revolute", "prismatic"):
                axis = np.asarray(joint.revolute_axis() if jtype == "revolute"
                                  else joint.translation_axis(), dtype=float)
                R_a = _axis_to_z_rotation(axis)
                k = len(parent)
                parent.append(anchor)
                K.append(X_AP @ X_PF @ _homogeneous(R_a))
                kind.append(REVOLUTE if jtype == "revolute" else PRISMATIC)
                qidx.append(joint.position_start())
                names.append(joint.name())
                anchor_of[child] = (k, _homogeneous(R_a.T) @ X_MC)
            else:
                raise UnsupportedModel(f"joint {joint.name()!r} of type {jtype!r} is not supported")
            body_anchor[joint.child_body().name()] = anchor_of[child]
            stack.append(child)

    F = len(parent)
    ancestors = np.zeros((F, F), dtype=bool)
    for k in range(F):
        j = k
        while j >= 0:
            ancestors[k, j] = True
            j = parent[j]
    return CompiledChain(
        parent=np.asarray(parent, dtype=np.int64),
        K=np.asarray(K, dtype=float).reshape(F, 4, 4),
        kind=np.asarray(kind, dtype=np.int64),
        qidx=np.asarray(qidx, dtype=np.int64),
        ancestors=ancestors,
        joint_names=tuple(names),
        body_anchor=body_anchor,
    )


def _signed_permutations(KR: np.ndarray, tol: float = 1e-15) -> np.ndarray:
    """``(F, 3)`` source column of each column of K's rotation where it is a signed permutation.

    Axis-aligned URDFs (most industrial arms, the Panda, DH tables with α in multiples of
    90°) give rotations whose entries are 0 or ±1; the kernel then copies signed columns
    instead of multiplying 3x3 matrices. Rows of -1 mark general rotations.
    """
    perm = -np.ones((len(KR), 3), dtype=np.int64)
    for k, R in enumerate(KR):
        big = np.abs(R) > 1.0 - tol
        small = np.abs(R) < tol
        if np.all(big | small) and np.all(big.sum(axis=0) == 1) and np.all(big.sum(axis=1) == 1):
            perm[k] = np.argmax(big, axis=0)
    return perm


class BatchKinematics:
    """Population kinematics of a :class:`drake_mh.robot.Robot`, compiled from its plant.

    All methods take ``Q (N, nq)`` (a single ``(nq,)`` is treated as ``N = 1``) and loop over
    configurations inside compiled code.
    """

    def __init__(self, robot):
        self.robot = robot
        self.chain = compile_chain(robot.plant)
        c = self.chain
        self._args = (c.parent, np.ascontiguousarray(c.K[:, :3, :3]),
                      np.ascontiguousarray(c.K[:, :3, 3]), _signed_permutations(c.K[:, :3, :3]),
                      c.kind, c.qidx)
        self._frame_cache: dict[str, tuple] = {}
        self._one_functions: dict[tuple, object] = {}
        self._q_shape = (robot.nq,)
        self._native = None

    @property
    def nq(self) -> int:
        return self.robot.nq

    @property
    def chain_arrays(self) -> tuple:
        """The chain as the compiled kernels read it: ``(parent (F,), KR (F, 3, 3), Kp (F, 3),
        perm (F, 3), kind (F,), qidx (F,))`` (each moving frame's parent, fixed rotation and
        translation [m] from it, signed axis permutation, joint kind, configuration index)."""
        return self._args

    def frame_arrays(self, frame: str | None = None) -> tuple:
        """``(anchor, R_AF (3, 3), p_AF (3,) [m], on_path (F,) bool)`` of a named frame (default:
        the end effector): its moving frame ``A``, its fixed pose in it, and the frames on ``A``'s
        path to the world, as the compiled kernels read them.

        Raises:
            FrameNotFound: the robot has no such frame on a moving body of the chain.
        """
        return self._frame_anchor(frame)

    def _frame_anchor(self, frame: str | None):
        """(anchor, R_AF, p_AF, on_path) for a named frame (default: the end effector)."""
        name = self.robot.ee_frame_name if frame is None else frame
        if name not in self._frame_cache:
            drake_frame = self.robot._frame(name)
            body = drake_frame.body().name()
            if body not in self.chain.body_anchor:
                raise FrameNotFound(name, self.chain.body_anchor)
            anchor, X_AB = self.chain.body_anchor[body]
            X_AF = X_AB @ drake_frame.GetFixedPoseInBodyFrame().GetAsMatrix4()
            F = len(self.chain.parent)
            on_path = self.chain.ancestors[anchor] if anchor >= 0 else np.zeros(F, dtype=bool)
            self._frame_cache[name] = (anchor, np.ascontiguousarray(X_AF[:3, :3]),
                                       np.ascontiguousarray(X_AF[:3, 3]), on_path.copy())
        return self._frame_cache[name]

    def core_kinematics(self):
        """The chain in the compiled core (``drake_mh._native.Kinematics``, built once), or None
        where the core is not built or is switched off (:mod:`drake_mh._support.native`): then the
        numba kernels answer."""
        if compiled_core() is None:
            return None
        if self._native is None:
            parent, KR, Kp, perm, kind, qidx = self._args
            self._native = compiled_core().Kinematics(
                np.concatenate([parent, perm.ravel(), kind, qidx]).astype(np.int64),
                np.concatenate([KR.ravel(), Kp.ravel()]))
        return self._native

    def _run(self, Q, frame, want_jac: bool):
        native = self.core_kinematics()
        if native is not None:
            anchor, ER, Ep, on_path = self._frame_anchor(frame)
            T, J = native.fk_jacobian(self.robot.check_Q(Q), anchor, ER.ravel(), Ep, on_path, want_jac)
            return T, J if want_jac else np.empty((0, 6, self.nq))
        QT = self._transposed(Q)
        anchor, ER, Ep, on_path = self._frame_anchor(frame)
        N = QT.shape[1]
        T = np.empty((N, 4, 4))
        J = np.empty((N, 6, self.nq)) if want_jac else np.empty((0, 6, self.nq))
        _kernels.fk_jacobian(QT, *self._args, anchor, ER, Ep, on_path, want_jac, T, J)
        return T, J

    def one(self, q, frame: str | None = None, want_jac: bool = False) -> np.ndarray:
        """Pose ``X_WF (4, 4)`` (or, with ``want_jac``, the Jacobian ``(6, nq)``) of one configuration.

        What ``Robot.fk`` / ``Robot.jacobian`` run: :meth:`one_function`'s closure for the frame.
        """
        return self.one_function(frame, want_jac)(q)

    def one_function(self, frame: str | None = None, want_jac: bool = False):
        """``f(q) -> X_WF (4, 4)`` (or the Jacobian ``(6, nq)``) for one configuration, cached per frame.

        One compiled call (no allocation inside, finiteness checked there), about 1 µs of kernel
        plus 0.5 µs of Python instead of Drake's 6-11 µs; any ``q`` that is not already a float
        ``(nq,)`` array goes through ``Robot.check_q`` first, and a non-finite one gets its
        error from there. Every argument of the kernel is bound in the closure (the dispatch
        cost grows with the number of arguments Python passes).
        """
        key = (frame, want_jac, compiled_core() is not None)
        function = self._one_functions.get(key)
        if function is not None:
            return function
        native = self.core_kinematics()
        if native is not None:  # the compiled core (finiteness checked there)
            run, (anchor, ER, Ep, on_path) = native.fk_jacobian_one, self._frame_anchor(frame)
            ER, ndarray, f64, shape, check = ER.ravel(), np.ndarray, np.dtype(np.float64), self._q_shape, \
                self.robot.check_q

            empty, nq, no_jacobian = np.empty, shape[0], np.empty((6, shape[0]))

            def function(q):
                if not (type(q) is ndarray and q.dtype is f64 and q.shape == shape):
                    q = check(q)
                T = empty((4, 4))
                J = empty((6, nq)) if want_jac else no_jacobian
                if not run(q, anchor, ER, Ep, on_path, T, J, want_jac):
                    check(q)  # raises, naming the joints
                return J if want_jac else T

            self._one_functions[key] = function
            return function
        F = len(self.chain.parent)
        (parent, KR, Kp, perm, kind, qidx), (anchor, ER, Ep, on_path) = self._args, self._frame_anchor(frame)
        R, p = np.empty((F, 3, 3)), np.empty((F, 3))
        kernel, empty, ndarray, f64 = _kernels.fk_one, np.empty, np.ndarray, np.dtype(np.float64)
        shape, nq, check = self._q_shape, self._q_shape[0], self.robot.check_q
        no_jacobian = np.empty((6, nq))

        def function(q):
            if not (type(q) is ndarray and q.dtype is f64 and q.shape == shape):
                q = np.ascontiguousarray(check(q))
            T = empty((4, 4))
            J = empty((6, nq)) if want_jac else no_jacobian
            if not kernel(q, parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path, want_jac, R, p, T, J):
                check(q)  # raises, naming the joints
            return J if want_jac else T

        self._one_functions[key] = function
        return function

    def _transposed(self, Q) -> np.ndarray:
        """Checked batch as a C-contiguous ``(nq, N)`` array (the kernels' layout)."""
        return np.ascontiguousarray(self.robot.check_Q(Q).T)

    def fk(self, Q, frame: str | None = None) -> np.ndarray:
        """Poses ``X_WF (N, 4, 4)`` of the end effector (or ``frame``)."""
        return self._run(Q, frame, False)[0]

    def positions(self, Q, frame: str | None = None) -> np.ndarray:
        """Positions ``p_WF (N, 3)`` of the end effector (or ``frame``) [m]."""
        return self._run(Q, frame, False)[0][:, :3, 3]

    def jacobian(self, Q, frame: str | None = None) -> np.ndarray:
        """Geometric Jacobians ``(N, 6, nq)``, rows ``[ω_W; v_W]`` as Drake's."""
        return self._run(Q, frame, True)[1]

    def fk_jacobian(self, Q, frame: str | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Poses ``(N, 4, 4)`` and Jacobians ``(N, 6, nq)`` in one pass."""
        return self._run(Q, frame, True)

    def manipulability(self, Q, translational: bool = True) -> np.ndarray:
        """Yoshikawa manipulability ``(N,)`` of the end effector (see ``Robot.manipulability``)."""
        J = self.jacobian(Q)
        J = J[:, 3:, :] if translational else J
        det = np.linalg.det(J @ np.swapaxes(J, 1, 2))
        return np.sqrt(np.maximum(det, 0.0))

    def compile_points(self, links, offsets) -> tuple[np.ndarray, np.ndarray]:
        """Express points given in link frames as (anchor, offset) pairs for :meth:`points`.

        Args:
            links: ``(S,)`` link names.
            offsets: ``(S, 3)`` positions ``p_BS`` of the points in their link frames [m].
        """
        offsets = np.asarray(offsets, dtype=float).reshape(-1, 3)
        anchors = np.empty(len(links), dtype=np.int64)
        p_AS = np.empty_like(offsets)
        for i, (link, p_BS) in enumerate(zip(links, offsets)):
            if link not in self.chain.body_anchor:
                raise FrameNotFound(link, self.chain.body_anchor, what="link")
            anchor, X_AB = self.chain.body_anchor[link]
            anchors[i] = anchor
            p_AS[i] = X_AB[:3, :3] @ p_BS + X_AB[:3, 3]
        return anchors, np.ascontiguousarray(p_AS)

    def points(self, Q, anchors: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """World positions ``(N, S, 3)`` of points compiled by :meth:`compile_points`."""
        if self.core_kinematics() is not None:  # p_WF + R_WF p_FS from the compiled core's frames (anchor -1: W)
            R, p = self.moving_frames(Q)
            world = anchors < 0
            at = np.where(world, 0, anchors)
            out = p[:, at] + np.einsum("nsij,sj->nsi", R[:, at], offsets)
            out[:, world] = offsets[world]
            return out
        QT = self._transposed(Q)
        out = np.empty((QT.shape[1], len(anchors), 3))
        _kernels.points(QT, *self._args, anchors, offsets, out)
        return out

    @functools.cached_property
    def _sphere_points(self):
        model = self.robot.sphere_model
        return self.compile_points(list(model.links), model.centres_B)

    def sphere_centres(self, Q) -> np.ndarray:
        """World positions ``(N, S, 3)`` of the centres of ``robot.sphere_model``'s spheres."""
        return self.points(Q, *self._sphere_points)

    def moving_frames(self, Q) -> tuple[np.ndarray, np.ndarray]:
        """World rotations ``(N, F, 3, 3)`` and origins ``(N, F, 3)`` of every joint's moving frame.

        Column 2 of each rotation is the joint axis in W; frame k belongs to
        ``chain.joint_names[k]``.
        """
        native = self.core_kinematics()
        if native is not None:
            return native.moving_frames(self.robot.check_Q(Q))
        QT = self._transposed(Q)
        F = len(self.chain.parent)
        R = np.empty((QT.shape[1], F, 3, 3))
        p = np.empty((QT.shape[1], F, 3))
        _kernels.moving_frames(QT, *self._args, R, p)
        return R, p
