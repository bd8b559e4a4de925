"""The package: public API, and the core importing without MuJoCo or rerun."""

from __future__ import annotations

import subprocess
import sys

import mjtvm


def test_public_api_is_exported():
    for name in mjtvm.__all__:
        assert hasattr(mjtvm, name), name
    assert callable(mjtvm.tvmmp) and callable(mjtvm.tvms) and callable(mjtvm.load_state)


def test_core_imports_without_mujoco_or_rerun():
    """The core (states, Problems 1 and 2, the solve CLI) must not import the coupling libraries."""
    code = (
        "import sys, mjtvm, mjtvm.cli; "
        "print(sorted(m for m in ('mujoco', 'rerun', 'cvxpy', 'matplotlib') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_every_package_is_installed():
    """pyproject.toml lists the packages by hand (models/ is mapped to mjtvm.models): none missing."""
    import tomllib
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    listed = set(
        tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]["packages"]
    )
    found = {".".join(p.parent.relative_to(root).parts) for p in (root / "mjtvm").rglob("__init__.py")}
    assert found | {"mjtvm.models"} == listed
    assert (root / "models" / "__init__.py").is_file()
