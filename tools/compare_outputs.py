r"""Record the CLI's outputs on every shipped grasp and state, or compare two such records.

A refactoring that moves code must not change what ``mjtvm`` prints. This script runs the
installed ``mjtvm`` (through ``python -m mjtvm.cli``, so the interpreter's own package) on:

* ``mjtvm solve`` and ``mjtvm export-state`` for every shipped state
  (``mjtvm/data/examples/*.json``), every shipped grasp file (``*/*.toml`` in the models
  folder) and the paper's names ``case1``, ``case1-s``, ``case2``;
* ``mjtvm tvms case1``;
* ``mjtvm replay --no-plots --states 4`` (the default grasp, Case 2, with its sweeps);

and writes each command's exit code, standard output and error, and output files to a folder,
with the timing fields removed (they differ between any two runs).

Usage::

    python tools/compare_outputs.py record DIR
    python tools/compare_outputs.py --compare OLD NEW

``--compare`` prints every differing file with a unified diff and exits 1 on any difference,
0 when the two folders hold the same files with the same contents.
"""

from __future__ import annotations

import argparse
import csv
import difflib
import io
import json
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

# Fields that measure time, not results: removed before the outputs are stored.
TIMING_KEYS = frozenset({"timings", "assemble_s", "solve_s", "total_s", "wall_s", "elapsed_s"})


def _package_dirs() -> tuple[Path, Path]:
    """Return the installed package's examples folder and models folder."""
    import mjtvm.data
    from mjtvm.grasp.resolve.file import models_root

    data = Path(mjtvm.data.__file__).resolve().parent
    models = models_root().resolve()
    return data / "examples", models


def _strip(value: Any) -> Any:
    """Return ``value`` without its timing fields, recursively."""
    if isinstance(value, dict):
        return {k: _strip(v) for k, v in value.items() if k not in TIMING_KEYS}
    if isinstance(value, list):
        return [_strip(v) for v in value]
    return value


def _clean_json(text: str) -> str:
    """Return JSON text without timings, re-indented, or ``text`` unchanged when it is no JSON."""
    try:
        value = json.loads(text)
    except ValueError:
        return text
    return json.dumps(_strip(value), indent=1, sort_keys=True) + "\n"


def _clean_csv(text: str) -> str:
    """Return CSV text without its timing columns."""
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return text
    keep = [i for i, name in enumerate(rows[0]) if name not in TIMING_KEYS]
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    for row in rows:
        writer.writerow([row[i] for i in keep if i < len(row)])
    return out.getvalue()


def _run(args: list[str], folder: Path, name: str, replace: dict[str, str] | None = None) -> None:
    """Run ``mjtvm ARGS`` and store its exit code, cleaned output and error as ``folder/name.*``."""
    proc = subprocess.run(
        [sys.executable, "-m", "mjtvm.cli", *args], capture_output=True, text=True, check=False
    )
    out, err = proc.stdout, proc.stderr
    for old, new in (replace or {}).items():
        out, err = out.replace(old, new), err.replace(old, new)
    (folder / f"{name}.rc").write_text(f"{proc.returncode}\n", encoding="utf-8")
    (folder / f"{name}.out.json").write_text(_clean_json(out), encoding="utf-8")
    (folder / f"{name}.err.txt").write_text(err, encoding="utf-8")
    sys.stdout.write(f"{name}: exit {proc.returncode}\n")


def record(folder: Path) -> None:
    """Run every command and write the cleaned outputs to ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    examples, models = _package_dirs()
    inputs: list[tuple[str, str]] = [(f"example-{p.stem}", str(p)) for p in sorted(examples.glob("*.json"))]
    inputs += [(f"grasp-{p.parent.name}-{p.stem}", str(p)) for p in sorted(models.glob("*/*.toml"))]
    inputs += [(f"name-{n}", n) for n in ("case1", "case1-s", "case2")]
    # Paths are stored relative to the package so that moving the folders changes no record.
    replace = {str(examples): "EXAMPLES", str(models): "MODELS"}
    for name, arg in inputs:
        _run(["solve", arg], folder, f"solve-{name}", replace)
        if not name.startswith("example-"):
            _run(["export-state", arg], folder, f"export-{name}", replace)
    _run(["tvms", "case1", "--quiet"], folder, "tvms-case1", replace)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "replay"
        _run(
            ["replay", "--out", str(out), "--no-plots", "--states", "4", "--quiet"],
            folder,
            "replay",
            {**replace, str(out): "OUT"},
        )
        # The run's lock file holds a process id, not a result.
        for path in sorted(p for p in out.glob("*") if not p.name.startswith(".")):
            text = path.read_text(encoding="utf-8")
            cleaned = _clean_csv(text) if path.suffix == ".csv" else _clean_json(text)
            (folder / f"replay-{path.name}").write_text(cleaned, encoding="utf-8")


def compare(old: Path, new: Path) -> int:
    """Print the differences between two records; return 1 if they differ, else 0."""
    names_old = {p.name for p in old.iterdir()}
    names_new = {p.name for p in new.iterdir()}
    differ = 0
    for name in sorted(names_old ^ names_new):
        sys.stdout.write(f"only in {'OLD' if name in names_old else 'NEW'}: {name}\n")
        differ = 1
    for name in sorted(names_old & names_new):
        a = (old / name).read_text(encoding="utf-8").splitlines(keepends=True)
        b = (new / name).read_text(encoding="utf-8").splitlines(keepends=True)
        if a != b:
            differ = 1
            sys.stdout.writelines(difflib.unified_diff(a, b, f"OLD/{name}", f"NEW/{name}", n=2))
    sys.stdout.write("outputs differ\n" if differ else "identical\n")
    return differ


def main(argv: list[str] | None = None) -> int:
    """Parse the command line and record or compare; return the exit code."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--compare", nargs=2, metavar=("OLD", "NEW"), help="diff two recorded folders")
    parser.add_argument("record", nargs="*", metavar="record DIR", help="record into DIR")
    args = parser.parse_args(argv)
    if args.compare:
        return compare(Path(args.compare[0]), Path(args.compare[1]))
    if len(args.record) != 2 or args.record[0] != "record":
        parser.error("give `record DIR` or `--compare OLD NEW`")
    record(Path(args.record[1]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
