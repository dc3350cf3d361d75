"""Statistics over paired blocks: Friedman average ranks and Wilcoxon vs the best with Holm.

Follows Derrac et al. (2011), "A practical tutorial on the use of nonparametric statistical
tests as a methodology for comparing evolutionary and swarm intelligence algorithms",
Swarm and Evolutionary Computation 1:3-18: rank methods within each block (instance ×
replicate), average the ranks, test the omnibus hypothesis with Friedman's test, then
compare the best-ranked method with every other by Wilcoxon's signed-rank test with Holm's
step-down correction of the p-values.
"""

from __future__ import annotations

import logging
import math
import warnings
from dataclasses import dataclass

import numpy as np

from drake_mh.study.report.data import ReportData, as_float, method_of

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class PairwiseTest:
    """Wilcoxon signed-rank test of the best method against one other.

    Attributes:
        method: the other method.
        n_pairs: blocks compared.
        wins, losses, ties: blocks where the best method is better / worse / equal.
        p_value: raw two-sided p-value (NaN if the test could not run).
        p_holm: Holm-adjusted p-value.
    """

    method: str
    n_pairs: int
    wins: int
    losses: int
    ties: int
    p_value: float
    p_holm: float


@dataclass(frozen=True)
class RankStats:
    """Friedman ranks and pairwise tests.

    Attributes:
        metric: the ranked field.
        methods: methods in order of average rank (best first).
        average_ranks: ``(M,)`` average rank of each method in ``methods`` (1 = best).
        n_blocks: complete blocks used (every method has a record).
        n_incomplete: blocks dropped because some method has no record.
        friedman_statistic, friedman_p: Friedman chi-square test (NaN with < 3 methods).
        pairwise: best vs each other method.
    """

    metric: str
    methods: list[str]
    average_ranks: np.ndarray
    n_blocks: int
    n_incomplete: int
    friedman_statistic: float
    friedman_p: float
    pairwise: list[PairwiseTest]

    @property
    def best(self) -> str:
        """The method with the lowest average rank."""
        return self.methods[0]


def holm(p_values: np.ndarray) -> np.ndarray:
    """Holm's step-down adjustment of ``(m,)`` p-values (NaN entries stay NaN).

    Args:
        p_values: raw p-values.

    Returns:
        ``(m,)`` adjusted p-values, monotone in the order of the raw ones, capped at 1.
    """
    p = np.asarray(p_values, dtype=float)
    adjusted = np.full_like(p, np.nan)
    valid = np.flatnonzero(np.isfinite(p))
    m = valid.size
    order = valid[np.argsort(p[valid], kind="stable")]
    running = 0.0
    for i, index in enumerate(order):
        running = max(running, min(1.0, (m - i) * p[index]))
        adjusted[index] = running
    return adjusted


def loss_matrix(data: ReportData, metric: str) -> tuple[np.ndarray, list[str], int]:
    """Builds the ``(B, M)`` loss matrix over complete blocks.

    A case that raised, failed to report the metric or reported NaN gets ``+inf`` loss (the
    worst rank); the metric is negated when higher is better.

    Returns:
        ``(L, methods, n_incomplete)`` with ``L`` of shape ``(B, M)``.
    """
    methods = list(data.methods)
    sign = 1.0 if data.fields.lower_is_better else -1.0
    blocks: dict[tuple, dict[str, float]] = {}
    for record in data.records:
        block = tuple(str(record.get(k)) for k in data.instance_keys)
        value = as_float(record.get(metric)) if record.get("status") == "ok" else math.nan
        loss = sign * value if math.isfinite(value) else math.inf
        blocks.setdefault(block, {}).setdefault(method_of(record, data.fields), loss)
    complete = [b for b in blocks.values() if len(b) == len(methods)]
    matrix = np.array([[b[m] for m in methods] for b in complete], dtype=float).reshape(len(complete), len(methods))
    return matrix, methods, len(blocks) - len(complete)


def _finite_stand_in(matrix: np.ndarray) -> np.ndarray:
    """Replaces +inf (failure) by a finite value worse than every finite loss."""
    finite = matrix[np.isfinite(matrix)]
    worst = (np.max(np.abs(finite)) * 2.0 + 1.0) if finite.size else 1.0
    return np.where(np.isfinite(matrix), matrix, worst)


def rank_stats(data: ReportData, metric: str | None = None) -> RankStats | None:
    """Computes Friedman average ranks and Wilcoxon-Holm tests of the best method.

    Args:
        data: the loaded results.
        metric: field to rank (default: the error field).

    Returns:
        The statistics, or ``None`` with fewer than 2 methods or no complete block.
    """
    from scipy import stats

    metric = metric or data.fields.error
    matrix, methods, n_incomplete = loss_matrix(data, metric)
    if len(methods) < 2 or matrix.shape[0] == 0:
        return None
    ranks = np.vstack([stats.rankdata(row) for row in matrix])  # ties get average ranks
    average = ranks.mean(axis=0)
    order = np.argsort(average, kind="stable")
    sorted_methods = [methods[i] for i in order]
    friedman_stat = friedman_p = math.nan
    if len(methods) >= 3 and matrix.shape[0] >= 2:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                result = stats.friedmanchisquare(*_finite_stand_in(matrix).T)
                friedman_stat, friedman_p = float(result.statistic), float(result.pvalue)
            except ValueError as exc:
                logger.info("Friedman test not computed: %s", exc)
    finite = _finite_stand_in(matrix)
    best = order[0]
    raw = []
    partial = []
    for index in order[1:]:
        diff = finite[:, best] - finite[:, index]
        wins, losses = int(np.sum(diff < 0)), int(np.sum(diff > 0))
        ties = int(diff.size - wins - losses)
        p = math.nan
        if wins + losses == 0:
            p = 1.0  # identical on every block
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    p = float(stats.wilcoxon(finite[:, best], finite[:, index], zero_method="wilcox").pvalue)
                except ValueError as exc:
                    logger.info("Wilcoxon test not computed for %s: %s", methods[index], exc)
        raw.append(p)
        partial.append((methods[index], diff.size, wins, losses, ties, p))
    adjusted = holm(np.asarray(raw, dtype=float)) if raw else np.array([])
    pairwise = [
        PairwiseTest(method=m, n_pairs=n, wins=w, losses=lo, ties=t, p_value=p, p_holm=float(a))
        for (m, n, w, lo, t, p), a in zip(partial, adjusted)
    ]
    return RankStats(
        metric=metric,
        methods=sorted_methods,
        average_ranks=average[order],
        n_blocks=matrix.shape[0],
        n_incomplete=n_incomplete,
        friedman_statistic=friedman_stat,
        friedman_p=friedman_p,
        pairwise=pairwise,
    )
