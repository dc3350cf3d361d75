"""Vectorized benchmark functions: shifted / rotated classics and a CEC 2017 subset.

Every function maps a population ``X (P, D)`` to ``(P,)`` and is built the CEC way
(Awad, Ali, Liang, Qu, Suganthan, "Problem Definitions and Evaluation Criteria for the
CEC 2017 Special Session and Competition on Single Objective Real-Parameter Numerical
Optimization", Tech. Rep., 2016)::

    z = M (s (x - o)) + post,     f(x) = g(z) + f_bias

with the optimum ``o`` (the *shift*), an orthogonal rotation ``M`` (identity when not
rotated), a scale ``s`` mapping the box onto the base function's natural domain, and
``g`` the base function with its minimum ``g = 0`` at ``z = 0``.

Centre bias (Kudela, Nature Machine Intelligence 4:1239, 2022): an *unshifted* function
(``shift="none"``) has its optimum at the origin = the centre of a symmetric box; the
ratio of errors shifted / unshifted exposes algorithms that are drawn to the origin.

CEC 2017 (:func:`cec2017`): the simple functions F1 (bent cigar), F3 (Zakharov),
F4 (Rosenbrock), F5 (Rastrigin), F9 (Levy) and F10 (Schwefel) - a representative subset of
unimodal and multimodal ones - implemented from the report and the organisers' C code
(``cec17_func.cpp``: scales 2.048/100 Rosenbrock, 5.12/100 Rastrigin, 1000/100 Schwefel,
1 otherwise; bias 100 x function number). F2 was withdrawn by the organisers; F6-F8,
hybrid and composition functions are not implemented. Shift vectors and rotation matrices
are the organisers' data files when the optional ``opfunu`` package (extra ``bench``) is
installed - only its data files are used: opfunu 1.0.4's own CEC 2017 classes are
renumbered and several differ from the official definitions (Zakharov without the
``0.5 i`` weights, Rastrigin without the 5.12/100 scale, Levy with a 5.12/100 scale,
as reported on opfunu's tracker) - and seeded random ones otherwise (``data="generated"``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drake_mh.errors import InvalidArgument, UnknownMethod

__all__ = [
    "BASE_FUNCTIONS",
    "CEC2017_FUNCTIONS",
    "TestFunction",
    "cec2017",
    "make",
    "official_cec2017_data",
    "random_rotation",
    "random_shift",
]

# --- base functions g(Z (P, D)) -> (P,), minimum 0 at Z = 0 ---------------------------------


def sphere(Z: np.ndarray) -> np.ndarray:
    """Sphere ``sum z_i^2``."""
    return np.einsum("pd,pd->p", Z, Z)


def ellipsoid(Z: np.ndarray) -> np.ndarray:
    """High-conditioned elliptic ``sum 10^(6 i/(D-1)) z_i^2`` (CEC ``ellips_func``)."""
    D = Z.shape[1]
    w = 10.0 ** (6.0 * np.arange(D) / max(D - 1, 1))
    return (Z * Z) @ w


def bent_cigar(Z: np.ndarray) -> np.ndarray:
    """Bent cigar ``z_1^2 + 10^6 sum_{i>1} z_i^2`` (CEC 2017 F1)."""
    return Z[:, 0] ** 2 + 1e6 * np.einsum("pd,pd->p", Z[:, 1:], Z[:, 1:])


def zakharov(Z: np.ndarray) -> np.ndarray:
    """Zakharov ``sum z^2 + (sum 0.5 i z_i)^2 + (sum 0.5 i z_i)^4`` (CEC 2017 F3)."""
    s = Z @ (0.5 * np.arange(1, Z.shape[1] + 1))
    return np.einsum("pd,pd->p", Z, Z) + s ** 2 + s ** 4


def rosenbrock(Z: np.ndarray) -> np.ndarray:
    """Rosenbrock, shifted by +1 inside so that the minimum is at ``z = 0`` (CEC 2017 F4)."""
    Y = Z + 1.0
    a, b = Y[:, :-1], Y[:, 1:]
    return np.sum(100.0 * (a * a - b) ** 2 + (a - 1.0) ** 2, axis=1)


def rastrigin(Z: np.ndarray) -> np.ndarray:
    """Rastrigin ``sum z^2 - 10 cos(2 pi z) + 10`` (CEC 2017 F5)."""
    return np.sum(Z * Z - 10.0 * np.cos(2.0 * np.pi * Z) + 10.0, axis=1)


def levy(Z: np.ndarray) -> np.ndarray:
    """Levy with ``w = 1 + z/4`` (CEC 2017 F9)."""
    W = 1.0 + Z / 4.0
    head = np.sin(np.pi * W[:, 0]) ** 2
    body = np.sum((W[:, :-1] - 1.0) ** 2 * (1.0 + 10.0 * np.sin(np.pi * W[:, :-1] + 1.0) ** 2), axis=1)
    tail = (W[:, -1] - 1.0) ** 2 * (1.0 + np.sin(2.0 * np.pi * W[:, -1]) ** 2)
    return head + body + tail


_SCHWEFEL_SHIFT = 4.209687462275036e002
_SCHWEFEL_BIAS = 4.189828872724338e002


def schwefel(Z: np.ndarray) -> np.ndarray:
    """Modified Schwefel of CEC 2014/2017 (F10), minimum ~0 at ``z = 0``."""
    Y = Z + _SCHWEFEL_SHIFT
    D = Z.shape[1]
    m = np.fmod(np.abs(Y), 500.0)
    inside = -Y * np.sin(np.sqrt(np.abs(Y)))
    over = -(500.0 - m) * np.sin(np.sqrt(500.0 - m)) + ((Y - 500.0) / 100.0) ** 2 / D
    under = -(-500.0 + m) * np.sin(np.sqrt(500.0 - m)) + ((Y + 500.0) / 100.0) ** 2 / D
    val = np.where(Y > 500.0, over, np.where(Y < -500.0, under, inside))
    return np.sum(val, axis=1) + _SCHWEFEL_BIAS * D


def ackley(Z: np.ndarray) -> np.ndarray:
    """Ackley ``-20 exp(-0.2 sqrt(mean z^2)) - exp(mean cos 2 pi z) + 20 + e``."""
    D = Z.shape[1]
    a = np.sqrt(np.einsum("pd,pd->p", Z, Z) / D)
    b = np.sum(np.cos(2.0 * np.pi * Z), axis=1) / D
    return -20.0 * np.exp(-0.2 * a) - np.exp(b) + 20.0 + math.e


def griewank(Z: np.ndarray) -> np.ndarray:
    """Griewank ``1 + sum z^2 / 4000 - prod cos(z_i / sqrt(i))``."""
    D = Z.shape[1]
    return 1.0 + np.einsum("pd,pd->p", Z, Z) / 4000.0 - np.prod(np.cos(Z / np.sqrt(np.arange(1, D + 1))), axis=1)


#: name -> (g, CEC scale s for the box [-100, 100]^D)
BASE_FUNCTIONS: dict[str, tuple[Callable[[np.ndarray], np.ndarray], float]] = {
    "sphere": (sphere, 1.0),
    "ellipsoid": (ellipsoid, 1.0),
    "bent_cigar": (bent_cigar, 1.0),
    "zakharov": (zakharov, 1.0),
    "rosenbrock": (rosenbrock, 2.048 / 100.0),
    "rastrigin": (rastrigin, 5.12 / 100.0),
    "levy": (levy, 1.0),
    "schwefel": (schwefel, 1000.0 / 100.0),
    "ackley": (ackley, 32.768 / 100.0),
    "griewank": (griewank, 600.0 / 100.0),
}

#: CEC 2017 function number -> base function name (implemented subset)
CEC2017_FUNCTIONS: dict[int, str] = {1: "bent_cigar", 3: "zakharov", 4: "rosenbrock", 5: "rastrigin",
                                     9: "levy", 10: "schwefel"}


@dataclass(frozen=True)
class TestFunction:
    """A shifted (and possibly rotated) vectorized test function.

    Attributes:
        name: e.g. ``"rastrigin"`` or ``"cec2017_f5"``.
        lower: lower bounds ``(D,)``.
        upper: upper bounds ``(D,)``.
        shift: the optimum ``o (D,)`` (in x).
        rotation: orthogonal ``M (D, D)`` or ``None``.
        scale: ``s`` in ``z = M (s (x - o))``.
        f_opt: the optimal value (the bias).
        base: the base function ``g``.
    """

    __test__ = False  # not a pytest class despite its name

    name: str
    lower: np.ndarray
    upper: np.ndarray
    shift: np.ndarray
    rotation: np.ndarray | None
    scale: float
    f_opt: float
    base: Callable[[np.ndarray], np.ndarray] = field(repr=False)

    @property
    def dim(self) -> int:
        """Dimension D."""
        return self.shift.size

    @property
    def bounds(self) -> np.ndarray:
        """``(D, 2)`` box."""
        return np.stack([self.lower, self.upper], axis=1)

    @property
    def x_opt(self) -> np.ndarray:
        """The minimizer ``(D,)``."""
        return self.shift.copy()

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """Objective values ``(P,)`` of ``X (P, D)`` (a single ``(D,)`` point gives ``(1,)``)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        Z = (X - self.shift) * self.scale
        if self.rotation is not None:
            Z = Z @ self.rotation.T
        return self.base(Z) + self.f_opt

    def error(self, f: np.ndarray | float) -> np.ndarray | float:
        """``f - f_opt`` (the quantity benchmarks report)."""
        return f - self.f_opt


