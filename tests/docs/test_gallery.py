"""docs/gallery.md shows every picture ``tools/gallery.py`` makes, each present and small."""

from __future__ import annotations

from pathlib import Path

from tests.support.tools import tool_module

ROOT = Path(__file__).resolve().parents[2]


def test_gallery_is_complete() -> None:
    gallery = tool_module("gallery")
    assert gallery.check() == [], "run python tools/gallery.py --write"
