"""Ask/tell base class, result type and argument checks shared by every optimizer.

Every optimizer minimizes a *vectorized* objective ``f(X (P, D)) -> (P,)`` over a box
``lower <= x <= upper`` with an exact budget of function evaluations (nfe) and a seeded
:class:`numpy.random.Generator`. The protocol is ask/tell::

    opt = PSO(bounds, budget=5000, seed=1)
    while not opt.done:
        X = opt.ask()                       # (k, D) candidates
        X = X[: opt.budget - opt.nfe]       # never exceed the budget (last generation)
        opt.tell(X, f(X))
    opt.result()

:func:`drake_mh.optim.minimize` runs exactly this loop (plus target / callback / timing),
so an ask/tell run with the same seed is bit-identical to a ``minimize`` run.

Conventions shared by all algorithms (each docstring states the rest):

* ``NaN`` objective values are treated as ``+inf`` (worst), never as best. ``-inf`` is the
  minimum there is: the tell that reports it makes it the best point and ends the run (the
  algorithm's own state never sees it, so its arithmetic stays finite).
* ``t/T`` in the papers' schedules is the used fraction of the budget ``nfe / budget``
  (:meth:`Optimizer.progress`); for a fixed population this equals iteration / max_iter.
* A *partial* tell (fewer rows than were asked: the truncated last generation) updates
  the best-so-far point, ``nfe`` and the history but not the algorithm's state; the run
  is then over (:attr:`Optimizer.done`).
* ``x0`` rows (clipped into the box) replace the first rows of the initial population.
"""

from __future__ import annotations

import abc
import dataclasses
import logging
import numbers
import time as _time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from drake_mh.errors import AskTellError, InvalidArgument, InvalidObjective
from drake_mh.optim.population import distinct_indices

logger = logging.getLogger(__name__)

__all__ = [
    "Optimizer",
    "OptimizeResult",
    "summarize_array",
    "OptimizerState",
    "as_bounds",
    "check_budget",
    "check_x0",
    "evaluate",
]


@dataclass(frozen=True)
class OptimizeResult:
    """Outcome of one optimizer run.

    Attributes:
        x: best point found, shape ``(D,)``.
        f: objective value at ``x``.
        nfe: function evaluations used (never more than the budget).
        nit: completed generations (full tells after the initial population included).
        time: wall-clock time of the run [s] (objective included).
        message: why the run stopped: ``"budget exhausted"``, ``"target reached"`` or
            ``"stopped by callback"``.
        history: ``(K, 2)`` array of ``(nfe, best-so-far f)`` after every tell.
        method: the method name.
        seed: the seed the run was started with.
        population: the last population ``(P, D)`` (for warm starts), or ``None``.
        population_f: objective values of ``population`` ``(P,)``, or ``None``.
    """

    x: np.ndarray
    f: float
    nfe: int
    nit: int
    time: float
    message: str
    history: np.ndarray
    method: str = ""
    seed: Any = None
    population: np.ndarray | None = None
    population_f: np.ndarray | None = None

    @property
    def success(self) -> bool:
        """``True`` when the run ended because the target was reached."""
        return self.message == "target reached"

    def __repr__(self) -> str:
        """A few lines: method, f, nfe, nit, time, ``x`` summarized (not the history's rows)."""
        x = np.asarray(self.x)
        pop = "" if self.population is None else f", last population {np.shape(self.population)}"
        return (f"OptimizeResult(method={self.method!r}, seed={self.seed!r}, message={self.message!r})\n"
                f"  f = {self.f:.6g}, nfe = {self.nfe}, nit = {self.nit}, time = {self.time:.3g} s\n"
                f"  x = {summarize_array(x)} (D = {x.size})\n"
                f"  history: {len(self.history)} rows (nfe, best f){pop}")

    __str__ = __repr__


