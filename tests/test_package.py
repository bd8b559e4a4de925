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


def _without_cvxpy(code: str) -> subprocess.CompletedProcess[str]:
    """Run ``code`` in a child where ``import cvxpy`` fails, as on ``pip install .`` alone."""
    return subprocess.run(
        [sys.executable, "-c", "import sys; sys.modules['cvxpy'] = None\n" + code],
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_a_solve_and_a_grasp_solve_need_no_cvxpy():
    """cvxpy is the ``reference`` extra: the main commands run without it."""
    code = "from mjtvm.cli import main\nraise SystemExit(main(['solve', 'allegro-ik']))"
    out = _without_cvxpy(code)
    assert out.returncode == 0, out.stderr
    assert '"tvmmp"' in out.stdout


def test_the_reference_without_cvxpy_is_one_line_naming_the_extra():
    out = _without_cvxpy("from benchmarks.__main__ import main\nraise SystemExit(main(['--quick']))")
    assert out.returncode == 2
    assert (
        out.stderr.strip()
        .splitlines()[-1]
        .endswith('cvxpy is not installed: pip install -e ".[reference]" in a clone')
    )
    assert "Traceback" not in out.stderr
