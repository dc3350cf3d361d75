"""The cyclic paper's two cases, in metres, and its published figures.

* :func:`maple_leaf_task` — §V.B: the 12-DOF arm (12 links of 0.30 m) draws the Japanese
  maple leaf (eq. (26)) through three Lissajous moving bases (Table III), joint constraints of
  eq. (27) and three circular obstacles of radius 0.10 m at (0.95, 0.15), (1.45, 0.65),
  (0.40, -0.15) m. All four components use the positive root of eq. (8b) (the paper: only it
  satisfies eq. (27)).
* :func:`circle_task` — §V.A: the 5-DOF arm (0.22, 0.20, 0.18, 0.16, 0.14 m) draws the circle
  of eq. (24) with a 2-link component in four stages (Table I, eq. (25)) and one 3-link
  component. **As printed the case is infeasible** (``knots="paper"``): the 2-link tip is 0.311
  to 0.934 m from the circle over the period while the 3-link part reaches 0.48 m (0.725 m at
  t = 0, REFERENCES.md). ``knots="drake_mh"`` (default) is our replacement table, chosen by a
  documented search following the paper's own rule (its step 2b: knots inside the 3-link
  component's workspace) — see :func:`circle_task` and ``docs/cyclic.md``.

Readings (documented, each verified in ``tests/cyclic/test_reproduction.py``):

* Leaf: scale 0.10 m and centre (1.80, 0.50) m (not printed; REFERENCES.md).
* Moving base II: ``y = 0.12 sin(2Ωt + φ) + 0.70``. Table IV's component 2 reproduces with
  φ = π/3 (its target), component 3 with φ = π/6 (its base, as printed): the paper's numbers
  come from two different moving bases II, i.e. not from one connected arm. A connected plan
  must choose one: ``phase_ii`` (default π/6, as printed).
"""

from __future__ import annotations

import math

import numpy as np

from drake_mh.cyclic.curves import Circle, Lissajous, MapleLeaf
from drake_mh.cyclic.obstacles import CircleObstacle
from drake_mh.cyclic.task import CyclicTask, ThreeLinkComponent, TwoLinkComponent
from drake_mh.cyclic.two_link import StagedPolynomial
from drake_mh.errors import InvalidArgument

__all__ = [
    "PERIOD", "moving_bases", "maple_leaf_task", "circle_task", "TABLE_I", "TABLE_I_DRAKE_MH",
    "TABLE_II", "TABLE_III_SEARCH", "TABLE_IV", "LEAF_OBSTACLES",
]

PERIOD = 2 * math.pi
"""Period T [s] of both paper paths (eq. (24): T = 2π s; eq. (26): Ω = 2π/T, T not printed)."""

LEAF_OBSTACLES = (CircleObstacle((0.95, 0.15), 0.10), CircleObstacle((1.45, 0.65), 0.10),
                  CircleObstacle((0.40, -0.15), 0.10))
"""§V.B: circles of radius 10 cm at (95, 15), (145, 65), (40, -15) cm."""

#: Table IV: component -> {"ga": (fitness, k), "woa": (fitness, k)}
TABLE_IV = {
    1: {"ga": (8.520017, -0.2964), "woa": (8.520015, -0.2959)},
    2: {"ga": (10.7813247, 0.2857), "woa": (10.7813234, 0.2861)},
    3: {"ga": (5.1071097, -1.3635), "woa": (5.1071078, -1.3644)},
    4: {"ga": (15.25502, 1.4053), "woa": (15.255025, 1.4053)},
}

#: Table II (5-DOF): method -> (fitness, k)
TABLE_II = {"ga": (20.2871801, -0.2838), "woa": (20.2871779, -0.2828)}

#: Table III "search area" of k per 3-link component [rad] (the 4th is in the text)
TABLE_III_SEARCH = {1: (-0.4, 0.9), 2: (0.0, 0.7), 3: (-1.6, -0.9), 4: (0.9, 1.6)}

#: Table I: joint -> stage I..IV initial angles [rad] (the finals are the next stage's initials)
TABLE_I = np.array([[-2.75, -2.6, -1.8, -2.0],
                    [1.3, 1.8, 1.0, 2.0]])

#: drake_mh's replacement of Table I (see :func:`circle_task`): joint -> stage initial angles [rad]
TABLE_I_DRAKE_MH = np.array([[1.51, 0.14, -0.17, 1.78],
                             [1.18, 2.88, 1.06, -0.90]])


def moving_bases(phase_ii: float = math.pi / 6, period: float = PERIOD) -> tuple[Lissajous, Lissajous, Lissajous]:
    """Table III's moving bases I, II, III in metres (x and y of III are both Lissajous)."""
    return (Lissajous(ax=0.12, nx=2, cx=0.40, ay=0.12, ny=1, cy=0.30, period=period),
            Lissajous(ax=0.12, nx=1, cx=1.00, ay=0.12, ny=2, cy=0.70, phy=phase_ii, period=period),
            Lissajous(ax=0.12, nx=1, cx=1.40, ay=0.12, ny=2, cy=0.10, period=period))


