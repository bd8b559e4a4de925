r"""How well each measure predicts the simulation: ROC AUC of ``mjtvm rank --verify``.

Per measure ([`auc_scores()`][mjtvm.jobs.rank_auc.auc_scores]: ``tvmmp``, each direction's
``alpha_l<l>`` = min over k of alpha_kl, ``epsilon_l1``, ``epsilon_linf``, ``grasp_sigma_min``,
``force_closure`` as 0/1) and per simulated outcome (``sim_hold``, ``sim_speed_success``):

* **AUC** ([`roc_auc()`][mjtvm.jobs.rank_auc.roc_auc]): the Mann-Whitney statistic, the
  probability that a grasp that succeeds in simulation scores higher than one that fails, ties
  counted 1/2: $\frac{1}{n_1 n_0}\sum_{i \in +}\sum_{j \in -} ([s_i > s_j] + \frac12 [s_i = s_j])$.
  0.5 is chance, 1 a perfect ranking.
* **Missing scores**: a grasp without a value (an infeasible grasp's TVMMP or alpha, a measure
  not computed, ``--measures none``) scores **lowest**, below every value and tied with the
  other missing ones: "infeasible" is the worst a measure can say.
* **Missing outcomes**: a grasp without the outcome (not evaluated, not simulated, no direction
  with alpha > 0 for the speed) is left out of that outcome's AUC (``excluded``).
* **Confidence interval** ([`bootstrap_ci()`][mjtvm.jobs.rank_auc.bootstrap_ci]): the percentile
  bootstrap, `RESAMPLES` resamples of the grasps with replacement, seeded (`SEED`), the 2.5 and
  97.5 % quantiles of the resampled AUCs (resamples with one class only are dropped). NaN
  when one class is empty. Each resample is a row of per-grasp counts, and all resamples'
  AUCs of a measure are computed at once from the measure's sorted scores; every measure of
  an outcome is resampled by the same draws (the seed restarts for each).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mjtvm.errors import ParamError

__all__ = [
    "AUC_COLUMNS",
    "AUC_SCHEMA",
    "RESAMPLES",
    "SEED",
    "TARGETS",
    "auc_files",
    "auc_plot",
    "auc_scores",
    "auc_summary",
    "auc_table",
    "bootstrap_ci",
    "roc_auc",
]

RESAMPLES = 2000
"""Bootstrap resamples of the confidence interval."""
SEED = 0
"""The bootstrap's seed: the same rows give the same interval."""
TARGETS = ("sim_hold", "sim_speed_success")
"""The simulated outcomes the measures are scored against."""
MEASURE_KEYS = ("tvmmp", "epsilon_l1", "epsilon_linf", "grasp_sigma_min", "force_closure")
AUC_COLUMNS = (
    "measure",
    "target",
    "auc",
    "ci_low",
    "ci_high",
    "positives",
    "negatives",
    "excluded",
    "missing",
)
"""The columns of ``NAME-auc.csv``."""

_F64 = NDArray[np.float64]


_BLOCK = 1 << 20
"""At most this many (resample, grasp) counts are held at once: memory bounded for any dataset."""


def _resample_counts(rng: np.random.Generator, n: int, resamples: int) -> NDArray[np.signedinteger[Any]]:
    """The next ``resamples`` bootstrap resamples of ``n`` grasps as counts, shape (resamples, n).

    One draw of shape (resamples, n) takes the same values from ``rng`` as ``resamples``
    draws of ``n`` in turn (numpy's bounded integers read 32-bit halves from the bit
    generator, which keeps the spare half between calls), so the resamples do not depend on
    how they are split into blocks. int32 where every product of two counts fits (n^2 < 2^31):
    half the memory traffic of int64.
    """
    idx = rng.integers(0, n, (resamples, n)) + np.arange(resamples)[:, None] * n
    counts = np.bincount(idx.ravel(), minlength=resamples * n).reshape(resamples, n)
    return counts.astype(np.int32) if n * n < 2**31 else counts