def random_rotation(dim: int, rng: np.random.Generator) -> np.ndarray:
    """Haar-random orthogonal ``(D, D)`` matrix (QR of a Gaussian matrix, signs fixed)."""
    A = rng.standard_normal((dim, dim))
    Q, R = np.linalg.qr(A)
    return Q * np.sign(np.diag(R))


def random_shift(lower: np.ndarray, upper: np.ndarray, rng: np.random.Generator,
                 min_offset: float = 0.3, max_offset: float = 0.8) -> np.ndarray:
    """An optimum away from the box centre *and* the origin in every coordinate.

    Each coordinate is ``c +- u h`` with centre ``c``, half-width ``h``, ``u ~ U(min_offset,
    max_offset)`` and a random sign; for a box symmetric about 0 this keeps
    ``|o_i| >= min_offset h``.
    """
    c, h = (upper + lower) / 2.0, (upper - lower) / 2.0
    u = rng.uniform(min_offset, max_offset, size=c.shape)
    sign = np.where(rng.random(c.shape) < 0.5, -1.0, 1.0)
    return c + sign * u * h


def make(name: str, dim: int, shift: str | np.ndarray = "random", rotate: bool = False,
         seed: int = 0, lower: float = -100.0, upper: float = 100.0, f_opt: float = 0.0) -> TestFunction:
    """Builds a shifted / rotated classic test function on the box ``[lower, upper]^D``.

    Args:
        name: one of :data:`BASE_FUNCTIONS`.
        dim: dimension D >= 2.
        shift: ``"random"`` (seeded, away from centre and origin, :func:`random_shift`),
            ``"none"`` (optimum at the origin) or an explicit ``(D,)`` optimum.
        rotate: apply a seeded random rotation.
        seed: seed of the shift and rotation.
        lower: lower bound of every coordinate.
        upper: upper bound of every coordinate.
        f_opt: value at the optimum.

    Raises:
        UnknownMethod: unknown name.
        InvalidArgument: bad dimension, box or shift.
    """
    if name not in BASE_FUNCTIONS:
        raise UnknownMethod(name, BASE_FUNCTIONS, what="test function")
    if not isinstance(dim, (int, np.integer)) or dim < 2:
        raise InvalidArgument(f"test functions need an integer dim >= 2; got {dim!r}")
    if not lower < upper:
        raise InvalidArgument(f"need lower < upper; got [{lower}, {upper}]")
    g, s100 = BASE_FUNCTIONS[name]
    lo, hi = np.full(dim, float(lower)), np.full(dim, float(upper))
    scale = s100 * 100.0 / (0.5 * (upper - lower))  # map the box half-width onto 100
    rng = np.random.default_rng([seed, dim, sorted(BASE_FUNCTIONS).index(name)])
    if isinstance(shift, str):
        if shift == "random":
            o = random_shift(lo, hi, rng)
        elif shift == "none":
            o = np.zeros(dim)
        else:
            raise InvalidArgument(f"shift must be 'random', 'none' or a (D,) array; got {shift!r}")
    else:
        o = np.asarray(shift, dtype=float).reshape(-1)
        if o.shape != (dim,) or np.any(o < lo) or np.any(o > hi):
            raise InvalidArgument(f"an explicit shift must be a ({dim},) point inside the box")
    M = random_rotation(dim, rng) if rotate else None
    unshifted = isinstance(shift, str) and shift == "none"
    tag = ("" if unshifted else "shifted_") + ("rotated_" if rotate else "")
    return TestFunction(f"{tag}{name}", lo, hi, o, M, scale, float(f_opt), g)


