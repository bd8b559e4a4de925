"""Exit codes, standard output (flushed per line; a closed pipe ends quietly) and the LP spinner."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from mjtvm.errors import OutputError

__all__ = [
    "EXIT_FAILURE",
    "EXIT_INPUT",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_PIPE",
    "EXIT_SOLVER",
    "LISTED",
    "bracket_progress",
    "emit",
    "grouped",
    "help_hint",
    "lp_progress",
    "one_line",
    "stdout_to_devnull",
    "warn",
    "warn_uncertified",
    "wrote",
]

EXIT_OK, EXIT_FAILURE, EXIT_INPUT, EXIT_SOLVER, EXIT_INTERRUPTED, EXIT_PIPE = 0, 1, 2, 3, 130, 141


def one_line(text: str) -> str:
    """``text`` with every non-printable character escaped as ``repr`` would (a newline as
    ``\\n``, a lone surrogate as ``\\ud800``): an error stays one line, and stderr never
    meets a character it cannot encode."""
    return "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in text)


def stdout_to_devnull() -> None:
    """Point file descriptor 1 at /dev/null so that the interpreter's final flush is silent
    (the recipe of Python's signal documentation for SIGPIPE)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # captured in-process: nothing to redirect
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def _write_all(text: str) -> None:
    """Write ``text`` to stdout, all of it, and flush.

    Unbuffered (``PYTHONUNBUFFERED=1``, ``python -u``), ``sys.stdout.write`` hands the bytes to
    the raw file, whose partial write (a pipe whose reader left: 64 KiB of 140 kB written)
    the text layer ignores: the rest would be lost without an error, and ``mjtvm tvms | head
    -c 1`` would exit 0. Writing to the binary layer until every byte is taken makes the next
    write after a partial one raise ``BrokenPipeError``.
    """
    stream = sys.stdout
    buffer = getattr(stream, "buffer", None)
    if buffer is None:  # a text stream without a binary layer (a test's StringIO)
        stream.write(text)
        stream.flush()
        return
    stream.flush()  # what the text layer holds goes first
    data = memoryview(text.encode(stream.encoding or "utf-8", stream.errors or "strict"))
    while data:
        n = buffer.write(data)
        if n is None:  # a non-blocking raw stdout that is full: what a buffered one raises
            raise BlockingIOError("standard output is full and non-blocking")
        data = data[n:]
    buffer.flush()


def emit(text: str) -> None:
    """Print a line to stdout and flush, so that a full or closed stdout is reported here
    (``BrokenPipeError``: [`mjtvm.cli.main()`][mjtvm.cli.main] exits 141)."""
    try:
        _write_all(text + "\n")
    except BrokenPipeError:
        raise
    except OSError as e:
        stdout_to_devnull()
        raise OutputError(
            "standard output", getattr(sys.stdout, "name", "<stdout>"), f"cannot write ({e.strerror or e})"
        ) from e


def wrote(path: object, note: str | None = None, *, stderr: bool = False) -> None:
    """The line of every command that wrote a file: ``wrote PATH`` or ``wrote PATH (NOTE)``
    (``(0.52 s)``), on stdout, or on stderr where stdout carries a report (``show``)."""
    text = f"wrote {path}" + (f" ({note})" if note else "")
    if stderr:
        print(one_line(text), file=sys.stderr, flush=True)
    else:
        emit(text)


def help_hint(prog: str) -> str:
    """The hint of every usage error, after its message: ``(try 'mjtvm sweep --help')``."""
    return f"(try '{prog} --help')"


def warn(text: str) -> None:
    """One line on stderr, ``mjtvm: warning: ...`` (escaped to one line)."""
    print(one_line(f"mjtvm: warning: {text}"), file=sys.stderr, flush=True)


LISTED = 5
"""Subjects a grouped warning names before "and N more"."""


def grouped(items: Iterable[tuple[str, str]], noun: str = "pairs") -> list[tuple[str, str, int]]:
    """``(subjects, cause, count)`` per distinct cause of ``(subject, cause)`` items, in first-seen
    order: ``subjects`` the one subject, or the first ``LISTED`` of them,
    ``and N more`` where there are more, and the count (``"alpha[0][0], alpha[0][1] (2 pairs)"``)."""
    causes: dict[str, list[str]] = {}
    for subject, cause in items:
        causes.setdefault(cause, []).append(subject)
    out = []
    for cause, subjects in causes.items():
        text = ", ".join(subjects[:LISTED])
        if len(subjects) > LISTED:
            text += f" and {len(subjects) - LISTED} more"
        n = len(subjects)
        out.append((text if n == 1 else f"{text} ({n} {noun})", cause, n))
    return out


def warn_uncertified(result: Any) -> None:
    """One stderr line per note of the pairs of a [`TvmmpResult`][mjtvm.problem2.result.TvmmpResult]
    whose answer is not certified, naming and counting them (the JSON holds each pair's
    ``certified`` and ``notes``)."""
    pairs = [(f"alpha[{k}][{l}]", str(result.note((k, l)))) for k, l in result.uncertified()]
    for subjects, note, n in grouped(pairs):
        warn(f"{subjects} {'is' if n == 1 else 'are'} not certified: {note}")


@contextlib.contextmanager
def lp_progress(enabled: bool, desc: str) -> Iterator[None]:
    """A spinner on stderr counting the HiGHS solves (Problem 1 does not know their number
    in advance: the projection adds facets until the polytope closes)."""
    if not enabled:
        yield
        return
    from tqdm import tqdm

    from mjtvm.lp.highs import observe_runs

    bar = tqdm(desc=desc, unit=" LP", file=sys.stderr, mininterval=0.25, leave=False)
    try:
        with observe_runs(lambda _seconds: bar.update()):
            yield
    finally:
        bar.close()


@contextlib.contextmanager
def bracket_progress(enabled: bool) -> Iterator[Callable[[dict[str, Any]], None] | None]:
    """A line on stderr with Problem 1's volume bracket as it narrows (the ``progress`` callback
    of [`tvms()`][mjtvm.polytopes.tvms.tvms]), or ``None`` when disabled."""
    if not enabled:
        yield None
        return
    from tqdm import tqdm

    # the line is the description: tqdm's {postfix} starts with ", " ("bracket: , [...")
    bar = tqdm(desc="bracket", bar_format="{desc}", file=sys.stderr, leave=False)

    def show(d: dict[str, Any]) -> None:
        if d.get("phase") == "estimate":
            bar.set_description_str(
                f"bracket: estimate in [{d['lower']:.6g}, {d['upper']:.6g}] width {100 * d['width']:.3g} %, "
                f"{d['samples']} points, {d['lps']} LPs, {d['seconds']:.1f} s"
            )
            return
        bar.set_description_str(
            f"bracket: [{d['inner']:.6g}, {d['outer']:.6g}] gap {100 * d['gap']:.3g} %, Hausdorff "
            f"{d['hausdorff']:.3g}, round {d['round']}, {d['lps']} LPs, {d['seconds']:.1f} s"
        )

    try:
        yield show
    finally:
        bar.close()