def summarize_array(a, edgeitems: int = 3, precision: int = 4) -> str:
    """One line for an array of any length: its first and last ``edgeitems`` values beyond 8."""
    return np.array2string(np.asarray(a), precision=precision, threshold=8, edgeitems=edgeitems,
                           separator=", ", max_line_width=10_000).replace("\n", "")


@dataclass(frozen=True)
class OptimizerState:
    """What a ``callback`` sees after each tell (read-only snapshot).

    Attributes:
        nfe: evaluations used so far.
        nit: completed generations.
        best_x: best point so far ``(D,)``.
        best_f: best value so far.
        X: the last evaluated candidates ``(k, D)``.
        F: their values ``(k,)``.
    """

    nfe: int
    nit: int
    best_x: np.ndarray
    best_f: float
    X: np.ndarray
    F: np.ndarray


# --- argument checks -------------------------------------------------------------------


def as_bounds(bounds: Any) -> tuple[np.ndarray, np.ndarray]:
    """Converts ``bounds`` to ``(lower (D,), upper (D,))`` float arrays.

    Args:
        bounds: a ``(D, 2)`` array-like of ``[lower, upper]`` rows; or a *tuple*
            ``(lower, upper)`` of two length-``D`` sequences; or an object with
            ``lb``/``ub`` attributes (``scipy.optimize.Bounds``).

    Raises:
        InvalidArgument: wrong shape, non-finite values or ``lower >= upper``.
    """
    if hasattr(bounds, "lb") and hasattr(bounds, "ub"):
        lower, upper = np.atleast_1d(bounds.lb), np.atleast_1d(bounds.ub)
    elif isinstance(bounds, tuple) and len(bounds) == 2:
        lower, upper = np.atleast_1d(bounds[0]), np.atleast_1d(bounds[1])
    else:
        try:
            B = np.asarray(bounds, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidArgument(
                f"bounds must be a (D, 2) array of [lower, upper] rows or a tuple (lower, upper); "
                f"could not convert {type(bounds).__name__}: {exc}"
            ) from None
        if B.ndim != 2 or B.shape[1] != 2 or B.shape[0] < 1:
            raise InvalidArgument(
                f"bounds must have shape (D, 2) (one [lower, upper] row per variable) or be a "
                f"tuple (lower, upper); got shape {B.shape}"
            )
        lower, upper = B[:, 0], B[:, 1]
    try:
        lower = np.asarray(lower, dtype=float).ravel().copy()
        upper = np.asarray(upper, dtype=float).ravel().copy()
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"bounds must be numeric: {exc}") from None
    if lower.shape != upper.shape or lower.size < 1:
        raise InvalidArgument(
            f"lower and upper bounds must have the same length D >= 1; got {lower.size} and {upper.size}"
        )
    if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
        raise InvalidArgument("bounds must be finite: every variable needs a finite box [lower, upper]")
    with np.errstate(over="ignore"):
        wide = np.flatnonzero(~np.isfinite(upper - lower))
    if wide.size:
        i = int(wide[0])
        raise InvalidArgument(
            f"bounds of variable {i} ([{lower[i]}, {upper[i]}]) are too wide: upper - lower overflows a "
            "double; rescale the variable so its box spans less than 1e308")
    bad = np.flatnonzero(~(lower < upper))
    if bad.size:
        i = int(bad[0])
        raise InvalidArgument(
            f"bounds need lower < upper for every variable; variable {i} has "
            f"[{lower[i]}, {upper[i]}] ({bad.size} such variable(s)). Swap them, or remove a "
            "fixed variable from the search"
        )
    return lower, upper


def make_rng(seed: Any, what: str = "seed") -> np.random.Generator:
    """``numpy.random.default_rng(seed)``, or :class:`InvalidArgument` naming what was wrong.

    Args:
        seed: ``None``, an integer >= 0, a sequence of such integers, a ``SeedSequence``, a
            ``BitGenerator`` or a ``Generator``.
        what: the argument's name in the message.
    """
    if isinstance(seed, bool) or isinstance(seed, (float, complex, str, bytes)):
        raise InvalidArgument(f"{what} must be an integer >= 0, a numpy SeedSequence/Generator or None; "
                              f"got {seed!r}")
    try:
        return np.random.default_rng(seed)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{what} must be an integer >= 0, a numpy SeedSequence/Generator or None; "
                              f"got {seed!r} ({exc})") from None


