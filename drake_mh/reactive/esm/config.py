"""Configuration of the ESM control step (ESM paper, eqs. (6)-(11)).

ESM = "Enhancing Safety and Manipulability" (Xie et al., the ESM paper in
``seeds/003_*.txt``). One control step solves, at the joint-angle level (eq. (11)),

    min_θ  h1 ||r(θ) - r_d|| + h2 / μ(θ)
    s.t.   max(θ⁻, θ_prev - q̇_max Δt) <= θ <= min(θ⁺, θ_prev + q̇_max Δt)
           δ_k (θ - θ_prev) / Δt <= Y V_k - V0_k        for every critical pair k

with μ the translational manipulability (eq. (3), 3 x nq Jacobian of the end effector).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from drake_mh.errors import InvalidArgument

CONSTRAINT_HANDLINGS = ("reject", "repair")
"""How a population member violating the obstacle inequality is treated (see
:mod:`drake_mh.reactive.esm.problem`)."""


@dataclass(frozen=True)
class ESMConfig:
    """Weights, gains and limits of the ESM scheme.

    Defaults are the ESM paper's (Sec. IV: h1 = h2 = 1, Y = 200, Δt = 0.028 s) except where
    noted. The paper gives no number for the safety threshold d.

    Attributes:
        h1: weight of the tracking error ``||r(θ) - r_d||`` [1/m] (eq. (10)).
        h2: weight of ``1/μ(θ)`` (eq. (10)). Note: at the paper's target the exact minimizer
            of ``e + 1/μ`` lies 3.8 cm off the target for ``h1 = h2 = 1`` (the multiplier
            ``||∇_r (1/μ*)|| = 2.39 > h1``); ``h1 >= 3 h2`` pins the end effector.
        Y: gain of the obstacle inequality (eq. (6)) [m/s].
        threshold: safety distance d [m] between robot links and obstacles (eq. (6)).
            0.05 m: the largest round value the Panda's base links (which cannot move away)
            keep in the paper's scenario 1 (link 1 passes 0.057 m under the sphere).
        dt: control period Δt [s] (eq. (11)).
        step_fraction: discrete-time safeguard γ of drake_mh (``None``: the paper's eq. (9)
            exactly). Eq. (6) bounds the approach speed by ``Y V ≈ Y D / 4``; with the forward
            difference of eq. (11) one step may then change D by ``Y Δt / 4 = 1.4 D`` at the
            paper's numbers, i.e. cross the threshold. With γ the bound is
            ``sgn(D) min(Y |V|, γ |D| / Δt)``: at most the fraction γ of the distance to the
            threshold is used up (or recovered) per step.
        buffer: drake_mh's margin [m] added to d inside the inequality (``D = ||M - N|| - d -
            buffer``) so that the second-order error of the linearized eq. (7) (the critical
            points slide along the surfaces, links rotate, during a step) does not cross d
            itself; 0 = the paper. Measured without it: 0.04 mm below d in scenario 1
            (0.7 mm with the paper's eq. (9)); with 1 mm, 1.6 mm below d in scenario 2 when
            solvers chatter at the velocity limit with 2-3 rows active on a cube's edges
            (a point 0.5 m from an axis turning 0.07 rad moves ~1.2 mm off its tangent).
        velocity_scale: fraction of the robot's velocity limits used for the box of eq. (11)
            (the paper's experiment used 0.7 rad/s for safety; 1.0 = the datasheet limits).
        fixed_link_tol: rows whose ``||δ_k||`` [m/rad] is below this are dropped: no joint
            moves that point along ``u`` (the base, or a capsule spinning about its own axis).
        unsatisfiable_relax: ρ for rows that nothing in the box satisfies (see
            ``ESMStep.relaxed_rows``).
        feasibility_tol: slack allowed when checking the inequalities, in units of the
            constraint (m/s · Δt = m) [m].
        repair_sweeps: sweeps of cyclic projection in the repair operator.
    """

    h1: float = 1.0
    h2: float = 1.0
    Y: float = 200.0
    threshold: float = 0.05
    dt: float = 0.028
    step_fraction: float | None = 0.5
    buffer: float = 0.003
    velocity_scale: float = 1.0
    fixed_link_tol: float = 1e-6
    unsatisfiable_relax: float = 0.05
    feasibility_tol: float = 1e-10
    repair_sweeps: int = 30

    def __post_init__(self):
        for name in ("h1", "h2", "threshold", "buffer", "fixed_link_tol", "unsatisfiable_relax", "feasibility_tol"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise InvalidArgument(f"ESMConfig.{name} must be a finite number >= 0; got {value!r}")
        for name in ("Y", "dt", "velocity_scale"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InvalidArgument(f"ESMConfig.{name} must be a finite number > 0; got {value!r}")
        if self.h1 == 0 and self.h2 == 0:
            raise InvalidArgument("ESMConfig: h1 and h2 are both 0, nothing to minimize; set one > 0")
        if self.step_fraction is not None and not (0 < self.step_fraction <= 1):
            raise InvalidArgument(
                f"ESMConfig.step_fraction must be in (0, 1] or None (paper's eq. (9) unchanged); "
                f"got {self.step_fraction!r}")
        if not (isinstance(self.repair_sweeps, int) and self.repair_sweeps >= 1):
            raise InvalidArgument(f"ESMConfig.repair_sweeps must be an integer >= 1; got {self.repair_sweeps!r}")
