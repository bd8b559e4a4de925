"""The options several commands share, each defined once: one spelling, one help text, one
range (the vocabulary of ``docs/cli.md``, whose tables ``tools/cli_tables.py`` generates from
the parsers)."""

from __future__ import annotations

import argparse

from mjtvm.cli.options import computed_default
from mjtvm.cli.values import (
    CONTACTS,
    MAX_FORCE,
    MAX_INDENT,
    MAX_JOBS,
    MAX_MU,
    MAX_SECONDS,
    MAX_STATES,
    READINGS,
    choices,
    cluster_address,
    folder,
    fraction,
    grasps,
    integer,
    names,
    number,
    numbers,
    output_file,
    source,
    stem,
)
from mjtvm.errors import OptionError
from mjtvm.model.limits import with_limit_horizon  # the commands' --limit-horizon, one meaning

__all__ = [
    "GRASP_HELP",
    "contacts_option",
    "friction_margin_option",
    "grasp_option",
    "hand_option",
    "indent_option",
    "jobs_option",
    "lift_options",
    "limit_horizon_option",
    "mg_option",
    "mu_option",
    "no_plots_option",
    "one_grasp",
    "out_options",
    "parallel_options",
    "png_option",
    "quiet_option",
    "reading_option",
    "resume_option",
    "rrd_option",
    "states_option",
    "time_limit_option",
    "with_limit_horizon",
]


GRASP_HELP = (
    "grasp: a mjtvm.grasp/1 file (.toml or .json), or a shipped grasp: the paper's case1, case1-s, "
    "case2 (with --hand), or any name in models/*/ (installed as mjtvm.models)"
)
"""The help of a command's GRASP argument (``--grasp``'s is the vocabulary's)."""

_POSITIONAL = "the positional argument instead, or `--grasp`, not both"


def grasp_option(p: argparse.ArgumentParser, *, default: str | None, many: bool = False) -> None:
    """``--grasp GRASP`` (``many``: a comma list, ``sweep``); default None: the command's
    positional argument is the other way to give it."""
    action = p.add_argument(
        "--grasp",
        default=default,
        type=grasps if many else source,
        metavar="GRASP",
        help="a grasp file (`mjtvm.grasp/1`, `.toml` or `.json`, docs/grasp-format.md) or a shipped "
        "grasp's name (`case1`, `case1-s`, `case2`, `allegro-ik`, `allegro-sphere`, `allegro-jenga`, "
        "`gripper3-box`, ...: the `*.toml` files of `models/*/`, installed as `mjtvm.models`); "
        "`sweep`: a comma list",
    )
    if default is None:
        computed_default(action, _POSITIONAL)


def one_grasp(positional: str | None, option: str | None, *, name: str = "GRASP") -> str:
    """The grasp of a command that takes it as ``name`` or as ``--grasp``: one of them.

    Raises
    ------
    OptionError
        Both given (which one was meant is not for the command to guess), or neither.
    """
    if positional is not None and option is not None:
        raise OptionError("--grasp", f"give {name} or --grasp, not both")
    source = positional if positional is not None else option
    if source is None:
        raise OptionError(name, "give a grasp file or a shipped grasp name (e.g. case2)")
    return source


def hand_option(p: argparse.ArgumentParser, *, many: bool = False) -> None:
    """``--hand NAME`` (``many``: a comma list, ``sweep``)."""
    p.add_argument(
        "--hand",
        default="default",
        type=names if many else str,
        metavar="NAME",
        help="the paper's hand variant of a shipped case: `humanlike`, or `default`, the paper's own hand "
        "(`case2` + `humanlike` is `case2-humanlike`; any other grasp: refused in one line); `sweep`: a comma list",
    )


def contacts_option(p: argparse.ArgumentParser, *, default: str) -> None:
    """``--contacts L,S``: the contact types of the lift's L/S fingers."""
    p.add_argument(
        "--contacts",
        type=choices(CONTACTS),
        default=default,
        metavar="L,S",
        help="contact types of the lift's L/S fingers (fingers 2 and 4 of Case 2): `L` (rolling, "
        "line) and/or `S` (sliding), distinct, comma-separated",
    )


