"""Scene fixtures built from primitives, in the spirit of the MotionBenchMaker sets.

MotionBenchMaker (Chamzas, Quintero-Peña, Kingston, Orthey, Rakita, Gleicher, Toussaint,
Kavraki, "MotionBenchMaker: A Tool to Generate and Benchmark Motion Planning Datasets", IEEE
RA-L 7(2), 2022) places a table, a bookshelf, a box or a cage around the robot, varies its
pose, and asks for a motion to a grasp inside it. The sizes below are those of its published
Panda scenes (boards 4 cm thick, cans 3 cm in radius); the placements, clutter and grasps are
drawn by our own generator (:mod:`drake_mh.planning.problems.generate`), not copied.

A fixture is drawn in its own frame F (x: away from the robot, into the fixture; y: lateral;
z: up; origin at the front of the fixture, on the floor of its lowest compartment or on the
table top), then placed in the world by a yaw about the robot's base axis. Each fixture returns
its obstacles and its *grasp sites*: objects the robot reaches for, each with the approach
directions that make sense inside the fixture (through the shelf's opening, down into the box).

Every function takes a ``numpy.random.Generator`` and returns a :class:`Fixture`; all lengths
in metres, angles in radians.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_mh.geometry.shapes import Box, Cylinder

CAN_RADIUS = 0.03
"""[m] the cans of MotionBenchMaker's shelves (14 cm tall; 12 cm on its tables)."""
BOARD = 0.04
"""[m] board and wall thickness."""


@dataclass(frozen=True)
class Site:
    """Something to reach for: an object and how a gripper may approach it.

    Attributes:
        name: the obstacle's name.
        p_W: ``(3,)`` centre of the object [m].
        size: half the object's width across the approach [m] (a can's radius, half a cube).
        approaches: ``(K, 3)`` unit approach directions in the world (the gripper moves along
            them towards the object), best first.
    """

    name: str
    p_W: np.ndarray
    size: float
    approaches: np.ndarray


@dataclass
class Fixture:
    """Obstacles and grasp sites of one drawn fixture, in the world frame.

    Attributes:
        kind: the problem set's name.
        obstacles: ``[(name, shape, p_WO (3,), rpy (3,))]`` ready for ``Scene.add``.
        sites: the :class:`Site` objects to reach for at the goal.
        starts: :class:`Site` objects for the start (another object of the fixture, a free spot
            on the table, a point under it); empty: the start is the robot's ready configuration.
        X_WF: ``(4, 4)`` pose of the fixture frame.
    """

    kind: str
    obstacles: list = field(default_factory=list)
    sites: list = field(default_factory=list)
    starts: list = field(default_factory=list)
    X_WF: np.ndarray = field(default_factory=lambda: np.eye(4))

    def add(self, name: str, shape, p_F, rpy_F=(0.0, 0.0, 0.0)) -> None:
        """Add an obstacle given in the fixture frame (``rpy_F``: roll, pitch in F, then yaw)."""
        from pydrake.math import RollPitchYaw, RotationMatrix

        R_FO = RotationMatrix(RollPitchYaw(*rpy_F)).matrix()
        R_WO = self.X_WF[:3, :3] @ R_FO
        p_W = self.X_WF[:3, :3] @ np.asarray(p_F, float) + self.X_WF[:3, 3]
        rpy_W = RollPitchYaw(RotationMatrix(R_WO)).vector()
        self.obstacles.append((name, shape, p_W, np.asarray(rpy_W)))

    def site(self, name: str, p_F, size: float, approaches_F, start: bool = False) -> Site:
        """Add a goal site (``start``: a start site) given in the fixture frame (approaches as
        directions in F)."""
        R = self.X_WF[:3, :3]
        A = np.atleast_2d(np.asarray(approaches_F, float)) @ R.T
        A /= np.linalg.norm(A, axis=1, keepdims=True)
        site = Site(name, R @ np.asarray(p_F, float) + self.X_WF[:3, 3], float(size), A)
        (self.starts if start else self.sites).append(site)
        return site


