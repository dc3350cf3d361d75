"""``straight``: the straight joint-space line from the start to the nearest goal configuration.

The baseline every planner must beat: it succeeds exactly when that one segment is certified
collision-free (what users often execute without checking).
"""

from __future__ import annotations

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.planning.solve import register


@register("straight", "the straight joint-space line to the nearest goal configuration (baseline)")
def plan(problem, goals, rng, deadline, budget, **options):
    if options:
        raise InvalidArgument(f"straight: unknown option(s) {sorted(options)}; it takes none")
    i = int(np.argmin(np.linalg.norm(goals - problem.q_start, axis=1)))
    return np.stack([problem.q_start, goals[i]]), {"goal": i}
