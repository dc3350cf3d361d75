"""Exact re-expansion of polynomial coefficients, shared by :mod:`.trajectory` and :mod:`.export`."""

from __future__ import annotations

from math import comb

import numpy as np

__all__ = ["shift_coefficients"]


def shift_coefficients(c: np.ndarray, shift: float) -> np.ndarray:
    """Re-expand polynomial coefficients (highest power first, scipy layout) about ``x0 + shift``.

    Args:
        c: ``(k+1, ...)`` coefficients of ``Σ c[m] (x - x0)^(k-m)``.
        shift: new expansion point minus ``x0``.

    Returns:
        ``(k+1, ...)`` coefficients of the same polynomial in powers of ``(x - x0 - shift)``.
    """
    k = c.shape[0] - 1
    out = np.zeros_like(c)
    for m in range(k + 1):  # power p = k - m of the original term
        p = k - m
        for j in range(p + 1):  # (y + shift)^p = Σ_j C(p, j) y^j shift^(p - j)
            out[k - j] += c[m] * comb(p, j) * shift ** (p - j)
    return out
