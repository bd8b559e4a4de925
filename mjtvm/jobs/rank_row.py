r"""The row of ``mjtvm rank``: [`RankRow`][mjtvm.jobs.rank_row.RankRow], the one statement of its
fields, their types and units, and of the columns they become in ``NAME.csv``.

[`rank_row()`][mjtvm.jobs.rank.rank_row] fills one per grasp and returns it as a dict
([`RankRow.to_dict()`][mjtvm.jobs.rank_row.RankRow.to_dict]: ``NAME.json``'s keys, in order);
[`flat_row()`][mjtvm.jobs.rank_row.flat_row] and
[`table_columns()`][mjtvm.jobs.rank_row.table_columns] make the columns of ``NAME.csv`` and
``NAME.parquet`` ([`mjtvm.jobs.rank_files`][mjtvm.jobs.rank_files]). ``docs/outputs.md`` documents
the same fields (tested against what is written).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

__all__ = ["CLASSIC_COLUMNS", "SIM_FIELDS", "RankRow", "csv_columns", "flat_row", "table_columns"]

_PAIRS = "pairs"
"""``csv`` metadata: a K x R list, one column ``<name>_k<k>_l<l>`` per pair, after the leading columns."""
_SPLIT = "k, l"
"""``csv`` metadata: a pair ``[k, l]``, two columns ``<name>_k`` and ``<name>_l``."""
_MEASURE = "measure"
"""``csv`` metadata: a classic measure, after the pairs' columns."""
_SIM = "sim"
"""``csv`` metadata: a simulated column (``--verify`` only), after the classic measures."""


def _measure() -> Any:
    return field(default=None, metadata={"csv": _MEASURE})


def _sim() -> Any:
    return field(default=None, metadata={"csv": _SIM})


