"""The kernels' one generator (drake_mh._support.random) against a plain-Python SplitMix64
(Steele, Lea & Flood 2014; Vigna's reference ``splitmix64.c``), both of its uses alike."""

from __future__ import annotations

import numpy as np

from drake_mh._support.random import below, next_u64, uniform, uniform_at

MASK = (1 << 64) - 1


def splitmix64(seed: int, count: int) -> list[int]:
    """Vigna's reference, in Python integers."""
    out, x = [], seed
    for _ in range(count):
        x = (x + 0x9E3779B97F4A7C15) & MASK
        z = x
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
        out.append(z ^ (z >> 31))
    return out


def test_the_stream_is_splitmix64():
    for seed in (0, 7, 1234567, MASK):
        state = np.array([seed], dtype=np.uint64)
        assert [int(next_u64(state)) for _ in range(50)] == splitmix64(seed, 50)
        assert int(state[0]) == (seed + 50 * 0x9E3779B97F4A7C15) & MASK


def test_uniform_takes_the_top_53_bits_and_both_uses_draw_the_same_numbers():
    seed = 20240605
    state = np.array([seed], dtype=np.uint64)
    bits = [int(uniform(state) * 2.0**53) for _ in range(1000)]  # exact: 53-bit integers times 2^-53
    assert bits == [z >> 11 for z in splitmix64(seed, 1000)]
    assert bits == [int(uniform_at(np.uint64(seed), n) * 2.0**53) for n in range(1000)]


def test_uniform_and_below_are_uniform():
    state = np.array([7], dtype=np.uint64)
    u = np.array([uniform(state) for _ in range(20_000)])
    assert u.min() >= 0.0 and u.max() < 1.0
    counts = np.histogram(u, bins=10, range=(0, 1))[0]
    assert np.all(np.abs(counts - 2000) < 5 * np.sqrt(2000))  # chi-square-sized deviations only
    k = np.array([below(state, 7) for _ in range(14_000)])
    assert set(k.tolist()) == set(range(7))
    assert np.all(np.abs(np.bincount(k) - 2000) < 5 * np.sqrt(2000))
    other = np.array([uniform_at(np.uint64(8), n) for n in range(1000)])
    assert abs(np.corrcoef(u[:1000], other)[0, 1]) < 0.1  # another seed, another stream