def reading_option(p: argparse.ArgumentParser, *, default: str) -> None:
    """``--reading R``: the slide direction of the S-points."""
    p.add_argument(
        "--reading",
        type=choices(READINGS, every="both"),
        default=default,
        metavar="R",
        help="slide direction of S-points: `physical` (the slip of the minimum-norm lift motion: "
        "friction resists the lift, what the physics supports), `literal` (the paper's printed "
        "vector, the reverse: the curve of its Fig. 8, docs/paper-results.md), a comma list of "
        "them, or `both`",
    )


_STATE_FILE = "`solve`: a grasp only (a state file: refused, exit 2)"


def mu_option(p: argparse.ArgumentParser, *, many: bool = False) -> None:
    """``--mu X``: one friction coefficient for every contact instead of the grasp's
    ([`with_options()`][mjtvm.grasp.resolve.loaded.Grasp.with_options]; ``many``: a comma list)."""
    action = p.add_argument(
        "--mu",
        type=numbers(0.0, MAX_MU) if many else number(0.0, MAX_MU),
        default=None,
        metavar="X",
        help=f"friction coefficient, for every contact of the grasp; `sweep`: a comma list; {_STATE_FILE}",
    )
    computed_default(action, "the grasp's (`0.3` for `case2`)")


def mg_option(p: argparse.ArgumentParser, *, many: bool = False, positive: bool = False) -> None:
    """``--mg NEWTONS``: the object's weight (N) instead of the grasp's (its REFS scaled to it;
    [`with_options()`][mjtvm.grasp.resolve.loaded.Grasp.with_options]; ``many``: a comma list;
    ``positive``: not 0, ``verify``)."""
    action = p.add_argument(
        "--mg",
        type=numbers(0.0, MAX_FORCE, unit="weights (N)")
        if many
        else number(0.0, MAX_FORCE, strict=positive, unit="N"),
        default=None,
        metavar="NEWTONS",
        help="object weight in N (the grasp's REFS scaled to it); `sweep`: a comma list; "
        f"{_STATE_FILE}; `verify`: not 0 (its rollouts need a weight)",
    )
    computed_default(action, "the grasp's (`1.0` for `case2`)")


def friction_margin_option(p: argparse.ArgumentParser) -> None:
    """``--friction-margin D``: the LPs use (1 - D) mu for every F contact (docs/state-format.md)."""
    action = p.add_argument(
        "--friction-margin",
        type=fraction,
        default=None,
        metavar="D",
        help="friction margin delta: every LP uses (1 - D) mu for each F contact's pyramid "
        "(docs/state-format.md#friction-margin-and-friction-intervals); replaces a state's "
        "`friction_margin` or a grasp file's (whose `cone` still applies: pyramidal makes it "
        "1 - (1 - D) / sqrt(2)); `verify`: on the rollouts' `--cone` instead; the result's "
        "`friction` object reports it with the TVMMP at margin 0",
    )
    computed_default(action, "the state's or grasp's (`0`)")


def limit_horizon_option(p: argparse.ArgumentParser) -> None:
    """``--limit-horizon METRES``: Problem 2's travel horizon of the joint limits (m of object travel;
    ``docs/joint-limits.md``), replacing the state's."""
    action = p.add_argument(
        "--limit-horizon",
        type=number(0.0, 1e3, unit="metres"),
        default=None,
        metavar="METRES",
        help="metres of object travel within which no joint may reach its position limit (Problem 2, "
        "docs/joint-limits.md); `0`: only the joints on a limit are held; replaces the state's or "
        "the grasp file's `joint_limits.horizon` at every state the command solves (`sweep`, `rank`: "
        "part of what `--resume` matches; `verify`: named in `lp_note`); `tvms` refuses it "
        "(Problem 1 has no horizon)",
    )
    computed_default(action, "the state's, or the grasp file's (`0.001`)")