def _frame(rng: np.random.Generator, front: tuple, height: tuple, spread: float = 1.75,
           face: float = 0.25) -> np.ndarray:
    """Fixture frame: direction ``φ ~ U(-spread, spread)`` around the base, front edge at a
    distance ``~ U(front)``, floor at ``z ~ U(height)``, facing the robot within ``± face``."""
    phi = rng.uniform(-spread, spread)
    distance = rng.uniform(*front)
    z = rng.uniform(*height)
    yaw = phi + rng.uniform(-face, face)
    X = np.eye(4)
    c, s = np.cos(yaw), np.sin(yaw)
    X[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    # the robot's base (world origin) lies on the fixture's -x side: put the front edge at
    # `distance` along the direction φ, then the frame origin there
    X[:3, 3] = [distance * np.cos(phi), distance * np.sin(phi), z]
    return X


def _scatter(rng: np.random.Generator, n: int, x: tuple, y, radii, gap: float = 0.05,
             tries: int = 200) -> list:
    """``n`` points in the box ``x × y`` (``y``: one range, or one per point) whose discs of
    ``radii`` stay ``gap`` apart; ``None`` for a point that found no room in ``tries`` draws."""
    radii = np.broadcast_to(np.asarray(radii, float), (n,))
    ys = [y] * n if np.ndim(y[0]) == 0 else list(y)
    placed: list = []
    out: list = []
    for i in range(n):
        out.append(None)
        for _ in range(tries):
            p = np.array([rng.uniform(*x), rng.uniform(*ys[i])])
            if all(np.linalg.norm(p - q) >= radii[i] + r + gap for q, r in placed):
                placed.append((p, radii[i]))
                out[i] = p
                break
    return out


def _side_approaches(rng: np.random.Generator, spread: float = 0.35, down: float = 0.0) -> np.ndarray:
    """Approach directions through a front opening (+x of F), yawed within ``± spread``,
    optionally tilted ``down`` [rad]; the straight one first."""
    yaws = [0.0, rng.uniform(-spread, spread)]
    return np.array([[np.cos(down) * np.cos(a), np.cos(down) * np.sin(a), -np.sin(down)] for a in yaws])


def _cans(fx: Fixture, rng: np.random.Generator, levels: list, per_level: int, x: tuple, y: tuple,
          height: float = 0.14, prefix: str = "can") -> None:
    count = 0
    for z in levels:
        for p in _scatter(rng, per_level, x, y, CAN_RADIUS, gap=0.08):
            if p is None:
                continue
            count += 1
            name = f"{prefix}{count}"
            centre = (p[0], p[1], z + height / 2)
            fx.add(name, Cylinder(CAN_RADIUS, height), centre)
            approaches = _side_approaches(rng)
            fx.site(name, centre, CAN_RADIUS, approaches)
            fx.site(name, centre, CAN_RADIUS, approaches, start=True)  # move from one can to another


def bookshelf_small(rng: np.random.Generator) -> Fixture:
    """One compartment (1.0 m wide, 26 cm high, 1.2 m deep) with three cans on its floor; from one
    can to another."""
    fx = Fixture("bookshelf_small", X_WF=_frame(rng, front=(0.45, 0.62), height=(0.15, 0.55)))
    depth, width, inner = 1.2, 1.0, 0.26
    fx.add("shelf_bottom", Box(depth, width, BOARD), (depth / 2, 0.0, -BOARD / 2))
    fx.add("shelf_top", Box(depth, width, BOARD), (depth / 2, 0.0, inner + BOARD / 2))
    for side, y in (("left", -1), ("right", 1)):
        fx.add(f"side_{side}", Box(depth, BOARD, inner + 2 * BOARD), (depth / 2, y * (width + BOARD) / 2, inner / 2))
    _cans(fx, rng, [0.0], 3, x=(0.1, 0.35), y=(-0.38, 0.38))
    return fx


def bookshelf_tall(rng: np.random.Generator) -> Fixture:
    """Four boards 30 cm apart (three compartments, 1.0 m wide, 1.2 m deep) between two tall
    sides, with three cans in each compartment; from a can to one in another compartment."""
    fx = Fixture("bookshelf_tall", X_WF=_frame(rng, front=(0.5, 0.65), height=(-0.1, 0.1)))
    depth, width, pitch = 1.2, 1.0, 0.3
    for i, label in enumerate(("bottom", "middle_bottom", "middle_top", "top")):
        fx.add(f"shelf_{label}", Box(depth, width, BOARD), (depth / 2, 0.0, i * pitch - BOARD / 2))
    for side, y in (("left", -1), ("right", 1)):
        fx.add(f"side_{side}", Box(depth + 0.1, BOARD, 1.64), (depth / 2, y * (width + BOARD) / 2, 0.1))
    _cans(fx, rng, [0.0, pitch, 2 * pitch], 3, x=(0.1, 0.35), y=(-0.38, 0.38))
    return fx


def bookshelf_thin(rng: np.random.Generator) -> Fixture:
    """A narrow shelf on four legs: six boards 25 cm apart (0.62 m deep), split by a vertical
    divider into two columns (48 cm wide), with up to ten cans; from a can to one on another level."""
    fx = Fixture("bookshelf_thin", X_WF=_frame(rng, front=(0.45, 0.6), height=(-0.05, 0.05)))
    depth, width, pitch = 0.62, 1.0, 0.25
    levels = [-0.35 + i * pitch for i in range(6)]
    for i, z in enumerate(levels):
        fx.add(f"shelf_{i}", Box(depth, width, BOARD), (depth / 2, 0.0, z - BOARD / 2))
    fx.add("shelf_vert", Box(depth, BOARD, levels[-1] - levels[0]), (depth / 2, 0.0, (levels[0] + levels[-1]) / 2))
    for label, x, y in (("fl", 0, -1), ("fr", 0, 1), ("bl", 1, -1), ("br", 1, 1)):
        fx.add(f"leg_{label}", Box(BOARD, BOARD, 1.64), (x * depth, y * (width / 2 + BOARD / 2), 0.12))
    count = 0
    for z in levels[:-1]:
        for column in (-1, 1):
            if rng.uniform() < 0.5:
                continue
            x, y = rng.uniform(0.08, 0.3), column * rng.uniform(0.12, 0.36)
            count += 1
            centre = (x, y, z + 0.07)
            fx.add(f"can{count}", Cylinder(CAN_RADIUS, 0.14), centre)
            approaches = _side_approaches(rng, spread=0.2)
            fx.site(f"can{count}", centre, CAN_RADIUS, approaches)
            fx.site(f"can{count}", centre, CAN_RADIUS, approaches, start=True)
    return fx


def box(rng: np.random.Generator) -> Fixture:
    """An open box (0.7 m square, 0.7 m walls, front wall 0.6 m) below the base with its lid
    leaning open, and a can inside; from the ready configuration to above the can."""
    fx = Fixture("box", X_WF=_frame(rng, front=(0.15, 0.28), height=(-0.5, -0.35), spread=1.6))
    side, wall = 0.7, 0.7
    c = side / 2
    fx.add("base", Box(side, side, BOARD), (c, 0.0, -BOARD / 2))
    fx.add("side_front", Box(BOARD, side, wall - 0.1), (0.0, 0.0, (wall - 0.1) / 2 - 0.05))
    fx.add("side_back", Box(BOARD, side, wall), (side, 0.0, wall / 2 - 0.05))
    for name, y in (("side_left", -1), ("side_right", 1)):
        fx.add(name, Box(side, BOARD, wall), (c, y * c, wall / 2 - 0.05))
    lid = rng.uniform(0.6, 0.9)  # leaning open towards the robot over the back wall
    fx.add("side_cap", Box(side, side, BOARD), (c + 0.1, 0.0, wall + 0.2), (0.0, lid, 0.0))
    p = (c + rng.uniform(-0.15, 0.15), rng.uniform(-0.2, 0.2), 0.07)
    fx.add("can", Cylinder(CAN_RADIUS, 0.14), p)
    top = (p[0], p[1], p[2] + 0.07)  # grasp the can from above: down onto its top
    tilt = rng.uniform(-0.3, 0.3)
    fx.site("can", top, 0.0, [[0.0, 0.0, -1.0], [np.sin(tilt), 0.0, -np.cos(tilt)]])
    return fx


def cage(rng: np.random.Generator) -> Fixture:
    """A cage (0.7 m square floor, walls on three sides, a roof, two bars across the front)
    with a 7 cm cube on its floor; from the ready configuration through the window between the
    bars to above the cube."""
    fx = Fixture("cage", X_WF=_frame(rng, front=(0.38, 0.5), height=(0.1, 0.35), spread=1.6, face=0.15))
    side = 0.7
    c = side / 2
    fx.add("base", Box(side, side, BOARD), (c, 0.0, -BOARD / 2))
    fx.add("side_back", Box(BOARD, side, side), (side, 0.0, side / 2 - 0.02))
    for name, y in (("side_left", -1), ("side_right", 1)):
        fx.add(name, Box(side, BOARD, side), (c, y * c, side / 2 - 0.02))
    fx.add("side_cap", Box(side - 0.05, side - 0.05, BOARD), (c + 0.05, 0.0, side - 0.01))
    fx.add("bar_low", Box(BOARD, side, BOARD), (0.0, 0.0, 0.14))
    fx.add("bar_high", Box(BOARD, side, BOARD), (0.0, 0.0, 0.44))
    p = (c + rng.uniform(-0.12, 0.05), rng.uniform(-0.15, 0.15), 0.035)
    fx.add("cube", Box(0.07, 0.07, 0.07), p)
    top = (p[0], p[1], 0.07)
    down = rng.uniform(0.9, 1.35)  # through the window, pointing down onto the cube
    fx.site("cube", top, 0.0, [[np.cos(down), 0.0, -np.sin(down)], [0.0, 0.0, -1.0]])
    return fx


def _table(fx: Fixture, rng: np.random.Generator) -> None:
    depth, width, legs = 1.2, 2.0, 0.7
    fx.add("table_top", Box(depth, width, BOARD), (depth / 2, 0.0, -BOARD / 2))
    for label, x, y in (("left_front", 0, -1), ("right_front", 0, 1), ("left_back", 1, -1), ("right_back", 1, 1)):
        fx.add(f"table_leg_{label}", Box(0.05, 0.05, legs),
               (0.05 + x * (depth - 0.1), y * (width / 2 - 0.05), -BOARD - legs / 2))
    # clutter (MotionBenchMaker's table objects): a can to grasp, a cube, a tall cylinder, boards
    shapes = [("can", Cylinder(CAN_RADIUS, 0.12), 0.06, 0.03),
              ("cube", Box(0.25, 0.25, 0.25), 0.125, 0.18),
              ("object1", Cylinder(0.05, 0.35), 0.175, 0.05),
              ("object2", Box(0.2, 0.02, 0.4), 0.2, 0.1),
              ("object3", Box(0.02, 0.2, 0.4), 0.2, 0.1),
              ("object4", Box(0.2, 0.05, 0.35), 0.175, 0.11),
              ("object5", Box(0.2, 0.05, 0.35), 0.175, 0.11)]
    # the can on one side, two free spots where the hand starts (having put something down) on
    # the other, a 30 cm board standing between the two sides, the clutter anywhere: the motion
    # crosses the table
    side = rng.choice([-1.0, 1.0])
    near, far = tuple(sorted((0.08 * side, 0.6 * side))), tuple(sorted((-0.6 * side, -0.08 * side)))
    fx.add("divider", Box(0.5, 0.02, 0.3), (0.35, 0.0, 0.15))
    order = [0, None, None] + list(range(1, len(shapes)))  # None: a start spot
    ranges = [near, far, far] + [(-0.6, 0.6)] * (len(order) - 3)
    radii = [0.08 if i is None else shapes[i][3] for i in order]
    points = _scatter(rng, len(order), x=(0.1, 0.55), y=ranges, radii=radii, gap=0.06)
    spots = 0
    for i, p in zip(order, points):
        if p is None:
            continue
        if i is None:
            spots += 1
            fx.site(f"spot{spots}", (p[0], p[1], 0.05), 0.0, [[0.0, 0.0, -1.0]], start=True)
            continue
        name, shape, half_height, _ = shapes[i]
        yaw = 0.0 if name == "can" else rng.uniform(-np.pi, np.pi)
        fx.add(name, shape, (p[0], p[1], half_height), (0.0, 0.0, yaw))
        if name == "can":
            top = (p[0], p[1], 2 * half_height)
            fx.site("can", (p[0], p[1], half_height), CAN_RADIUS, _side_approaches(rng, spread=0.5))
            fx.site("can_top", top, 0.0, [[0.0, 0.0, -1.0]])


def table_pick(rng: np.random.Generator) -> Fixture:
    """A 1.2 m x 2.0 m table on four legs, seven objects and a board across it; from a free spot
    on one side to the can on the other."""
    fx = Fixture("table_pick", X_WF=_frame(rng, front=(0.3, 0.45), height=(0.1, 0.3)))
    _table(fx, rng)
    return fx


def table_under_pick(rng: np.random.Generator) -> Fixture:
    """The same table, a little closer; from under the table top to the can on it."""
    fx = Fixture("table_under_pick", X_WF=_frame(rng, front=(0.25, 0.4), height=(0.2, 0.35)))
    _table(fx, rng)
    fx.starts.clear()  # the start is under the table top instead
    fx.site("under_table", (rng.uniform(0.12, 0.25), rng.uniform(-0.3, 0.3), -rng.uniform(0.16, 0.22)), 0.0,
            [[1.0, 0.0, 0.0]], start=True)
    return fx


#: set name -> fixture function, in MotionBenchMaker's order
FIXTURES = {
    "table_pick": table_pick,
    "table_under_pick": table_under_pick,
    "bookshelf_small": bookshelf_small,
    "bookshelf_tall": bookshelf_tall,
    "bookshelf_thin": bookshelf_thin,
    "box": box,
    "cage": cage,
}