@dataclass(frozen=True)
class RankRow:
    r"""One grasp of a ranked dataset: evaluated, or failed with its reason.

    The fields, in order, are ``NAME.json``'s keys; ``NAME.csv`` has them flattened
    ([`csv_columns()`][mjtvm.jobs.rank_row.csv_columns]). A grasp that cannot be evaluated has
    ``failure`` and ``reason`` and ``None`` results. The files add ``inputs``, the digest of what
    the row depends on ([`inputs_digest()`][mjtvm.jobs.rank_inputs.inputs_digest]).

    Attributes
    ----------
    id : str
        The grasp's id: the dataset's ``id``, else ``<file stem>:<index>``.
    source : str
        The dataset file's name.
    index : int
        The grasp's index in its file, from 0.
    object : str
        The object: the stem of the grasp's ``obj_path``, else the grasp file's object body.
    scale : float
        The object's scale factor (``obj_scale``, default 1).
    rank : int or None
        1 = best by the sort key (TVMMP, or ``--sort``), in the written files; ``None`` for
        an infeasible or failed grasp, one without the sort key, and in the checkpoint.
    contacts : int or None
        Contacts of the grasp state; for a failed grasp, those found before it failed;
        ``None`` if none were looked for.
    penetration : float or None
        m: depth of the deepest contact inside the object, 0 when none penetrates; ``None`` if
        not measured.
    nearest_distance : float or None
        m: the smallest signed distance between a contact the state keeps and the object,
        negative when penetrating; for a ``no contact`` row where nothing touches, the nearest
        distance of the geoms outside the object (the reason gives the selection's own);
        ``None`` when nothing is within 0.1 m or not measured.
    penetration_exceeded : bool or None
        Whether ``penetration`` is deeper than the grasp file's ``max_penetration`` (such a row
        is evaluated unless ``--refuse-penetration``); ``None`` if not measured.
    feasible : bool
        Whether every REFS vertex can be balanced (``False`` for a failed grasp).
    tvmmp : float or None
        m/s per unit RVDS vertex: the TVMMP, or ``None`` (infeasible or failed).
    limiting : list of int or None
        ``[k, l]`` of the pair attaining the TVMMP; CSV: ``limiting_k``, ``limiting_l``.
    alpha : list of list of float or None
        m/s per unit RVDS vertex: K x R alpha_kl, ``None`` where not optimal; CSV:
        ``alpha_k<k>_l<l>``.
    status : list of list of str or None
        K x R statuses; CSV: ``status_k<k>_l<l>``.
    certified : bool or None
        Whether every alpha of the row is certified; ``None`` for a failed grasp.
    failure : str or None
        One of [`FAILURES`][mjtvm.jobs.rank.FAILURES], or ``None`` when evaluated.
    reason : str or None
        The one-line error of a failed grasp; for a TVMMP of 0 or an infeasible grasp, the
        diagnosis of its limiting (else first) pair; else ``None``.
    force_closure : bool or None
        Whether the contacts' primitive wrenches hold the object against any wrench.
    epsilon_l1 : float or None
        N per N: Ferrari-Canny epsilon, L1 (sum of normal forces 1).
    epsilon_linf : float or None
        N per N: Ferrari-Canny epsilon, L-infinity (each normal force at most 1), a lower bound.
    epsilon_linf_gap : float or None
        N per N: the bracket of ``epsilon_linf``.
    grasp_sigma_min : float or None
        N per N: the smallest singular value of the scaled grasp matrix.
    manipulability : float or None
        (m/s)^D per (rad/s)^D: Yoshikawa's measure of the object twists from unit joint speeds.
    torque_scale : float or None
        m: rho, the object's bounding radius from the contacts.

    sim_hold : bool or None
        The hold test of DexGraspBench: the object stays within 5 cm and 15 deg under a push of
        10 m/s^2 x its mass for 2 s along each of +-x, +-y, +-z
        ([`mjtvm.physics.disturb`][mjtvm.physics.disturb]).
    sim_hold_dirs : int or None
        Directions held, of 6.
    sim_hold_translation : float or None
        m: the object's largest displacement in the hold test.
    sim_hold_rotation : float or None
        deg: the object's largest rotation in the hold test.
    sim_speed_pass_08, sim_speed_pass_10, sim_speed_pass_12 : float or None
        Fraction of the directions with alpha_l > 0 whose witness rollout at s x alpha_l passes
        ``mjtvm verify``'s criteria, s = 0.8, 1.0, 1.2.
    sim_speed_dirs : int or None
        Directions with alpha_l > 0 (those tested).
    sim_speed_success : bool or None
        The prediction holds: every tested direction passes at 0.8 alpha_l.
    sim_failure : str or None
        What failed first, in words (``""`` when everything passed).

    The last seven before them are the classic measures ([`CLASSIC_COLUMNS`][mjtvm.jobs.rank_row.CLASSIC_COLUMNS];
    ``None`` for a failed grasp and with ``--measures none``). Every measure is better higher
    (``--sort`` ranks by any of them, descending). The ``sim_*`` fields
    ([`SIM_FIELDS`][mjtvm.jobs.rank_row.SIM_FIELDS]) are the simulation of ``--verify``
    ([`mjtvm.physics.grasp_sim`][mjtvm.physics.grasp_sim]): in the rows of such a run only.
    """

    id: str
    source: str
    index: int
    object: str
    scale: float
    rank: int | None = None
    contacts: int | None = None
    penetration: float | None = None
    nearest_distance: float | None = None
    penetration_exceeded: bool | None = None
    feasible: bool = False
    tvmmp: float | None = None
    limiting: list[int] | None = field(default=None, metadata={"csv": _SPLIT})
    alpha: list[list[float | None]] | None = field(default=None, metadata={"csv": _PAIRS})
    status: list[list[str]] | None = field(default=None, metadata={"csv": _PAIRS})
    certified: bool | None = None
    failure: str | None = None
    reason: str | None = None
    force_closure: bool | None = _measure()
    epsilon_l1: float | None = _measure()
    epsilon_linf: float | None = _measure()
    epsilon_linf_gap: float | None = _measure()
    grasp_sigma_min: float | None = _measure()
    manipulability: float | None = _measure()
    torque_scale: float | None = _measure()
    sim_hold: bool | None = _sim()
    sim_hold_dirs: int | None = _sim()
    sim_hold_translation: float | None = _sim()
    sim_hold_rotation: float | None = _sim()
    sim_speed_pass_08: float | None = _sim()
    sim_speed_pass_10: float | None = _sim()
    sim_speed_pass_12: float | None = _sim()
    sim_speed_dirs: int | None = _sim()
    sim_speed_success: bool | None = _sim()
    sim_failure: str | None = _sim()

    def to_dict(self, *, sim: bool = False) -> dict[str, Any]:
        """The row as ``NAME.json`` holds it.

        Parameters
        ----------
        sim
            With the ``sim_*`` fields (a ``--verify`` run).

        Returns
        -------
        dict
            Every field, in order (the lists as they are); the ``sim_*`` ones only with ``sim``.
        """
        return {f.name: getattr(self, f.name) for f in fields(self) if sim or f.metadata.get("csv") != _SIM}


