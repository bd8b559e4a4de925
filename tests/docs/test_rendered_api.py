"""The API page renders: docstrings use Markdown cross-references and TeX math, not Sphinx roles."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# A Sphinx role (:func:`x`) or directive (.. math::) that mkdocstrings would print as raw text.
SPHINX = re.compile(r":(?:py:)?(?:func|class|meth|attr|mod|data|obj|exc|math|ref):`|^\s*\.\. [a-z]+::", re.M)


def test_the_checker_sees_a_role() -> None:
    assert SPHINX.search("see :func:`~mjtvm.problem2.tvmmp.tvmmp`")
    assert SPHINX.search("x\n.. math:: a = b\n")
    assert not SPHINX.search("see [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp] and $a = b$")


def test_no_sphinx_roles_in_docstrings() -> None:
    hits = [
        f"{path.relative_to(ROOT)}: {m.group(0)}"
        for path in sorted((ROOT / "mjtvm").rglob("*.py"))
        for m in SPHINX.finditer(path.read_text(encoding="utf-8"))
    ]
    assert not hits, f"{len(hits)} Sphinx roles (write [`name`][dotted.path] or $tex$): {hits[:5]}"