def _opfunu_data_dir() -> Path | None:
    try:
        import opfunu  # noqa: F401  (optional extra "bench")
    except ImportError:
        return None
    import opfunu as _op

    d = Path(_op.__file__).parent / "cec_based" / "data_2017"
    return d if d.is_dir() else None


def official_cec2017_data(dim: int) -> bool:
    """Whether the organisers' CEC 2017 data files for dimension ``dim`` are installed."""
    folder = _opfunu_data_dir()
    return folder is not None and (folder / f"M_1_D{dim}.txt").is_file()


def cec2017(number: int, dim: int, data: str = "auto", seed: int = 0) -> TestFunction:
    """A CEC 2017 simple function of the implemented subset, box ``[-100, 100]^D``.

    Args:
        number: function number, one of :data:`CEC2017_FUNCTIONS` (1, 3, 4, 5, 9, 10).
        dim: dimension (2, 10, 20, 30, 50 or 100 with the official data).
        data: ``"official"`` (the organisers' shift/rotation files, needs ``opfunu``),
            ``"generated"`` (seeded: shift U(-80, 80)^D, Haar rotation) or ``"auto"``
            (official if available).
        seed: seed of the generated data.

    Returns:
        TestFunction with ``f_opt = 100 * number``.

    Raises:
        UnknownMethod: a function number outside the subset.
        InvalidArgument: unavailable data or dimension.
    """
    if number not in CEC2017_FUNCTIONS:
        raise UnknownMethod(str(number), [str(k) for k in CEC2017_FUNCTIONS], what="CEC 2017 function")
    name = CEC2017_FUNCTIONS[number]
    g, scale = BASE_FUNCTIONS[name]
    if data not in ("auto", "official", "generated"):
        raise InvalidArgument(f"data must be 'auto', 'official' or 'generated'; got {data!r}")
    folder = _opfunu_data_dir() if data in ("auto", "official") else None
    mfile = folder / f"M_{number}_D{dim}.txt" if folder is not None else None
    if data == "official" and (mfile is None or not mfile.is_file()):
        raise InvalidArgument(
            f"official CEC 2017 data for F{number}, D = {dim} not available: install the extra "
            "'bench' (pip install drake_mh[bench]) and use D in (2, 10, 20, 30, 50, 100), "
            "or pass data='generated'"
        )
    if mfile is not None and mfile.is_file():
        o = np.loadtxt(folder / f"shift_data_{number}.txt", ndmin=2)[0, :dim]
        M = np.loadtxt(mfile).reshape(dim, dim)
    else:
        rng = np.random.default_rng([seed, dim, number, 2017])
        o = rng.uniform(-80.0, 80.0, dim)
        M = random_rotation(dim, rng)
    lo, hi = np.full(dim, -100.0), np.full(dim, 100.0)
    return TestFunction(f"cec2017_f{number}", lo, hi, o, M, scale, 100.0 * number, g)
