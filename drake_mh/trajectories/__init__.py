"""Trajectories under limits: time parameterization, certification, via-point polynomials.

* :func:`retime` — toppra / Drake ``Toppra`` / ruckig on a joint path, certified or raising;
* :func:`certify` — dense-sampling check of position, velocity, acceleration, jerk and torque
  (gravity included) against a robot's limits;
* :class:`Trajectory` — ``q(t) = p(s(t))`` with exact derivatives up to jerk; ``sample(rate_hz,
  robot)``, ``save(path, robot)`` (ROS 2 ``JointTrajectory`` JSON/YAML, CSV) and ``to_drake()``;
  :func:`load_trajectory` reads the files back (:mod:`~drake_mh.trajectories.export`);
* :class:`BatchDynamics` — inverse dynamics of whole batches, compiled from the Drake plant;
* :mod:`~drake_mh.trajectories.viapoint` — the ABC paper's 4th/5th-order via-point polynomials
  and its fitness.

See ``docs/trajectories.md``.
"""

from drake_mh.trajectories.certify import QUANTITIES, Certificate, certify
from drake_mh.trajectories.dynamics import BatchDynamics, batch_dynamics
from drake_mh.trajectories.export import TrajectorySamples, load_trajectory
from drake_mh.trajectories.retime import RETIMERS, retime, ruckig_state_to_state
from drake_mh.trajectories.trajectory import Trajectory
from drake_mh.trajectories.viapoint import ViaPointFitness, ViaPointProblem, viapoint_trajectory

__all__ = ["retime", "certify", "Certificate", "Trajectory", "BatchDynamics", "batch_dynamics",
           "ruckig_state_to_state", "RETIMERS", "QUANTITIES", "ViaPointProblem", "ViaPointFitness",
           "viapoint_trajectory", "TrajectorySamples", "load_trajectory"]
