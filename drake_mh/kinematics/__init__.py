"""Kinematics compiled from the Drake plant: batched and single-configuration FK and Jacobians.

* :mod:`.batch` — :class:`BatchKinematics` (``Robot.batch``: ``fk(Q) -> (N, 4, 4)``,
  ``jacobian(Q) -> (N, 6, nq)``, points and frames of a population) and
  :func:`compile_chain`, the joint frames and axes read from the plant;
* :mod:`.kernels` — the compiled FK/Jacobian kernels themselves, the documented entry points
  that other packages' compiled code calls (:func:`~.kernels.frames_block`,
  :func:`~.kernels.fk_jacobian_one`, ...).
"""

from drake_mh.kinematics.batch import PRISMATIC, BatchKinematics, CompiledChain, compile_chain

__all__ = ["BatchKinematics", "CompiledChain", "compile_chain", "PRISMATIC"]
