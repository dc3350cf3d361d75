"""The scene's compiled kernels (numba), one module per thing they compute.

* :mod:`.collision` — batched collision and clearance of configurations against the obstacles
  (sphere model, bounding spheres, closed-form distances);
* :mod:`.entry` — their entry points from Python (one configuration, packed arrays);
* :mod:`.states` — the planners' early-exit state check with margins;
* :mod:`.pairs` — self-collision sphere pairs and their floors;
* :mod:`.segments` — certified segments (Lipschitz bisection);
* :mod:`.exact` and :mod:`.gjk` — exact distances and certified GJK;
* :mod:`.packing` — a scene's arrays packed into two buffers; :mod:`.context` — those arrays
  and a workspace behind one pointer.

What compiled planners may use (the names below; their arrays come from
:meth:`drake_mh.scene.Scene.planner_binding` and :attr:`~drake_mh.scene.Scene.collision_model`):

* :func:`unpack` the scene's two packed buffers into its arrays, and :class:`CheckContext`
  to hold them with a workspace;
* :func:`collision_free` — configurations free of collision (boolean, batched);
* :func:`state_workspace`, :func:`check_states`, :func:`check_blocks` — the early-exit state
  check with per-link and per-pair margins, its answers :data:`CLEAR`, :data:`NEAR`,
  :data:`COLLISION`;
* :func:`certify_segments` (:data:`CERTIFIED`) and :func:`segment_floor` — certified segments
  and a self-collision pair's certified floor along one.
"""

from drake_mh.scene.kernels.collision import collision_free
from drake_mh.scene.kernels.context import CheckContext
from drake_mh.scene.kernels.packing import unpack
from drake_mh.scene.kernels.pairs import segment_floor
from drake_mh.scene.kernels.segments import CERTIFIED, certify_segments
from drake_mh.scene.kernels.states import CLEAR, COLLISION, NEAR, check_blocks, check_states, state_workspace

__all__ = ["CheckContext", "unpack", "collision_free", "state_workspace", "check_states", "check_blocks", "CLEAR",
           "NEAR", "COLLISION", "certify_segments", "CERTIFIED", "segment_floor"]
