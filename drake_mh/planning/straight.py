"""``straight``: the straight joint-space line from the start to the nearest goal configuration.

The baseline every planner must beat: it succeeds exactly when that one segment is certified
collision-free (what users often execute without checking).
"""

from __future__ import annotations

import numpy as np

from drake_mh.errors import InvalidArgument

def plan(problem, goals, rng, deadline, budget, **options):
    """The straight line from ``problem.q_start`` to the nearest row of ``goals`` (no options)."""
    if options:
        raise InvalidArgument(f"straight: unknown option(s) {sorted(options)}; it takes none")
    i = int(np.argmin(np.linalg.norm(goals - problem.q_start, axis=1)))
    return np.stack([problem.q_start, goals[i]]), {"goal": i}
