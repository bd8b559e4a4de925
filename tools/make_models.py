r"""Write the committed MJCF models (``models/paper_hand/*.xml``) from :func:`mjtvm.paper_hand.hand.model_files`.

Usage: ``python tools/make_models.py [OUTPUT_DIR]`` (default: the repository's
``models/paper_hand/``). ``tests/paper_hand/test_hand.py`` checks that the committed files equal this output.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mjtvm.paper_hand.hand import model_files


def main(argv: list[str] | None = None) -> int:
    """Write every model file; return the process exit code."""
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0]) if args else Path(__file__).resolve().parent.parent / "models" / "paper_hand"
    out.mkdir(parents=True, exist_ok=True)
    for name, text in model_files().items():
        (out / name).write_text(text, encoding="utf-8")
        sys.stdout.write(f"wrote {out / name}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
