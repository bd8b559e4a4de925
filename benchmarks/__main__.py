"""``python -m benchmarks`` (from a clone; not installed with the package): the suite of [`benchmarks.suite`][benchmarks.suite], its report
([`benchmarks.report`][benchmarks.report]) printed and written to NAME.json and NAME.md."""

from __future__ import annotations

import argparse
import contextlib
import json
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from mjtvm.cli import guarded
from mjtvm.cli.options import Parser, computed_default, removed_option
from mjtvm.cli.output import EXIT_OK, emit
from mjtvm.cli.values import (
    MAX_BASELINE_REPEATS,
    MAX_NOTES_BYTES,
    MAX_REPEATS,
    input_file,
    integer,
    integers,
    shown,
)
from mjtvm.cli.vocabulary import out_options, quiet_option, time_limit_option
from mjtvm.errors import StateError

__all__ = ["add_arguments", "main"]


_DESCRIPTION = (
    "Time the paper's cases (Problem 1 and 2) against the cvxpy and cdd baselines, the full lift, "
    "the Fig. 9 sweeps on 1 and 2 processes, synthetic hands of 2-16 fingers and the dataset scale "
    "(grasps/s of batches of 22-joint states, mjtvm solve as a process); write NAME.json and NAME.md "
    "to --out."
)


def main(argv: list[str] | None = None) -> int:
    """``python -m benchmarks [options]``: the exit codes and one-line errors of ``mjtvm``."""
    parser = Parser(prog="python -m benchmarks", description=_DESCRIPTION)
    add_arguments(parser)
    return guarded(lambda: parser.parse_args(argv), _cmd_bench)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``python -m benchmarks`` (the vocabulary of ``docs/cli.md``)."""
    parser.add_argument("--quick", action="store_true", help="skip Case 2's Problem 1 and every cdd run")
    parser.add_argument(
        "--repeats",
        type=integer(1, MAX_REPEATS),
        default=200,
        metavar="N",
        help="timed calls per Problem 2 state",
    )
    parser.add_argument(
        "--baseline-repeats",
        type=integer(1, MAX_BASELINE_REPEATS),
        default=10,
        metavar="N",
        help="timed cvxpy calls per state",
    )
    sizes = parser.add_argument(
        "--rank-sizes",
        type=integers(1, 10_000_000),
        default=None,
        metavar="N,N,...",
        help="grasps of the generated datasets of the `mjtvm rank` memory rows; the largest also "
        "runs on a local Dask cluster of 2 worker processes",
    )
    computed_default(sizes, "400,4000 with --quick, else 400,4000,40000")
    time_limit_option(parser)
    out_options(parser, name="bench")
    removed_option(parser, "--md", "the table is NAME.md beside NAME.json in --out")
    notes = parser.add_argument(
        "--notes",
        type=input_file,
        default=None,
        metavar="FILE",
        help="text file whose lines are appended to the table's notes "
        f"(at most {MAX_NOTES_BYTES >> 20} MiB of UTF-8 text)",
    )
    computed_default(notes, "none")
    quiet_option(parser)


def _steps(quick: bool, sizes: int) -> int:
    """How many ``say`` steps [`run_suite()`][benchmarks.suite.run_suite] announces (the progress bar's total)."""
    cases = 3 if quick else 4
    rank = 5 + sizes + 1  # throughput (2 hands), P2 floor, fingers, jobs, one per memory size, the Dask run
    return cases + 5 + rank  # the lift, the sweeps, the scaling, the peers, the dataset scale


def _read_notes(path: Path | None) -> list[str]:
    """The lines of the ``--notes`` file (none without one), read up to [`MAX_NOTES_BYTES`][benchmarks.__main__.MAX_NOTES_BYTES]."""
    if path is None:
        return []
    try:
        with path.open("rb") as f:
            raw = f.read(MAX_NOTES_BYTES + 1)  # bounded: a device or a huge file is refused
    except OSError as e:
        raise StateError("--notes", f"cannot read {shown(str(path))} ({e.strerror or e})") from e
    if len(raw) > MAX_NOTES_BYTES:
        raise StateError(
            "--notes", f"expected a text file of at most {MAX_NOTES_BYTES} bytes, got a larger one"
        )
    try:
        return raw.decode("utf-8").rstrip().splitlines()
    except UnicodeDecodeError as e:
        raise StateError(
            "--notes", f"expected UTF-8 text, got byte 0x{raw[e.start]:02x} at offset {e.start}"
        ) from e


@contextlib.contextmanager
def _step_bar(total: int, quiet: bool) -> Iterator[Callable[[str], None]]:
    """A progress bar on stderr, advanced as the suite announces its next step; full on success."""
    from tqdm import tqdm

    bar = tqdm(total=total, desc="bench", unit="step", disable=quiet)
    started: list[str] = []

    def step(text: str) -> None:  # a step's name is announced at its start: count the previous one
        if started:
            bar.update()
        started.append(text)
        bar.set_description_str(f"bench: {text}")

    try:
        yield step
        bar.update(bar.total - bar.n)
    finally:
        bar.close()


def _cmd_bench(args: argparse.Namespace) -> int:
    """Run the suite with parsed options, print the table, write NAME.json and NAME.md atomically.

    The output folder is checked and locked before the run (which takes minutes).

    Raises
    ------
    OutputError
        ``--out`` cannot be written or another run holds its lock.
    StateError
        The ``--notes`` file cannot be read.
    """
    from benchmarks import report as bench_report
    from benchmarks import suite
    from mjtvm.formats.files import check_output_dir, output_lock, write_files

    outdir = check_output_dir(args.out)
    extra = _read_notes(args.notes)
    with output_lock(outdir):
        n_sizes = len(args.rank_sizes) if args.rank_sizes else 2 if args.quick else 3
        with _step_bar(_steps(args.quick, n_sizes), args.quiet) as step:
            report: dict[str, Any] = suite.run_suite(
                quick=args.quick,
                rank_sizes=args.rank_sizes,
                repeats=args.repeats,
                baseline_repeats=args.baseline_repeats,
                time_limit=args.time_limit,
                progress=step,
            )
        notes = bench_report.auto_notes(report) + extra
        table = bench_report.format_suite_table(report, notes)
        report["notes"] = notes
        out_json, out_md = outdir / f"{args.name}.json", outdir / f"{args.name}.md"
        write_files({out_json: json.dumps(report, indent=1) + "\n", out_md: "```\n" + table + "\n```\n"})
    emit(table)
    emit(f"wrote {out_json} and {out_md}")
    return EXIT_OK


if __name__ == "__main__":  # the guard matters: the 2-process sweep's workers re-import this module
    raise SystemExit(main())