CLASSIC_COLUMNS = tuple(f.name for f in fields(RankRow) if f.metadata.get("csv") == _MEASURE)
"""The classic measures a row carries ([`GraspMeasures`][mjtvm.measures.GraspMeasures]'s fields): all
but the kinematic velocity polytope, whose support LPs cost 1-3.5 s a grasp on a 16-joint
hand (``mjtvm.classic_measures(state)`` computes it)."""

SIM_FIELDS = tuple(f.name for f in fields(RankRow) if f.metadata.get("csv") == _SIM)
"""The simulated columns of ``--verify`` ([`grasp_sim()`][mjtvm.physics.grasp_sim.grasp_sim]'s ``SIM_COLUMNS``)."""

_PAIR_FIELDS = tuple(f.name for f in fields(RankRow) if f.metadata.get("csv") == _PAIRS)
_SPLIT_FIELDS = tuple(f.name for f in fields(RankRow) if f.metadata.get("csv") == _SPLIT)


def csv_columns() -> tuple[str, ...]:
    """The first columns of ``NAME.csv``, in order.

    Returns
    -------
    tuple of str
        Every field of [`RankRow`][mjtvm.jobs.rank_row.RankRow] but the K x R lists and the
        classic measures, ``limiting`` as ``limiting_k`` and ``limiting_l``. The pairs'
        ``alpha_k<k>_l<l>`` and ``status_k<k>_l<l>`` follow, then the classic measures and any
        other key of the rows (``inputs``).
    """
    out: list[str] = []
    for f in fields(RankRow):
        kind = f.metadata.get("csv")
        if kind == _SPLIT:
            out += [f"{f.name}_k", f"{f.name}_l"]
        elif kind not in (_PAIRS, _MEASURE, _SIM):
            out.append(f.name)
    return tuple(out)


def flat_row(row: Mapping[str, Any]) -> dict[str, Any]:
    """A row ([`RankRow.to_dict()`][mjtvm.jobs.rank_row.RankRow.to_dict], plus ``inputs``) flattened
    for CSV and Parquet.

    Parameters
    ----------
    row
        The row as ``NAME.json`` holds it.

    Returns
    -------
    dict
        The other keys as they are, then ``limiting_k``, ``limiting_l`` (``None`` without a
        limiting pair), then per pair ``alpha_k<k>_l<l>`` and ``status_k<k>_l<l>``.
    """
    out = {k: v for k, v in row.items() if k not in (*_PAIR_FIELDS, *_SPLIT_FIELDS)}
    for name in _SPLIT_FIELDS:
        out[f"{name}_k"], out[f"{name}_l"] = row[name] if row[name] is not None else (None, None)
    first = row[_PAIR_FIELDS[0]]
    for k, line in enumerate(first or ()):
        for l in range(len(line)):
            for name in _PAIR_FIELDS:
                out[f"{name}_k{k}_l{l}"] = row[name][k][l]
    return out


def table_columns(flat: Sequence[Mapping[str, Any]]) -> list[str]:
    """The columns of ``NAME.csv`` and ``NAME.parquet``, in order.

    Parameters
    ----------
    flat
        The flattened rows ([`flat_row()`][mjtvm.jobs.rank_row.flat_row]).

    Returns
    -------
    list of str
        [`csv_columns()`][mjtvm.jobs.rank_row.csv_columns], then the pairs' columns (every
        ``alpha_k<k>_l<l>`` by k, l, then every ``status_k<k>_l<l>``), then the other keys in
        order of first appearance (the classic measures, ``inputs``).
    """
    lead = csv_columns()
    extra = list(dict.fromkeys(k for r in flat for k in r if k not in lead))
    prefixes = tuple(f"{name}_k" for name in _PAIR_FIELDS)
    pairs = sorted(
        (k for k in extra if k.startswith(prefixes)),
        key=lambda k: (
            next(i for i, p in enumerate(prefixes) if k.startswith(p)),
            *(int(x[1:]) for x in k.split("_")[-2:]),
        ),
    )
    return [*lead, *pairs, *(k for k in extra if k not in pairs)]
