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
"""