def check_seed(seed: Any, what: str = "seed") -> int:
    """``seed`` as an ``int >= 0`` (numpy's integers included), or :class:`InvalidArgument` naming
    ``what``: a float (``1.5`` would be truncated), text, a bool or a negative number."""
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise InvalidArgument(f"{what} must be an integer >= 0, got {seed!r}")
    return int(seed)


MAX_BUDGET = 10**12
"""Largest budget of the IK methods and planners (kernels count it in 64-bit integers, with
headroom for their products)."""


def check_timeout(timeout: Any) -> float | None:
    """``timeout`` [s] as a float in ``(0, inf)``, or ``None`` (no limit); :class:`InvalidArgument`
    for text (``"1"``), a bool, NaN, inf, a number <= 0 or an int beyond a double."""
    if timeout is None:
        return None
    try:
        seconds = float(timeout) if isinstance(timeout, numbers.Real) else float("nan")
    except OverflowError:  # an int beyond a double
        seconds = float("nan")
    if isinstance(timeout, bool) or not 0 < seconds < float("inf"):
        raise InvalidArgument(f"timeout must be a positive, finite number of seconds or None (no limit); "
                              f"got {str(timeout)[:40]!r}")
    return seconds


def check_budget(budget: Any) -> int:
    """Returns ``budget`` as an ``int >= 1`` or raises :class:`InvalidArgument`."""
    try:
        whole = not isinstance(budget, bool) and isinstance(budget, numbers.Real) and float(budget).is_integer()
    except OverflowError:  # an int beyond a double
        whole = False
    if not whole:
        raise InvalidArgument(
            f"budget is a number of function evaluations and must be an integer >= 1; got {str(budget)[:40]}"
        )
    if budget < 1:
        raise InvalidArgument(f"budget must be >= 1 function evaluation; got {budget}")
    return int(budget)


def check_x0(x0: Any, lower: np.ndarray, upper: np.ndarray) -> np.ndarray | None:
    """Returns the seed points as a ``(K, D)`` array clipped into the box, or ``None``.

    Raises:
        InvalidArgument: wrong shape or non-finite values.
    """
    if x0 is None:
        return None
    try:
        X0 = np.array(x0, dtype=float, ndmin=2)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"x0 must be numeric with shape (D,) or (K, D): {exc}") from None
    D = lower.size
    if X0.ndim != 2 or X0.shape[1] != D or X0.shape[0] < 1:
        raise InvalidArgument(f"x0 must have shape ({D},) or (K, {D}); got {np.shape(x0)}")
    if not np.all(np.isfinite(X0)):
        raise InvalidArgument("x0 must be finite")
    clipped = np.clip(X0, lower, upper)
    if np.any(clipped != X0):
        logger.warning("x0 lies partly outside the bounds; clipped into the box")
    return clipped


