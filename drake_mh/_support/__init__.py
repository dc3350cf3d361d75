"""The package's plumbing, shared by every sub-package (private to drake_mh; not a user API).

* :mod:`.cache` — the on-disk cache folder, atomic writes, content hashes;
* :mod:`.numba_cache` — numba's cache kept in a folder named by the kernels' sources
  (configured by ``drake_mh/__init__.py`` before any kernel is imported);
* :mod:`.native` — the compiled core (C++), where it is built;
* :mod:`.borrow` — arrays borrowed from a buffer inside compiled code.
"""
