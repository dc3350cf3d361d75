"""A cyclic planning task: a planar arm split into 2-link and 3-link components.

The cyclic paper models a planar hyper-redundant arm as a chain of components (its
Sec. III.A): a **2-link component** follows periodic sixth-order polynomial joint trajectories
(eq. (16), stages of eq. (25)); a **3-link component** keeps its orientation angle constant
(eq. (17)) and puts its tip on a periodic curve — the next **moving base** (Table III) or, for
the last component, the end-effector path. Every curve has the path's period, so every joint
trajectory is periodic.

:class:`CyclicTask` holds the arm (link lengths, joint limits — from Drake with
:meth:`CyclicTask.for_robot`), the components in arm order, and circular obstacles.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from drake_mh.cyclic.curves import PeriodicCurve, as_curve
from drake_mh.cyclic.obstacles import CircleObstacle
from drake_mh.cyclic.two_link import StagedPolynomial
from drake_mh.errors import InvalidArgument, UnsupportedModel

__all__ = ["TwoLinkComponent", "ThreeLinkComponent", "CyclicTask", "planar_chain"]


@dataclass(frozen=True)
class TwoLinkComponent:
    """Two joints driven by :class:`StagedPolynomial` trajectories (eqs. (16), (25))."""

    trajectory: StagedPolynomial
    name: str = "2-link"

    n_joints = 2

    def __post_init__(self):
        if not isinstance(self.trajectory, StagedPolynomial) or self.trajectory.n_joints != 2:
            raise InvalidArgument(f"{self.name}: trajectory must be a StagedPolynomial of 2 joints")


@dataclass(frozen=True)
class ThreeLinkComponent:
    """Three joints with a constant orientation angle k whose tip follows ``target``.

    Attributes:
        target: the curve the tip follows (a moving base, or the end-effector path); a
            :class:`PeriodicCurve` (see :func:`drake_mh.cyclic.curves.as_curve`).
        root: sign of eq. (8b): +1 (middle joint in [0, π]) or -1.
        search: optional ``(lo, hi)`` search box for k [rad] (the paper's Table III "search
            area"); default: the hull of the feasible intervals computed by the planner.
        name: for messages and reports.
    """

    target: PeriodicCurve
    root: int = 1
    search: tuple[float, float] | None = None
    name: str = "3-link"

    n_joints = 3

    def __post_init__(self):
        if not isinstance(self.target, PeriodicCurve):
            raise InvalidArgument(f"{self.name}: target must be a PeriodicCurve; wrap callables or samples "
                                  "with drake_mh.cyclic.curves.as_curve(curve, period)")
        if self.root not in (1, -1):
            raise InvalidArgument(f"{self.name}: root must be +1 or -1 (sign of eq. (8b)), got {self.root!r}")
        if self.search is not None and not (len(self.search) == 2 and self.search[0] < self.search[1]):
            raise InvalidArgument(f"{self.name}: search must be (lo, hi) with lo < hi [rad], got {self.search!r}")


def planar_chain(robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Link lengths and limits of a planar serial arm, read from its Drake model.

    The joint origins and the end effector at ``q = 0`` (``robot.batch.moving_frames`` and
    ``robot.batch.positions``) give the link lengths; every joint axis must be +z of the world
    and every origin in one plane z = const (so that positive angles turn counter-clockwise
    seen from +z, the paper's convention).

    Returns:
        ``(lengths (n,) [m], lower (n,), upper (n,) [rad])``.

    Raises:
        UnsupportedModel: the arm is not planar in world x-y with +z joint axes.
    """
    q0 = np.zeros((1, robot.nq))
    R, p = robot.batch.moving_frames(q0)
    ee = robot.batch.positions(q0)
    axes = R[0, :, :, 2]
    points = np.vstack([p[0], ee])
    if not (np.allclose(axes, [0.0, 0.0, 1.0], atol=1e-9) and np.ptp(points[:, 2]) < 1e-9):
        raise UnsupportedModel(f"{robot.name}: cyclic planning needs a planar arm whose joint axes are all "
                               "world +z and whose joints and end effector lie in one plane z = const "
                               "(like urdf/planar5.urdf, planar12.urdf)")
    lengths = np.linalg.norm(np.diff(points[:, :2], axis=0), axis=1)
    return lengths, np.array(robot.lower, dtype=float), np.array(robot.upper, dtype=float)


@dataclass(frozen=True)
class CyclicTask:
    """A planar arm, its components and obstacles (all lengths in metres, angles in radians).

    Attributes:
        lengths: ``(n,)`` link lengths [m] in arm order.
        components: 2-link / 3-link components in arm order; their joint counts add up to n;
            the last one is a :class:`ThreeLinkComponent` whose target is the end-effector path.
        lower, upper: ``(n,)`` joint limits [rad], relative angles of eq. (3).
        obstacles: circles no link may touch (eq. (6)).
        n_samples: samples per period for the objective and the checks (the paper: 1000).
        link_radius: link half-thickness added to obstacle radii [m] (0: the paper's lines).
        name: for reports.
    """

    lengths: tuple
    components: tuple
    lower: tuple
    upper: tuple
    obstacles: tuple = ()
    n_samples: int = 1000
    link_radius: float = 0.0
    name: str = "cyclic task"

    def __post_init__(self):
        lengths = np.asarray(self.lengths, dtype=float).reshape(-1)
        n = len(lengths)
        object.__setattr__(self, "lengths", tuple(lengths))
        object.__setattr__(self, "components", tuple(self.components))
        object.__setattr__(self, "obstacles", tuple(self.obstacles))
        lower = np.asarray(self.lower, dtype=float).reshape(-1)
        upper = np.asarray(self.upper, dtype=float).reshape(-1)
        if np.any(lengths <= 0) or lower.shape != (n,) or upper.shape != (n,) or np.any(lower > upper):
            raise InvalidArgument(f"{self.name}: need n positive lengths and (n,) limits lower <= upper; got "
                                  f"{n} lengths, limits of shapes {lower.shape}, {upper.shape}")
        object.__setattr__(self, "lower", tuple(lower))
        object.__setattr__(self, "upper", tuple(upper))
        if not self.components or not isinstance(self.components[-1], ThreeLinkComponent):
            raise InvalidArgument(f"{self.name}: the last component must be a ThreeLinkComponent whose target "
                                  "is the end-effector path")
        for c in self.components:
            if not isinstance(c, (TwoLinkComponent, ThreeLinkComponent)):
                raise InvalidArgument(f"{self.name}: components must be TwoLinkComponent or ThreeLinkComponent, "
                                      f"got {type(c).__name__}")
            if isinstance(c, TwoLinkComponent) and abs(c.trajectory.period - self.period) > 1e-12 * self.period:
                raise InvalidArgument(f"{self.name}: {c.name} has period {c.trajectory.period} s but the path "
                                      f"has {self.period} s; cyclic planning needs one period")
            if isinstance(c, ThreeLinkComponent) and abs(c.target.period - self.period) > 1e-12 * self.period:
                raise InvalidArgument(f"{self.name}: {c.name}'s curve has period {c.target.period} s but the "
                                      f"path has {self.period} s; moving bases must repeat with the path")
        total = sum(c.n_joints for c in self.components)
        if total != n:
            raise InvalidArgument(f"{self.name}: components cover {total} joints but the arm has {n}")
        for c in self.obstacles:
            if not isinstance(c, CircleObstacle):
                raise InvalidArgument(f"{self.name}: obstacles must be CircleObstacle, got {type(c).__name__}")

    @classmethod
    def for_robot(cls, robot, components: Sequence, obstacles: Sequence[CircleObstacle] = (), **kwargs):
        """A task on a Drake robot: lengths and joint limits read with :func:`planar_chain`."""
        lengths, lower, upper = planar_chain(robot)
        kwargs.setdefault("name", robot.name)
        return cls(tuple(lengths), tuple(components), tuple(lower), tuple(upper), tuple(obstacles), **kwargs)

    @property
    def n(self) -> int:
        return len(self.lengths)

    @property
    def path(self) -> PeriodicCurve:
        """The end-effector path (the last component's target)."""
        return self.components[-1].target

    @property
    def period(self) -> float:
        return self.components[-1].target.period

    def joint_slices(self) -> list[slice]:
        """The joints of each component, in arm order."""
        out, i = [], 0
        for c in self.components:
            out.append(slice(i, i + c.n_joints))
            i += c.n_joints
        return out

    def three_link_indices(self) -> list[int]:
        """Indices into :attr:`components` of the 3-link components (one k each)."""
        return [i for i, c in enumerate(self.components) if isinstance(c, ThreeLinkComponent)]

    def with_curve(self, index: int, curve) -> CyclicTask:
        """A copy with component ``index``'s target replaced (callable/samples accepted)."""
        comps = list(self.components)
        old = comps[index]
        if not isinstance(old, ThreeLinkComponent):
            raise InvalidArgument(f"component {index} is not a 3-link component")
        comps[index] = ThreeLinkComponent(as_curve(curve, self.period), old.root, old.search, old.name)
        return CyclicTask(self.lengths, tuple(comps), self.lower, self.upper, self.obstacles, self.n_samples,
                          self.link_radius, self.name)
