"""Stable case keys, file-safe case ids and per-case seeds.

A case's seed depends only on the study seed and the case's key (its grid values), never
on the order in which cases run or on how many workers run them.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Mapping

import numpy as np

_UNSAFE = re.compile(r"[^A-Za-z0-9._=-]+")


def case_key(params: Mapping[str, object], exclude: tuple[str, ...] = ()) -> str:
    """Returns the stable text key of a case, e.g. ``robot=panda/method=pso/rep=3``.

    Args:
        params: the case's grid values, in grid key order.
        exclude: keys left out (e.g. the method key, for the instance key).

    Returns:
        ``key=value`` pairs joined by ``/``; values formatted with ``repr`` for floats so
        that the text (and hence the seed) is exact.
    """
    parts = []
    for name, value in params.items():
        if name in exclude:
            continue
        text = repr(value) if isinstance(value, float) else str(value)
        parts.append(f"{name}={text}")
    return "/".join(parts)


def _digest_words(text: str) -> tuple[int, ...]:
    digest = hashlib.sha256(text.encode("utf-8")).digest()
    return tuple(int.from_bytes(digest[i : i + 4], "little") for i in range(0, 32, 4))


def derive_seed(study_seed: int, key: str) -> int:
    """Derives a 63-bit seed from the study seed and a case key.

    Uses ``numpy.random.SeedSequence(entropy=study_seed, spawn_key=sha256(key) words)``.

    Args:
        study_seed: the study's seed (non-negative int).
        key: the case key (see :func:`case_key`).

    Returns:
        A non-negative int below 2**63, suitable for ``numpy.random.default_rng``.
    """
    sequence = np.random.SeedSequence(entropy=int(study_seed), spawn_key=_digest_words(key))
    return int(sequence.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))


def case_id(key: str) -> str:
    """Returns a file-name-safe, unique id for a case key (readable prefix + 10 hex digits)."""
    readable = _UNSAFE.sub("_", key.replace("/", "__"))[:60].strip("_") or "case"
    return f"{readable}-{hashlib.sha256(key.encode('utf-8')).hexdigest()[:10]}"
