"""``mjtvm show GRASP``: look before you solve. The contact report of a grasp as loaded (every
geom near the object: distance, normal, type, selected or why not) as a table or JSON, its
warnings and problems on stderr, and a rerun recording that needs no lift or solve."""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import TYPE_CHECKING, Any

from mjtvm.cli.lift import check_file_folder
from mjtvm.cli.options import Subparsers, command, computed_default
from mjtvm.cli.output import EXIT_OK, emit, warn, wrote
from mjtvm.cli.values import number, source
from mjtvm.cli.vocabulary import (
    GRASP_HELP,
    grasp_option,
    hand_option,
    indent_option,
    one_grasp,
    png_option,
    rrd_option,
)
from mjtvm.errors import ModelError
from mjtvm.formats import atomic_write

if TYPE_CHECKING:
    from mjtvm.grasp.contacts.report import ContactRow
    from mjtvm.grasp.resolve.loaded import Grasp

__all__ = ["COLUMNS", "add_show", "report_document", "warn_contacts"]

#: The table's columns (header, width); the JSON rows hold the same fields (docs/outputs.md).
COLUMNS = (
    ("geom", 22),
    ("body", 16),
    ("object_geom", 14),
    ("distance_mm", 12),
    ("normal", 26),
    ("type", 6),
    ("selected", 9),
    ("why", 0),
)
_MAX_WITHIN_MM = 100.0


def add_show(sub: Subparsers) -> None:
    """``mjtvm show GRASP [--json] [--within MILLIMETRES] [--rrd FILE]``."""
    p = command(
        sub,
        "show",
        "look before you solve: a grasp's contacts (distances, normals, types) and a rerun recording",
        "Load a grasp (no state, no LP) and print every geom near the object: the geom, its body, "
        "the object's geom, the exact distance (mm; negative: penetration), the normal into the "
        "object, the file's type, whether the state selects the contact and why not. Penetration and "
        "IK targets that do not touch are warned about on stderr, as is what would stop "
        "export-state (the table is printed first).",
    )
    p.add_argument("grasp_file", nargs="?", default=None, type=source, metavar="GRASP", help=GRASP_HELP)
    grasp_option(p, default=None)
    hand_option(p)
    within = p.add_argument(
        "--within",
        type=number(0.0, _MAX_WITHIN_MM, unit="mm"),
        default=None,
        metavar="MILLIMETRES",
        help="list the geoms within this distance of the object (mm)",
    )
    computed_default(within, "10 contact tolerances, at least 1 mm")
    p.add_argument("--json", action="store_true", help="print the report as JSON instead of a table")
    indent_option(p)
    rrd_option(p)
    png_option(p)
    p.set_defaults(func=_cmd_show)


def warn_contacts(grasp: Grasp) -> None:
    """A stderr warning per line of [`contact_warnings()`][mjtvm.grasp.contacts.report.contact_warnings]."""
    from mjtvm.grasp.contacts.report import contact_warnings

    for line in contact_warnings(grasp):
        warn(line)


def _row(r: ContactRow) -> dict[str, Any]:
    return {
        "geom": r.geom,
        "body": r.body,
        "object_geom": r.object_geom,
        "distance": r.distance,
        "position": [float(x) for x in r.position],
        "normal": None if r.normal is None else [float(x) for x in r.normal],
        "type": r.type,
        "selected": r.selected,
        "why": r.why or None,
    }


def report_document(
    grasp: Grasp, rows: list[ContactRow], within: float, problem: str | None
) -> dict[str, Any]:
    """The JSON of ``mjtvm show --json`` (``docs/outputs.md``)."""
    from mjtvm.grasp.contacts.report import contact_warnings

    return {
        "grasp": grasp.name,
        "contact_tolerance": grasp.contact_tolerance,
        "max_penetration": float(grasp.document["max_penetration"]),  # the loader's default filled in
        "within": within,
        "contacts": [_row(r) for r in rows],
        "warnings": contact_warnings(grasp),
        "problem": problem,
    }


def _cell(value: Any, width: int) -> str:
    text = "-" if value is None or value == "" else str(value)
    return text.ljust(width) if width else text


def _table(rows: list[ContactRow]) -> list[str]:
    lines = ["  ".join(_cell(h, w) for h, w in COLUMNS).rstrip()]
    for r in rows:
        normal = None if r.normal is None else " ".join(f"{round(float(x), 3) + 0.0:+.3f}" for x in r.normal)
        distance = f"{round(1e3 * r.distance, 6) + 0.0:.4g}"
        values = (
            r.geom,
            r.body,
            r.object_geom,
            distance,
            normal,
            r.type,
            "yes" if r.selected else "no",
            r.why,
        )
        lines.append("  ".join(_cell(v, w) for v, (_, w) in zip(values, COLUMNS, strict=True)).rstrip())
    return lines


def _cmd_show(args: argparse.Namespace) -> int:
    if args.png is not None:  # MuJoCo picks its GL back end when imported: headless, EGL
        os.environ.setdefault("MUJOCO_GL", "egl")
    from mjtvm.grasp import load_grasp  # MuJoCo only here
    from mjtvm.grasp.contacts.report import NEAR_TOLERANCES, contact_rows

    source = one_grasp(args.grasp_file, args.grasp)
    check_file_folder(args.rrd, "--rrd")
    check_file_folder(args.png, "--png")
    grasp = load_grasp(source, hand=args.hand)
    tol = grasp.contact_tolerance
    within = max(NEAR_TOLERANCES * tol, 1e-3) if args.within is None else 1e-3 * args.within
    rows = contact_rows(grasp, within)
    try:
        grasp.check_contacts()
        problem = None
    except ModelError as e:  # a GraspError, shown, not raised: the report is what helps to fix it
        problem = str(e)
    if args.json:
        emit(json.dumps(report_document(grasp, rows, within, problem), indent=args.indent))
    else:
        emit(
            f"{grasp.name}: contact_tolerance {1e3 * tol:g} mm, geoms within {1e3 * within:g} mm of the object"
        )
        for line in _table(rows):
            emit(line)
    warn_contacts(grasp)
    if problem is not None:
        warn(f"the grasp's state would be refused: {problem}")
    if args.rrd is not None:
        _record(grasp, rows, args.rrd)
    if args.png is not None:
        _picture(grasp, args.png)
    sys.stdout.flush()
    return EXIT_OK


def _record(grasp: Grasp, rows: list[ContactRow], path: str) -> None:
    from mjtvm.grasp.contacts.shapes import geom_shapes
    from mjtvm.viewer.grasp_view import record_grasp  # rerun: only with --rrd

    record_grasp(
        path, geom_shapes(grasp.model, grasp.data, grasp.object_body), rows, grasp.mu, name=grasp.name
    )
    wrote(path, stderr=True)  # stdout: the report


def _picture(grasp: Grasp, path: str) -> None:
    from mjtvm.grasp.contacts.picture import render_grasp
    from mjtvm.jobs.figures import grasp_png

    picture = render_grasp(grasp.model, grasp.data, grasp.object_body, grasp.contact_tolerance, mu=grasp.mu)
    atomic_write(
        path,
        grasp_png(picture, f"{grasp.name}: contacts within {1e3 * grasp.contact_tolerance:g} mm"),
        option="--png",
    )
    wrote(path, stderr=True)  # stdout: the report