def evaluate(f: Callable[[np.ndarray], Any], X: np.ndarray) -> np.ndarray:
    """Calls the vectorized objective and checks that it returned ``(P,)`` numbers.

    Raises:
        InvalidObjective: the objective returned a wrong shape, a non-numeric or a complex value.
    """
    X_view = X.view()
    X_view.flags.writeable = False  # an objective must not change the candidates it scores
    try:
        F = f(X_view)
    except ValueError as exc:
        if "read-only" not in str(exc):
            raise
        raise InvalidObjective(
            "the objective modified the population X in place (it is read-only, so that the "
            "returned x is the point that scored f); work on a copy, e.g. X = X.copy()"
        ) from exc
    try:
        complex_ = np.iscomplexobj(F)
        F = F if complex_ else np.asarray(F, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidObjective(
            f"the objective must return a float array of shape ({len(X)},); conversion failed: {exc}"
        ) from None
    if complex_:  # numpy would keep the real part with only a warning
        raise InvalidObjective(
            "the objective returned complex values; it must return real numbers (take np.real or "
            "np.abs of them if that is what you minimize)")
    if F.shape != (len(X),):
        if F.size == len(X) and F.ndim == 2:
            F = F.reshape(-1)
        else:
            raise InvalidObjective(
                f"the objective takes a population X of shape (P, D) and must return shape (P,); "
                f"for P = {len(X)} it returned shape {F.shape}. Vectorize it over the rows of X "
                "(e.g. np.sum(X**2, axis=1))"
            )
    return F


# --- base class --------------------------------------------------------------------------


@dataclass(frozen=True)
class NoParams:
    """Hyper-parameters of an algorithm that has none."""


class Optimizer(abc.ABC):
    """Ask/tell base class.

    Subclasses define ``name``, ``Config`` (a frozen dataclass of hyper-parameters with the
    papers' defaults), ``default_pop_size(D)``, ``min_pop_size``, and implement
    :meth:`_start` (set up after construction), :meth:`_ask` and :meth:`_tell`.

    Args:
        bounds: box, see :func:`as_bounds`.
        budget: function evaluations the run may use (schedules use it as their horizon).
        seed: seed of :func:`numpy.random.default_rng` (an int, a ``SeedSequence`` or ``None``).
        pop_size: population size; ``None`` uses the algorithm's default.
        x0: ``(D,)`` or ``(K, D)`` points injected into the initial population.
        **params: hyper-parameters, the fields of ``Config``.

    Raises:
        InvalidArgument: bad bounds, budget, population size, x0 or hyper-parameter.
    """

    name: ClassVar[str] = ""
    Config: ClassVar[type] = NoParams
    min_pop_size: ClassVar[int] = 1

    def __init__(self, bounds: Any, budget: int, seed: Any = None, pop_size: int | None = None,
                 x0: Any = None, **params: Any):
        self.lower, self.upper = as_bounds(bounds)
        self.width = self.upper - self.lower
        self.dim = self.lower.size
        self.budget = check_budget(budget)
        self.seed = seed
        self.rng = make_rng(seed)
        self.config = self._make_config(params)
        if pop_size is None:
            pop_size = self.default_pop_size(self.dim)
        if isinstance(pop_size, bool) or not isinstance(pop_size, numbers.Integral) or pop_size < self.min_pop_size:
            raise InvalidArgument(
                f"pop_size of {self.name!r} must be an integer >= {self.min_pop_size}; got {pop_size!r}"
            )
        self.pop_size = int(pop_size)
        self.x0 = check_x0(x0, self.lower, self.upper)
        if self.x0 is not None and len(self.x0) > self.pop_size:
            raise InvalidArgument(
                f"x0 has {len(self.x0)} points but the population holds {self.pop_size}; pass at "
                f"most pop_size points or raise pop_size to >= {len(self.x0)}"
            )
        self.nfe = 0
        self.nit = 0
        self.best_x = np.full(self.dim, np.nan)
        self.best_f = np.inf
        self._history: list[tuple[int, float]] = []
        self._pending: np.ndarray | None = None
        self._truncated = False
        self._start()

    # -- configuration --------------------------------------------------------------------

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        """Default population size for dimension ``dim`` (overridden per algorithm)."""
        return 50

    @classmethod
    def _make_config(cls, params: dict[str, Any]):
        names = [f.name for f in dataclasses.fields(cls.Config)]
        unknown = sorted(set(params) - set(names))
        if unknown:
            raise InvalidArgument(
                f"unknown parameter(s) {unknown} for method {cls.name!r}; valid parameters: "
                f"{', '.join(names) if names else '(none)'}"
            )
        return cls.Config(**params)

    # -- protocol --------------------------------------------------------------------------

    @property
    def done(self) -> bool:
        """``True`` when the budget is used up, the last tell was partial, or a value was -inf."""
        return self.nfe >= self.budget or self._truncated or self.best_f == -np.inf

    def progress(self) -> float:
        """Used fraction of the budget, ``t/T`` of the papers' schedules, in ``[0, 1]``."""
        return self.nfe / self.budget

    def ask(self) -> np.ndarray:
        """Returns the next candidates ``X (k, D)`` to evaluate (all inside the box).

        Raises:
            AskTellError: ``ask`` twice without ``tell``, or the run is over.
        """
        if self._pending is not None:
            raise AskTellError("ask() called twice: tell() the values of the previous candidates first")
        if self.done:
            raise AskTellError(
                f"the run is over (nfe = {self.nfe} of budget {self.budget}"
                f"{', last tell was partial' if self._truncated else ''}"
                f"{', a value was -inf' if self.best_f == -np.inf else ''}); read result()"
            )
        X = self._ask()
        self._pending = X
        return X

    def tell(self, X: np.ndarray, F: Any) -> None:
        """Reports the objective values ``F (k,)`` of the first ``k`` asked rows ``X (k, D)``.

        ``k`` smaller than asked (budget truncation) ends the run.

        Raises:
            AskTellError: no pending ask, or ``X``/``F`` do not match the asked candidates.
        """
        pending = self._pending
        if pending is None:
            raise AskTellError("tell() without a pending ask(): call ask() first")
        if np.iscomplexobj(F):
            raise InvalidObjective("tell() got complex values; objective values must be real numbers")
        F = np.asarray(F, dtype=float).reshape(-1)
        k = F.shape[0]
        if k > len(pending) or np.shape(X) != (k, self.dim):
            raise AskTellError(
                f"tell() expects the first k <= {len(pending)} asked rows X (k, {self.dim}) and their "
                f"values F (k,); got X {np.shape(X)} and F ({k},)"
            )
        if not np.array_equal(X, pending[:k], equal_nan=True):
            raise AskTellError(
                "tell() got other candidates than ask() returned: report the values of the asked "
                "rows X, unchanged and in order")
        if k > self.budget - self.nfe:
            raise AskTellError(
                f"telling {k} values would exceed the budget ({self.budget - self.nfe} evaluations left)"
            )
        self._pending = None
        self.nfe += k
        if k:
            i = int(F.argmin())            # argmin returns the first NaN if there is one
            fi = F[i]
            if fi != fi:                   # NaN counts as +inf (worst), never as best
                F = np.where(np.isnan(F), np.inf, F)
                i = int(F.argmin())
                fi = F[i]
            if fi < self.best_f:
                self.best_f = float(fi)
                self.best_x = pending[i].copy()
        self._history.append((self.nfe, self.best_f))
        if k < len(pending):
            self._truncated = True
            return
        if self.best_f == -np.inf:  # the minimum there is: the run is over (done)
            return
        self._tell(pending, F)
        self.nit += 1

    def result(self, time: float = 0.0, message: str | None = None) -> OptimizeResult:
        """The best point found so far as an :class:`OptimizeResult`."""
        if message is None:
            message = "budget exhausted" if self.nfe >= self.budget else "stopped"
        pop, pop_f = self.population()
        return OptimizeResult(
            x=self.best_x.copy(),
            f=float(self.best_f),
            nfe=int(self.nfe),
            nit=int(self.nit),
            time=float(time),
            message=message,
            history=np.array(self._history, dtype=float).reshape(-1, 2),
            method=self.name,
            seed=self.seed,
            population=pop,
            population_f=pop_f,
        )

    def population(self) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The current population ``(P, D)`` and its values ``(P,)`` (``None`` if not kept)."""
        X = getattr(self, "X", None)
        F = getattr(self, "F", None)
        if X is None or F is None:
            return None, None
        return np.array(X, copy=True), np.array(F, copy=True)

    # -- helpers for subclasses --------------------------------------------------------------

    def initial_population(self, n: int | None = None) -> np.ndarray:
        """Uniform random ``(n, D)`` points in the box with ``x0`` in the first rows."""
        n = self.pop_size if n is None else n
        X = self.lower + self.rng.random((n, self.dim)) * self.width
        if self.x0 is not None:
            k = min(len(self.x0), n)
            X[:k] = self.x0[:k]
        return X

    def clip(self, X: np.ndarray) -> np.ndarray:
        """Projects ``X (k, D)`` onto the box (in place)."""
        np.maximum(X, self.lower, out=X)
        return np.minimum(X, self.upper, out=X)

    def reflect(self, X: np.ndarray) -> np.ndarray:
        """Mirrors out-of-box components back into the box (repeatedly, so any distance works)."""
        Y = np.mod(X - self.lower, 2.0 * self.width)
        Y = np.where(Y > self.width, 2.0 * self.width - Y, Y)
        R = np.minimum(np.maximum(self.lower + Y, self.lower), self.upper)
        return np.where((X < self.lower) | (X > self.upper), R, X)   # inside: untouched

    def reinit(self, X: np.ndarray) -> np.ndarray:
        """Replaces out-of-box components by uniform random values in their range (in place)."""
        out = (X < self.lower) | (X > self.upper)
        if out.any():
            R = self.lower + self.rng.random(X.shape) * self.width
            X[out] = R[out]
        return X

    def others(self, n: int) -> np.ndarray:
        """For each ``i < n`` a uniformly random index ``j != i`` (vectorized), shape ``(n,)``."""
        return (np.arange(n) + 1 + self.randint(n - 1, n)) % n

    def donors(self, n: int, pool: int, k: int = 3, exclude_self: bool = True) -> np.ndarray:
        """``(n, k)`` indices into ``range(pool)``, distinct within each row; with
        ``exclude_self`` row ``i`` never contains ``i`` (sequential sampling without
        replacement, :func:`~drake_mh.optim.population.distinct_indices`)."""
        return distinct_indices(self.rng.random((n, k)), pool, exclude_self)

    def randint(self, high: int, size) -> np.ndarray:
        """Uniform integers in ``[0, high)`` (``floor(u high)``; 3x faster than ``integers``)."""
        return (self.rng.random(size) * high).astype(np.intp)

    # -- to implement --------------------------------------------------------------------

    @abc.abstractmethod
    def _start(self) -> None:
        """Sets up the algorithm's state (called once at the end of ``__init__``)."""

    @abc.abstractmethod
    def _ask(self) -> np.ndarray:
        """Returns the next candidates (inside the box)."""

    @abc.abstractmethod
    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        """Updates the state with the values ``F (k,)`` of all asked candidates ``X (k, D)``."""


def run(opt: Optimizer, f: Callable[[np.ndarray], Any], target: float | None = None,
        callback: Callable[[OptimizerState], Any] | None = None) -> OptimizeResult:
    """Runs an ask/tell optimizer to its budget (or target / callback stop)."""
    t0 = _time.perf_counter()
    message = "budget exhausted"
    budget = opt.budget
    if target is not None and not isinstance(target, numbers.Real):
        raise InvalidArgument(f"target must be a number or None; got {target!r}")
    while not opt.done:
        X = opt.ask()
        rem = budget - opt.nfe
        if len(X) > rem:
            X = X[:rem]
        F = evaluate(f, X)
        opt.tell(X, F)
        if target is not None and opt.best_f <= target:
            message = "target reached"
            break
        if opt.best_f == -np.inf:
            message = "the objective returned -inf: the minimum there is"
            break
        if callback is not None:
            state = OptimizerState(opt.nfe, opt.nit, opt.best_x.copy(), opt.best_f, X, F)
            if callback(state):
                message = "stopped by callback"
                break
    return opt.result(_time.perf_counter() - t0, message)