def states_option(p: argparse.ArgumentParser, *, hint: str = "", minimum: int = 2) -> None:
    """``--states N``: the number of states along the lift (``hint``: added to its error;
    ``minimum``: 1 where one state, the grasp's own, is a check of its own)."""
    p.add_argument(
        "--states",
        type=integer(minimum, MAX_STATES, hint=hint),
        default=30,
        metavar="N",
        help="number of states along the lift (a count; `verify`: 1 is the grasp's own state, no lift)",
    )


def lift_options(p: argparse.ArgumentParser, *, contacts: str, reading: str) -> None:
    """The scripted lift of ``replay``: grasp, hand, friction, weight, states, contacts, reading."""
    grasp_option(p, default="case2")
    hand_option(p)
    mu_option(p)
    mg_option(p)
    states_option(p)
    action = p.add_argument(
        "--stop-margin",
        type=fraction,
        default=None,
        metavar="F",
        help="end the lift where a finger's contact Jacobian keeps this fraction of its smallest singular "
        "value at the start (0: to the reach limit)",
    )
    computed_default(action, "the grasp's `lift.stop_margin`, else `0.25`")
    contacts_option(p, default=contacts)
    reading_option(p, default=reading)


def out_options(p: argparse.ArgumentParser, *, name: str | None) -> None:
    """``--out DIR`` and (unless ``name`` is None) ``--name STEM`` with the default ``name``."""
    p.add_argument(
        "--out",
        type=folder,
        default="results",
        metavar="DIR",
        help="output folder (created if missing, checked writable before any work, locked while the "
        "run writes)",
    )
    if name is not None:
        p.add_argument(
            "--name", type=stem, default=name, metavar="STEM", help="file stem of the outputs inside `--out`"
        )


def jobs_option(p: argparse.ArgumentParser) -> None:
    """``--jobs N``: local worker processes."""
    p.add_argument("--jobs", type=integer(1, MAX_JOBS), default=1, metavar="N", help="local worker processes")


def parallel_options(p: argparse.ArgumentParser) -> None:
    """``--jobs N`` local worker processes and ``--cluster tcp://HOST:PORT`` (a Dask scheduler)."""
    jobs_option(p)
    action = p.add_argument(
        "--cluster",
        type=cluster_address,
        default=None,
        metavar="tcp://HOST:PORT",
        help="Dask scheduler address (the `cluster` extra; overrides `--jobs`; connection timeout 10 s)",
    )
    computed_default(action, "none: local processes")


def resume_option(p: argparse.ArgumentParser) -> None:
    """``--resume``: keep the finished rows of an interrupted or earlier run."""
    p.add_argument(
        "--resume",
        action="store_true",
        help="keep the finished rows of the checkpoint (`NAME.partial.json`; `rank`: `NAME.partial.jsonl`) "
        "and of `NAME.json` that belong to this run (`sweep`: to its grid) and whose inputs are unchanged",
    )


def indent_option(p: argparse.ArgumentParser) -> None:
    """``--indent N``: the indentation of the JSON printed."""
    p.add_argument(
        "--indent",
        type=integer(0, MAX_INDENT),
        default=1,
        metavar="N",
        help="JSON indentation (`show`: with `--json`)",
    )


def time_limit_option(p: argparse.ArgumentParser) -> None:
    """``--time-limit SECONDS``: wall-clock seconds of a projection (``tvms``) or a cdd run (``python -m benchmarks``)."""
    p.add_argument(
        "--time-limit",
        type=number(0.0, MAX_SECONDS, strict=True, unit="seconds"),
        default=120.0,
        metavar="SECONDS",
        help="wall-clock seconds: `tvms`: the projection's limit for both methods: `lp` then stops with "
        '`status: "approximate"` and the volume bracket, `cdd` with `status: "timeout"`; the benchmarks: '
        "the cap of each cdd run",
    )


