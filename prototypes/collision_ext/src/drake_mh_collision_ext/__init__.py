"""Prototype: drake_mh's batched collision_free (obstacles only) compiled at install."""
from drake_mh_collision_ext._collision_ext import collision_free_packed

__all__ = ["collision_free_packed"]