def _aucs(scores: _F64, labels: NDArray[np.bool_], counts: NDArray[np.signedinteger[Any]]) -> _F64:
    """The AUC under each row of per-grasp multiplicities ``counts`` (resamples, n), shape (resamples,).

    Each positive grasp i (weight w_i) counts the negatives below its score and half those tied
    with it: (C[lo_i] + C[hi_i]) / 2, C the cumulative counts of the negatives sorted by score,
    lo_i and hi_i the sorted positions before and after the negatives tied with it. The sum is
    kept doubled, in integers, so it is exact. NaN where a row counts one class only.
    ``-inf`` is a score like any other; NaN scores sort above all and tie with each other.
    """
    pos_i, neg_i = np.flatnonzero(labels), np.flatnonzero(~labels)
    neg_i = neg_i[np.argsort(scores[neg_i], kind="stable")]
    lo = np.searchsorted(scores[neg_i], scores[pos_i], "left")
    hi = np.searchsorted(scores[neg_i], scores[pos_i], "right")
    c = np.zeros((len(counts), len(neg_i) + 1), dtype=counts.dtype)
    np.cumsum(counts[:, neg_i], axis=1, out=c[:, 1:])
    w = counts[:, pos_i]
    twice = 2 * (w * c[:, lo]).sum(axis=1, dtype=np.int64)
    tied = lo != hi
    if tied.any():  # the half of the ties: only the columns that have some
        twice += (w[:, tied] * (c[:, hi[tied]] - c[:, lo[tied]])).sum(axis=1, dtype=np.int64)
    n1, n0 = w.sum(axis=1, dtype=np.int64), c[:, -1].astype(np.int64)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = twice / (2.0 * n1 * n0)
    out[(n1 == 0) | (n0 == 0)] = math.nan
    return out


def _pair(
    scores: Sequence[float] | _F64, labels: Sequence[bool] | NDArray[np.bool_]
) -> tuple[_F64, NDArray[np.bool_]]:
    """The scores as floats and the labels as bools, one of each a grasp, shape (n,)."""
    s, y = np.asarray(scores, dtype=float), np.asarray(labels, dtype=bool)
    if s.ndim != 1 or s.shape != y.shape:
        raise ParamError("labels", f"one score and one label a grasp, got shapes {s.shape} and {y.shape}")
    return s, y


def roc_auc(scores: Sequence[float] | _F64, labels: Sequence[bool] | NDArray[np.bool_]) -> float:
    """The ROC AUC of ``scores`` (higher: predicted success) for ``labels`` (module docstring).

    ``-inf`` is a valid score (a missing value, lowest). NaN when one class is empty.
    """
    s, y = _pair(scores, labels)
    if not len(s):
        return math.nan
    return float(_aucs(s, y, np.ones((1, len(s)), dtype=np.int64))[0])


