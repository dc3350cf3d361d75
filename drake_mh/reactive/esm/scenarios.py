"""The ESM paper's simulation scenarios on the Panda (Sec. IV-B, Figs. 4 and 5).

* ``"self_motion"`` (Fig. 4): self-motion manipulability optimization. θ0 = [0.481, 0.703,
  0.093, -0.800, -0.364, 0.992, 0.026] (flange within 1e-4 m of the target, μ = 0.108), fixed
  target [0.6, 0.3, 0.5] m, a sphere of radius 0.15 m from [0, -0.4, 0.6] m at 0.16 m/s along
  +Y, 4.5 s.
* ``"tracking"`` (Fig. 5): trajectory tracking while a cube-shaped obstacle changes its
  velocity direction every 5 s. The paper gives neither the path nor the obstacle's
  numbers; drake_mh's choice (``docs/esm.md``): the flange follows a horizontal circle of
  radius 0.1414 m around [0.5, 0.2, 0.5] m (through the paper's target, period 10 s, starting
  at θ0); a cube of side 0.12 m starts at [0.25, -0.25, 0.62] m and moves at 0.06 m/s along
  +Y, -Y, +Y ... switching every 5 s (back and forth across the upper arm), 15 s.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import UnknownMethod
from drake_mh.reactive.esm.config import ESMConfig
from drake_mh.geometry.shapes import Box, Sphere

THETA0 = (0.481, 0.703, 0.093, -0.800, -0.364, 0.992, 0.026)
"""ESM paper's initial configuration of the Panda [rad] (Sec. IV-B)."""
TARGET = (0.6, 0.3, 0.5)
"""ESM paper's desired end-effector position [m] (Sec. IV-A/B)."""


@dataclass(frozen=True)
class MovingObstacle:
    """An obstacle moving with piecewise-constant velocity.

    Attributes:
        name: obstacle name in the scene.
        shape: :class:`drake_mh.geometry.shapes.Sphere`, ``Box`` ...
        start: position at t = 0 [m] ``(3,)``.
        velocities: ``((t_from [s], (vx, vy, vz) [m/s]), ...)``, first ``t_from = 0``.
    """

    name: str
    shape: object
    start: tuple
    velocities: tuple

    def state(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Position [m] and velocity [m/s] at time ``t`` [s]."""
        p = np.asarray(self.start, dtype=float).copy()
        v = np.zeros(3)
        for i, (t_from, vel) in enumerate(self.velocities):
            if t < t_from:
                break
            t_to = self.velocities[i + 1][0] if i + 1 < len(self.velocities) else np.inf
            v = np.asarray(vel, dtype=float)
            p = p + v * (min(t, t_to) - t_from)
        return p, v


def _fixed_target(_t: float) -> np.ndarray:
    return np.asarray(TARGET, dtype=float)


CIRCLE_CENTRE = (0.5, 0.2, 0.5)
CIRCLE_PERIOD = 10.0


def _circle_target(t: float) -> np.ndarray:
    """Horizontal circle through the paper's target, counter-clockwise, period 10 s."""
    centre = np.asarray(CIRCLE_CENTRE)
    offset = np.asarray(TARGET) - centre
    radius, phase = np.hypot(offset[0], offset[1]), np.arctan2(offset[1], offset[0])
    angle = phase + 2.0 * np.pi * t / CIRCLE_PERIOD
    return centre + np.array([radius * np.cos(angle), radius * np.sin(angle), 0.0])


@dataclass(frozen=True)
class ESMScenario:
    """A timed ESM task.

    Attributes:
        name: scenario name.
        theta0: initial joint angles [rad].
        duration: simulated time [s].
        target: ``t [s] -> r_d (3,) [m]``.
        obstacles: the :class:`MovingObstacle` s.
        config: the :class:`ESMConfig` (Δt, weights, threshold).
    """

    name: str
    theta0: tuple
    duration: float
    target: Callable[[float], np.ndarray]
    obstacles: tuple
    config: ESMConfig = field(default_factory=ESMConfig)

    @property
    def steps(self) -> int:
        """Number of control steps ``round(duration / Δt)``."""
        return int(round(self.duration / self.config.dt))


def self_motion(config: ESMConfig | None = None, duration: float = 4.5) -> ESMScenario:
    """Scenario 1 (Fig. 4): self-motion manipulability optimization, sphere along +Y."""
    sphere = MovingObstacle("sphere", Sphere(0.15), (0.0, -0.4, 0.6), ((0.0, (0.0, 0.16, 0.0)),))
    return ESMScenario("self_motion", THETA0, duration, _fixed_target, (sphere,), config or ESMConfig())


def tracking(config: ESMConfig | None = None, duration: float = 15.0, period: float = 5.0,
             speed: float = 0.06) -> ESMScenario:
    """Scenario 2 (Fig. 5): circle tracking, cube reversing its direction every ``period`` s."""
    n = int(np.ceil(duration / period)) + 1
    velocities = tuple((k * period, (0.0, speed * (1 if k % 2 == 0 else -1), 0.0)) for k in range(n))
    cube = MovingObstacle("cube", Box((0.12, 0.12, 0.12)), (0.25, -0.25, 0.62), velocities)
    return ESMScenario("tracking", THETA0, duration, _circle_target, (cube,), config or ESMConfig())


SCENARIOS = {"self_motion": self_motion, "tracking": tracking}


def get_scenario(name: str, **kwargs) -> ESMScenario:
    """A scenario by name (``"self_motion"`` or ``"tracking"``).

    Raises:
        UnknownMethod: unknown name (lists the names).
    """
    if name not in SCENARIOS:
        raise UnknownMethod(name, SCENARIOS, what="ESM scenario")
    return SCENARIOS[name](**kwargs)
