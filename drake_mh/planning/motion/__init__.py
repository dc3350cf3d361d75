"""What the compiled planners (``rrt_connect``, ``lazy_prm_star``) share, compiled with numba.

* :mod:`.check` — :func:`certified_motion`: whether a straight joint-space motion is
  collision-free over its whole length (probe states, batched state checks with early exit,
  the Lipschitz certificate where a state is near), with its workspaces (:func:`workspaces`,
  :func:`motion_capacity`) and probes (:func:`probe_collides`, :data:`PROBES`,
  :data:`INTERIOR_PROBES`);
* :mod:`.shortcut` — :func:`shortcut` (random shortcutting, every shortcut certified) and
  :func:`drop_collinear`;
* :mod:`.clock` — :func:`now`, a monotonic clock read inside compiled code (deadlines without
  returning to Python; :func:`clock_address` gives the kernels its address);
* :mod:`.binding` — :func:`scene_arguments`: a scene's arrays as the kernels take them, bound
  once per scene;
* :mod:`.stats` — the statistics array the kernels add to (:data:`~.stats.STAT_NAMES`) and the
  outcomes of a plan (:data:`~.stats.FOUND`, :data:`~.stats.BUDGET`, :data:`~.stats.TIMEOUT`).
"""

from drake_mh.planning.motion.binding import scene_arguments
from drake_mh.planning.motion.check import (INTERIOR_PROBES, PROBES, certified_motion, motion_capacity,
                                            probe_collides, workspaces)
from drake_mh.planning.motion.clock import clock_address, now
from drake_mh.planning.motion.shortcut import arc_lengths, drop_collinear, shortcut
from drake_mh.planning.motion.stats import BUDGET, FOUND, STAT_NAMES, TIMEOUT

__all__ = ["certified_motion", "motion_capacity", "workspaces", "probe_collides", "PROBES", "INTERIOR_PROBES",
           "shortcut", "drop_collinear", "arc_lengths", "now", "clock_address", "STAT_NAMES", "FOUND", "BUDGET",
           "TIMEOUT", "scene_arguments"]
