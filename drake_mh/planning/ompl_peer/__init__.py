"""OMPL as an optional peer: ``ompl_rrtconnect`` and ``ompl_bitstar`` with our collision checker.

OMPL 2.0.1's registry wheel (``pip install ompl``, nanobind bindings; listed in the ``peers``
extra) plans in a real vector state space bounded by the joint limits; its validity function
is :meth:`drake_mh.scene.Scene.collision_free` for one configuration (the problem's
clearances), and its motion validator is :meth:`~drake_mh.scene.Scene.segment_free` (a
certified segment) by default: how the planners are set up is in :mod:`.planners`.

Where ``ompl`` cannot be imported, the methods are absent from
:data:`drake_mh.planning.methods.METHODS` (a study then reports them as unavailable);
:data:`OMPL_AVAILABLE` says which.
"""

try:
    import ompl.base  # noqa: F401
    import ompl.geometric  # noqa: F401
    import ompl.util  # noqa: F401
except ImportError:  # the optional peer is not installed
    OMPL_AVAILABLE = False
else:
    OMPL_AVAILABLE = True
    from drake_mh.planning.ompl_peer import planners  # noqa: F401

__all__ = ["OMPL_AVAILABLE"]