def maple_leaf_task(robot=None, phase_ii: float = math.pi / 6, obstacles=LEAF_OBSTACLES,
                    use_table_iii_search: bool = False, n_samples: int = 1000,
                    link_radius: float = 0.0) -> CyclicTask:
    """§V.B: the 12-DOF arm tracking the maple leaf through three moving bases.

    Args:
        robot: a Drake :class:`~drake_mh.robot.Robot` to read lengths and limits from (e.g.
            ``load_robot("planar12")``); ``None``: 12 × 0.30 m and eq. (27)'s limits.
        phase_ii: phase of moving base II's y (π/6 printed; π/3 reproduces component 2).
        obstacles: the circles (default: the paper's three).
        use_table_iii_search: search k in Table III's areas instead of the computed
            feasible intervals.
        n_samples: samples per period (the paper: 1000).
        link_radius: link half-thickness for the obstacle test [m] (the paper: 0).
    """
    bases = moving_bases(phase_ii)
    targets = (*bases, MapleLeaf())
    comps = tuple(ThreeLinkComponent(target, root=1, name=f"component {i + 1}",
                                     search=TABLE_III_SEARCH[i + 1] if use_table_iii_search else None)
                  for i, target in enumerate(targets))
    if robot is not None:
        return CyclicTask.for_robot(robot, comps, obstacles, n_samples=n_samples, link_radius=link_radius,
                                    name="maple leaf (12-DOF)")
    lower = np.full(12, -math.pi)
    lower[[1, 4, 7, 10]] = 0.0  # eq. (27): joints 2, 5, 8, 11 in [0, π]
    return CyclicTask((0.30,) * 12, comps, tuple(lower), (math.pi,) * 12, tuple(obstacles), n_samples,
                      link_radius, name="maple leaf (12-DOF)")


def circle_task(robot=None, knots: str = "drake_mh", root: int = 1, a6: float = 0.0,
                n_samples: int = 1000) -> CyclicTask:
    """§V.A: the 5-DOF arm tracking eq. (24)'s circle: 2-link stages + one 3-link component.

    Args:
        robot: Drake robot for lengths and limits (``load_robot("planar5")``); ``None``:
            (0.22, 0.20, 0.18, 0.16, 0.14) m and ±π.
        knots: ``"paper"`` for Table I as printed (infeasible: no k exists, see the module
            docstring), ``"drake_mh"`` for :data:`TABLE_I_DRAKE_MH`, or a ``(2, S)`` array of
            stage initial angles [rad].
        root: sign of eq. (8b) for the 3-link component (the paper plans both).
        a6: eq. (16)'s sixth-order coefficient (the paper: 0).
        n_samples: samples per period.

    ``TABLE_I_DRAKE_MH`` replaces Table I by the paper's own rule (knots chosen so that the
    2-link tip stays inside the 3-link component's workspace, its step 2b), made concrete as a
    search: differential evolution (``drake_mh.optim``, 3000 evaluations, seed 2) over the 8
    stage angles minimizing, summed over both roots of eq. (8b), the 2-link joints' path length
    plus the best 3-link fitness over a 180-point k grid (200 samples per period), with
    infeasible designs graded by their violation; angles rounded to 0.01 rad. The 2-link tip
    then stays 0.215 - 0.459 m from the circle (3-link reach 0.48 m); feasible k: about
    [2.883, 3.385] (root +1) and [-2.942, -2.899] (root -1).
    """
    if isinstance(knots, str):
        if knots not in ("paper", "drake_mh"):
            raise InvalidArgument(f"knots must be 'paper', 'drake_mh' or a (2, S) array, got {knots!r}")
        table = TABLE_I if knots == "paper" else TABLE_I_DRAKE_MH
    else:
        table = np.asarray(knots, dtype=float)
        if table.ndim != 2 or table.shape[0] != 2:
            raise InvalidArgument(f"knots array must be (2, S) stage initial angles [rad], got shape {table.shape}")
    two = TwoLinkComponent(StagedPolynomial(table.T, PERIOD, a6), name="2-link")
    three = ThreeLinkComponent(Circle((-0.25, 0.30), 0.30, phase=3.0, period=PERIOD), root=root, name="3-link")
    if robot is not None:
        return CyclicTask.for_robot(robot, (two, three), (), n_samples=n_samples, name="circle (5-DOF)")
    return CyclicTask((0.22, 0.20, 0.18, 0.16, 0.14), (two, three), (-math.pi,) * 5, (math.pi,) * 5, (),
                      n_samples, name="circle (5-DOF)")