def no_plots_option(p: argparse.ArgumentParser) -> None:
    """``--no-plots``."""
    p.add_argument("--no-plots", action="store_true", help="do not write PNG plots")


def rrd_option(p: argparse.ArgumentParser) -> None:
    """``--rrd FILE``: a rerun recording of what the command computes (docs/rerun.md)."""
    action = p.add_argument(
        "--rrd",
        type=output_file,
        default=None,
        metavar="FILE",
        help="also write a rerun recording (docs/rerun.md; open it with `rerun FILE`) of what the "
        "command computes: `replay`: the lift (scene, contacts, velocity polytopes, TVMMP, joint "
        "operation points); `show`: the grasp (geoms, contact points, normals, friction cones); "
        "`verify`: the results",
    )
    computed_default(action, "none")


def png_option(p: argparse.ArgumentParser) -> None:
    """``--png FILE``: a picture of what the command computes (``show``, ``solve``, ``tvms``)."""
    action = p.add_argument(
        "--png",
        type=output_file,
        default=None,
        metavar="FILE",
        help="also write a PNG picture of what the command computes (docs/gallery.md): `show`: three "
        "views around the object with the contact points, by MuJoCo's renderer (headless: "
        "`MUJOCO_GL=egl`, set when unset); `solve`: every alpha_kl (m/s per unit of RVDS vertex) and "
        "the limiting pair's witness, each joint's (|tau| in N m, |qd| in rad/s) in its operation "
        "range; `tvms`: the TVMS's vertices projected on three planes (m/s; rad/s), with their hulls",
    )
    computed_default(action, "none")


def quiet_option(p: argparse.ArgumentParser) -> None:
    """``--quiet``: less on stderr."""
    p.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bar / spinner on stderr (`export-state`, `tvms`: no contact report or "
        "warnings either; `solve`: no warnings (contacts, zero alphas, certificates), standard "
        "output unchanged)",
    )


def dataset_options(p: argparse.ArgumentParser) -> None:
    """``--pose grasp|pregrasp|squeeze``, ``--dataset-key grasp_qpos|qpos``: how a dataset's
    arrays are read; ``--com-frame``: the object's frame at its centre of mass (docs/datasets.md)."""
    p.add_argument(
        "--pose",
        choices=("grasp", "pregrasp", "squeeze"),
        default="grasp",
        help="the pipeline pose ranked where a grasp carries several (DexGraspBench's `<pose>_qpos`)",
    )
    action = p.add_argument(
        "--dataset-key",
        choices=("grasp_qpos", "qpos"),
        default=None,
        help="what a 2-D `.npy` array holds: `grasp_qpos` (root pose + hand joints) or `qpos` (the "
        "model's qpos); without it such a file is refused, never guessed from its width",
    )
    computed_default(action, "none: a 2-D `.npy` is refused")
    p.add_argument(
        "--com-frame",
        action="store_true",
        help="the object's frame at its centre of mass: the REFS's moments (the weight's is then 0) "
        "and the RVDS's twists about it; the object stays where the dataset poses it (`grasp_qpos` rows only)",
    )


def rank_order_options(p: argparse.ArgumentParser) -> None:
    """``--refuse-penetration``, ``--measures classic|none``, ``--sort COLUMN`` of ``mjtvm rank``."""
    from mjtvm.jobs.rank_order import SORT_COLUMNS

    p.add_argument(
        "--refuse-penetration",
        action="store_true",
        help="a grasp deeper than the grasp file's max_penetration fails (failure penetration) "
        "instead of being evaluated and flagged (column penetration_exceeded)",
    )
    p.add_argument(
        "--measures",
        choices=("classic", "none"),
        default="classic",
        help="classic: the classic measures beside the TVMMP; none: TVMMP alone, the measure columns empty",
    )
    p.add_argument(
        "--sort",
        choices=SORT_COLUMNS,
        default="tvmmp",
        metavar="COLUMN",
        help="the column the rows are sorted and ranked by, descending (higher is better for "
        f"every measure): {', '.join(SORT_COLUMNS)}",
    )