def _bootstrap_cis(
    scores: _F64, labels: NDArray[np.bool_], *, resamples: int, seed: int, level: float
) -> list[tuple[float, float]]:
    """[`bootstrap_ci()`][mjtvm.jobs.rank_auc.bootstrap_ci] of each row of ``scores`` (measures, n).

    Every measure is resampled by the same draws (the seed restarts for each, as it would
    one measure at a time), so the draws are made once and shared.
    """
    m, n = scores.shape
    if n == 0 or labels.all() or not labels.any():
        return [(math.nan, math.nan)] * m
    rng = np.random.default_rng(seed)
    values = np.empty((m, max(resamples, 0)))
    block = max(1, _BLOCK // n)
    for first in range(0, resamples, block):
        counts = _resample_counts(rng, n, min(block, resamples - first))
        for i in range(m):
            values[i, first : first + len(counts)] = _aucs(scores[i], labels, counts)
    tail = 50.0 * (1.0 - level)
    out = []
    for v in values:
        v = v[~np.isnan(v)]
        if not len(v):
            out.append((math.nan, math.nan))
            continue
        low, high = np.percentile(v, [tail, 100.0 - tail])
        out.append((float(low), float(high)))
    return out


def bootstrap_ci(
    scores: Sequence[float] | _F64,
    labels: Sequence[bool] | NDArray[np.bool_],
    *,
    resamples: int = RESAMPLES,
    seed: int = SEED,
    level: float = 0.95,
) -> tuple[float, float]:
    """The percentile bootstrap interval of [`roc_auc()`][mjtvm.jobs.rank_auc.roc_auc] (module docstring)."""
    s, y = _pair(scores, labels)
    return _bootstrap_cis(s[None, :], y, resamples=resamples, seed=seed, level=level)[0]


def _number(value: Any) -> float:
    """A measure's value as a score: ``None`` and NaN lowest (``-inf``), a bool 0/1."""
    if value is None:
        return -math.inf
    v = float(value)
    return -math.inf if math.isnan(v) else v


def auc_scores(row: Mapping[str, Any]) -> dict[str, float]:
    """A row's scores: ``tvmmp``, ``alpha_l<l>`` (min over k of alpha_kl), the classic measures."""
    out = {key: _number(row.get(key)) for key in ("tvmmp",)}
    alpha = row.get("alpha")
    if alpha:
        for l in range(len(alpha[0])):
            values = [line[l] for line in alpha]
            out[f"alpha_l{l}"] = -math.inf if any(v is None for v in values) else float(min(values))
    for key in MEASURE_KEYS[1:]:
        out[key] = _number(row.get(key))
    return out


def auc_table(
    rows: Iterable[Mapping[str, Any]], *, resamples: int = RESAMPLES, seed: int = SEED
) -> list[dict[str, Any]]:
    """One line per (measure, target): [`AUC_COLUMNS`][mjtvm.jobs.rank_auc.AUC_COLUMNS].

    ``missing``: grasps scored lowest for want of a value, among those counted. A direction
    ``alpha_l<l>`` that some rows lack (failed grasps) scores lowest there.
    """
    scores: dict[str, list[float]] = {}
    labels: dict[str, list[bool | None]] = {t: [] for t in TARGETS}
    n = 0
    for row in rows:
        s = auc_scores(row)
        for key in s.keys() - scores.keys():
            scores[key] = [-math.inf] * n
        for key, values in scores.items():
            values.append(s.get(key, -math.inf))
        for t in TARGETS:
            v = row.get(t)
            labels[t].append(None if v is None else bool(v))
        n += 1
    order = [
        k
        for k in ("tvmmp", *sorted(k for k in scores if k.startswith("alpha_l")), *MEASURE_KEYS[1:])
        if k in scores
    ]
    out = []
    for t in TARGETS:
        known = np.array([v is not None for v in labels[t]], dtype=bool)
        y = np.array([bool(v) for v in labels[t]], dtype=bool)[known]
        # (measures, grasps); the reshape gives no rows the shape (0, 0)
        stack = np.array([scores[key] for key in order], dtype=float).reshape(len(order), n)[:, known]
        cis = _bootstrap_cis(stack, y, resamples=resamples, seed=seed, level=0.95)
        for key, s, (low, high) in zip(order, stack, cis, strict=True):
            out.append(
                {
                    "measure": key,
                    "target": t,
                    "auc": roc_auc(s, y),
                    "ci_low": low,
                    "ci_high": high,
                    "positives": int(y.sum()),
                    "negatives": int((~y).sum()),
                    "excluded": int((~known).sum()),
                    "missing": int(np.isneginf(s).sum()),
                }
            )
    return out


def auc_summary(table: Sequence[Mapping[str, Any]]) -> str:
    """The AUC lines of the stderr summary, one per target."""
    lines = []
    for t in TARGETS:
        mine = [r for r in table if r["target"] == t]
        if not mine:
            continue
        head = f"AUC vs {t} ({mine[0]['positives']} succeed, {mine[0]['negatives']} fail, {mine[0]['excluded']} not simulated)"
        parts = [f"{r['measure']} {r['auc']:.3f} [{r['ci_low']:.3f}, {r['ci_high']:.3f}]" for r in mine]
        lines.append(f"{head}: " + ", ".join(parts))
    return "\n".join(lines)


def auc_plot(table: Sequence[Mapping[str, Any]]) -> bytes:
    """``NAME-auc.png``: per target, each measure's AUC as a bar with its 95 % interval; 0.5 (chance) dashed."""
    from mjtvm.jobs.style import figure, finish, png

    measures = list(dict.fromkeys(r["measure"] for r in table))
    fig, ax = figure(max(4.8, 0.8 * len(measures) + 2.0), 3.8)
    width = 0.8 / len(TARGETS)
    x = np.arange(len(measures))
    for i, t in enumerate(TARGETS):
        mine = {r["measure"]: r for r in table if r["target"] == t}
        auc = np.array([mine[m]["auc"] if m in mine else math.nan for m in measures], dtype=float)
        low = np.array([mine[m]["ci_low"] if m in mine else math.nan for m in measures], dtype=float)
        high = np.array([mine[m]["ci_high"] if m in mine else math.nan for m in measures], dtype=float)
        err = np.vstack([np.nan_to_num(auc - low), np.nan_to_num(high - auc)])
        n = next(iter(mine.values()), {"positives": 0, "negatives": 0})
        none = " (no AUC: one class only)" if np.isnan(auc).all() else ""
        ax.bar(
            x + (i - 0.5 * (len(TARGETS) - 1)) * width,
            auc,  # NaN: no bar
            width,
            yerr=err,
            error_kw={"capsize": 2, "clip_on": False},  # an interval's end at 0 or 1 on the frame
            label=f"{t} ({n['positives']} succeed, {n['negatives']} fail){none}",
        )
    ax.axhline(0.5, ls="--", lw=0.8, color="0.4")
    ax.set_xticks(x, measures, rotation=45, ha="right")
    ax.set_ylim(0.0, 1.05)
    finish(
        fig,
        ax,
        xlabel="measure (-)",
        ylabel="ROC AUC (-)",
        title="ROC AUC of each measure against the simulation",
        notes=[
            f"bars: 95 % bootstrap interval ({RESAMPLES} resamples); dashed: chance (0.5)",
            "a missing value (infeasible) scores lowest",
        ],
    )
    return png(fig)


AUC_SCHEMA = "mjtvm.rank-auc/1"
"""The schema of ``NAME-auc.json``."""


def auc_files(
    rows: Iterable[Mapping[str, Any]], outdir: Any, name: str, *, plots: bool = True
) -> tuple[dict[Any, bytes | str], list[dict[str, Any]]]:
    """``NAME-auc.csv``, ``NAME-auc.json`` and (``plots``) ``NAME-auc.png`` of the rows, and the table."""
    import json

    from mjtvm.jobs.files import csv_text

    table = auc_table(rows)

    def cell(v: Any) -> Any:
        return "" if v is None or (isinstance(v, float) and math.isnan(v)) else v

    doc = {
        "schema": AUC_SCHEMA,
        "resamples": RESAMPLES,
        "seed": SEED,
        "level": 0.95,
        "rows": [{k: None if cell(v) == "" else v for k, v in r.items()} for r in table],
    }
    files: dict[Any, bytes | str] = {
        outdir / f"{name}-auc.csv": csv_text(table, list(AUC_COLUMNS), cell=cell),
        outdir / f"{name}-auc.json": json.dumps(doc, indent=1) + "\n",
    }
    if plots:
        files[outdir / f"{name}-auc.png"] = auc_plot(table)
    return files, table
