r"""Which rooms of ``mjtvm`` a command enters, in order (docs/architecture.md, "Two commands").

Runs ``mjtvm ARGS`` in this process under ``sys.setprofile`` and prints each room the first
time a function of it is called, with the module and function it entered by and the room that
called it; then how many calls crossed into each room. Standard output of the command goes to
``/dev/null``.

Usage (from the repository root)::

    python tools/trace_rooms.py solve allegro-ik
    python tools/trace_rooms.py rank shadow_hand_coupled-sphere DATASET --out /tmp/rank
"""

from __future__ import annotations

import collections
import contextlib
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = str(ROOT / "mjtvm") + os.sep


def _room(filename: str) -> tuple[str, str] | None:
    if not filename.startswith(PACKAGE):
        return None
    parts = Path(filename[len(PACKAGE) :]).with_suffix("").parts
    room = "mjtvm." + parts[0]
    if room == "mjtvm.grasp" and len(parts) > 2:
        room += "." + parts[1]
    return room, "mjtvm." + ".".join(p for p in parts if p != "__init__")


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(ROOT))
    from mjtvm.cli import main as mjtvm_main

    first: dict[str, str] = {}
    crossings: collections.Counter[str] = collections.Counter()
    stack: list[str | None] = []
    modules: set[str] = set()

    def profile(frame, event, arg):  # type: ignore[no-untyped-def]
        if event == "call":
            where = _room(frame.f_code.co_filename)
            caller = next((r for r in reversed(stack) if r is not None), None)
            room = where[0] if where else None
            if where is not None:
                modules.add(where[1])
            stack.append(room)
            if room is not None and room != caller and frame.f_code.co_name != "<module>":
                crossings[room] += 1
                if room not in first:
                    first[room] = f"{where[1]}.{frame.f_code.co_name}  (from {caller or 'the command line'})"
        elif event == "return" and stack:
            stack.pop()

    with open(os.devnull, "w") as null, contextlib.redirect_stdout(null):
        sys.setprofile(profile)
        try:
            code = mjtvm_main(argv)
        finally:
            sys.setprofile(None)
    print(f"mjtvm {' '.join(argv)}: exit {code}")
    for i, (room, how) in enumerate(first.items(), 1):
        print(f"{i:2d}. {room:24s} {how}")
    print(f"{len(modules)} modules of the package ran code")
    print("calls into each room from another:", ", ".join(f"{r} {n}" for r, n in crossings.most_common()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
