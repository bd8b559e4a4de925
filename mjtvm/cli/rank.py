"""``mjtvm rank``: rank a grasp dataset by TVMMP (``docs/cli.md``, ``docs/datasets.md``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from mjtvm.cli.options import Subparsers, command, computed_default
from mjtvm.cli.output import EXIT_OK, emit, wrote
from mjtvm.cli.values import input_path, number, source
from mjtvm.cli.vocabulary import (
    dataset_options,
    grasp_option,
    limit_horizon_option,
    no_plots_option,
    one_grasp,
    out_options,
    parallel_options,
    quiet_option,
    rank_order_options,
    resume_option,
)
from mjtvm.errors import OptionError

__all__ = ["add_rank"]

_HELP = "rank a dataset of grasp configurations by TVMMP: one row per grasp, CSV, JSON, plots"
_DESCRIPTION = (
    "Evaluate every grasp of the datasets (.npz, .npy, DexGraspBench per-grasp and DexGraspNet per-object .npy dicts, .csv, or folders of them: docs/datasets.md) "
    "with the grasp file's model, contact rules, ranges, REFS and RVDS; write NAME.json, NAME.csv, "
    "NAME.parquet (with pyarrow), NAME-objects.csv, NAME-objects.png, NAME-tvmmp.png and NAME-epsilon.png, and a summary on stderr. "
    "Rows are sorted and ranked by TVMMP (or --sort), infeasible then failed after. "
    "A grasp that fails is a row with its reason; one deeper than max_penetration is evaluated and flagged. "
    "--verify also simulates every grasp in MuJoCo (DexGraspBench's hold test, the speed test at "
    "0.8, 1.0, 1.2 alpha per direction: docs/physics-check.md#whole-datasets) and writes NAME-auc.csv, "
    "NAME-auc.json and NAME-auc.png."
)

MAX_HOLD_SECONDS = 10.0
"""``--push-time``: the longest push of the hold test (40,000 MuJoCo steps per direction)."""


def add_rank(sub: Subparsers) -> None:
    """``mjtvm rank GRASP DATASET...`` or ``mjtvm rank --grasp GRASP DATASET...``."""
    p = command(sub, "rank", _HELP, _DESCRIPTION)
    p.add_argument(
        "grasp_file",
        nargs="?",
        default=None,
        type=source,
        metavar="GRASP",
        help="a mjtvm.grasp/1 file or a shipped grasp's name (or --grasp)",
    )
    p.add_argument(
        "datasets", type=input_path, nargs="+", metavar="DATASET", help="dataset files, or folders of them"
    )
    grasp_option(p, default=None)
    dataset_options(p)
    limit_horizon_option(p)
    parallel_options(p)
    out_options(p, name="rank")
    resume_option(p)
    no_plots_option(p)
    rank_order_options(p)
    p.add_argument(
        "--verify",
        action="store_true",
        help="also simulate every grasp: the hold test and the speed test (the sim_* columns), and the "
        "ROC AUC of each measure against them (NAME-auc.csv, .json, .png)",
    )
    push = p.add_argument(
        "--push-time",
        type=number(0.0, MAX_HOLD_SECONDS, strict=True, unit="seconds"),
        default=None,
        metavar="SECONDS",
        help="with --verify: how long each of the hold test's six pushes lasts",
    )
    computed_default(push, "DexGraspBench's 2 s")
    quiet_option(p)
    p.set_defaults(func=_cmd_rank)


def _cmd_rank(args: argparse.Namespace) -> int:
    from mjtvm.jobs.rank_files import RankFiles, run_rank_files

    grasp, datasets = _grasp_and_datasets(args.grasp_file, args.grasp, args.datasets)
    if args.push_time is not None and not args.verify:
        raise OptionError("--push-time", "is the length of --verify's hold test: give --verify too")
    run = RankFiles(
        grasp=grasp,
        datasets=datasets,
        out=args.out,
        name=args.name,
        jobs=args.jobs,
        cluster=args.cluster,
        resume=args.resume,
        quiet=args.quiet,
        plots=not args.no_plots,
        limit_horizon=args.limit_horizon,
        pose=args.pose,
        dataset_key=args.dataset_key,
        com_frame=args.com_frame,
        refuse_penetration=args.refuse_penetration,
        measures=args.measures,
        sort=args.sort,
        verify=args.verify,
        hold_time=args.push_time,
    )
    for path in run_rank_files(run, emit=emit):
        wrote(path)
    return EXIT_OK


def _grasp_and_datasets(
    positional: str | None, option: str | None, datasets: list[Path]
) -> tuple[str, tuple[str, ...]]:
    """The grasp (GRASP or ``--grasp``, one of them: [`one_grasp()`][mjtvm.cli.options.one_grasp])
    and the datasets. With ``--grasp``, argparse gives the first word to GRASP: a dataset file
    unless it names a grasp (``.toml``, a ``mjtvm.grasp/1`` JSON file, a shipped name)."""
    from mjtvm.cli.solve import is_grasp_source

    if option is not None and positional is not None and not is_grasp_source(positional):
        try:
            datasets = [input_path(positional), *datasets]
        except argparse.ArgumentTypeError as e:
            raise OptionError("DATASET", str(e)) from e
        positional = None
    return one_grasp(positional, option), tuple(str(p) for p in datasets)
