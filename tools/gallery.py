r"""The pictures of ``docs/gallery.md``: one per command, on shipped grasps, into docs/gallery/.

Usage: ``python tools/gallery.py --write`` (run every command below, copy its picture) or
``--check`` (every picture exists, is under 150 KB, and the page shows each one, no other).

``show``, ``replay``, ``verify`` and ``rank`` draw their own pictures; ``solve`` and ``tvms``
print JSON (mjtvm.result/1, mjtvm.tvms/1), which this script draws in the package's one style
([`mjtvm.jobs.style`][mjtvm.jobs.style]): the alphas per RVDS vertex, and three 2-D
projections of the TVMS vertices. Every command runs with fixed inputs (one job, no
randomness), so a rerun gives the same pictures up to the matplotlib and MuJoCo versions.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "gallery"
PAGE = ROOT / "docs" / "gallery.md"
LIMIT = 150_000
RANK = ("models/shadow_hand/shadow_hand_coupled-sphere.toml", "mjtvm/data/examples/shadow-sphere-dataset.npz")
PICTURES = {
    "show.png": "mjtvm show case2 --png show.png",  # then 256 colours
    "solve.png": "mjtvm solve case2 > solve.json; python tools/gallery.py --write",
    "tvms.png": "mjtvm tvms case2 > tvms.json; python tools/gallery.py --write",
    "replay.png": "mjtvm replay --states 12 --out results  # results/fig8.png",
    "verify.png": "mjtvm verify --states 1 --out results  # results/verify.png",
    "rank.png": f"mjtvm rank {RANK[0]} {RANK[1]} --jobs 1 --out results  # results/rank-epsilon.png",
}
"""Each picture and the command that regenerates it (the page's captions name these)."""


def _mjtvm(*words: str) -> str:
    from mjtvm.cli import main

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(list(words))
    if code != 0:
        raise SystemExit(f"mjtvm {' '.join(words)}: exit {code}")
    return buf.getvalue()


def solve_png(result: dict[str, Any], name: str) -> bytes:
    """Solve's witness: alpha per RVDS vertex l, one bar group per REFS k, the limiting pair marked."""
    import numpy as np

    from mjtvm.jobs.figures import ALPHA_UNIT, X_LABELS
    from mjtvm.jobs.style import figure, finish, png

    alpha = np.array([[np.nan if a is None else a for a in row] for row in result["alpha"]], dtype=float)
    fig, ax = figure(6.0, 4.0)
    n_k, n_l = alpha.shape
    width = 0.8 / n_k
    for k in range(n_k):
        ax.bar(np.arange(n_l) + (k - 0.5 * (n_k - 1)) * width, alpha[k], width=width, label=f"REFS k = {k}")
    k, l = result["limiting"]
    ax.plot(
        [l + (k - 0.5 * (n_k - 1)) * width],
        [1.05 * alpha[k, l]],
        "v",
        color="black",
        ms=7,
        label="limiting pair (the TVMMP)",
    )
    ax.set_xticks(range(n_l))
    ax.set_ylim(bottom=0.0, top=1.15 * np.nanmax(alpha))
    title = f"{name}: TVMMP = {result['tvmmp']:.3f} (the smallest alpha)"
    finish(fig, ax, xlabel=X_LABELS["l"], ylabel=rf"$\alpha_{{kl}}$ {ALPHA_UNIT}", title=title)
    return png(fig)  # type: ignore[no-any-return]


def tvms_png(tvms: dict[str, Any], name: str) -> bytes:
    """The TVMS polytope's vertices (object twists) projected on the planes vx-vy, vx-vz, vy-vz."""
    import numpy as np
    from scipy.spatial import ConvexHull

    from mjtvm.jobs.style import figure, finish, png

    v = np.array(tvms["vertices"], dtype=float)
    fig, axes = figure(9.0, 3.6, (1, 3))
    names = ("$v_x$ (m/s)", "$v_y$ (m/s)", "$v_z$ (m/s)")
    for ax, (i, j) in zip(axes[0], ((0, 1), (0, 2), (1, 2)), strict=True):
        xy = v[:, [i, j]]
        if len(xy) >= 3 and np.linalg.matrix_rank(xy - xy.mean(axis=0)) == 2:
            hull = ConvexHull(xy)
            ring = np.r_[hull.vertices, hull.vertices[:1]]
            ax.fill(xy[ring, 0], xy[ring, 1], alpha=0.25, color="tab:blue")
            ax.plot(xy[ring, 0], xy[ring, 1], "-", color="tab:blue", lw=1.0)
        ax.plot(xy[:, 0], xy[:, 1], "o", color="tab:blue", ms=3)
        ax.set_aspect("equal", adjustable="datalim")
        ax.margins(0.12)
        finish(fig, ax, xlabel=names[i], ylabel=names[j], title=f"{names[i][:5]} - {names[j][:5]}")
    fig.suptitle(f"{name}: TVMS, {len(v)} vertices (dimension {tvms['dimension']}), linear part", fontsize=10)
    return png(fig)  # type: ignore[no-any-return]


def _palette(path: Path) -> None:
    """Reduce a rendered picture to 256 colours (the page's size limit), as rerun_screenshot.py does."""
    from PIL import Image

    with Image.open(path) as image:
        small = image.convert("RGB").quantize(
            colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
        )
    small.save(path, optimize=True)


def write() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    os.environ.setdefault("MUJOCO_GL", "egl")
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        _mjtvm("show", "case2", "--png", str(OUT / "show.png"))
        _palette(OUT / "show.png")
        (OUT / "solve.png").write_bytes(solve_png(json.loads(_mjtvm("solve", "case2", "--quiet")), "case2"))
        (OUT / "tvms.png").write_bytes(tvms_png(json.loads(_mjtvm("tvms", "case2", "--quiet")), "case2"))
        _mjtvm("replay", "--states", "12", "--out", str(t / "replay"), "--quiet")
        shutil.copy(t / "replay" / "fig8.png", OUT / "replay.png")
        _mjtvm("verify", "--states", "1", "--out", str(t / "verify"), "--quiet")
        shutil.copy(t / "verify" / "verify.png", OUT / "verify.png")
        _mjtvm("rank", *(str(ROOT / p) for p in RANK), "--jobs", "1", "--out", str(t / "rank"), "--quiet")
        shutil.copy(t / "rank" / "rank-epsilon.png", OUT / "rank.png")


def check() -> list[str]:
    """What is wrong with the gallery, one line each (empty: nothing)."""
    page = PAGE.read_text(encoding="utf-8")
    out = []
    for name, command in PICTURES.items():
        path = OUT / name
        if not path.is_file():
            out.append(f"{path.relative_to(ROOT)}: missing (python tools/gallery.py --write)")
        elif path.stat().st_size > LIMIT:
            out.append(f"{path.relative_to(ROOT)}: {path.stat().st_size} bytes > {LIMIT}")
        if f"(gallery/{name})" not in page:
            out.append(f"docs/gallery.md: does not show gallery/{name}")
        if command.split(";")[0].split("  #")[0] not in page:
            out.append(f"docs/gallery.md: does not name the command of {name}: {command}")
    for path in sorted(OUT.glob("*.png")):
        if path.name not in PICTURES:
            out.append(f"{path.relative_to(ROOT)}: not a picture of the gallery")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", action="store_true", help="regenerate docs/gallery/*.png")
    mode.add_argument("--check", action="store_true", help="check the pictures and the page")
    args = parser.parse_args(argv)
    if args.write:
        write()
    problems = check()
    for line in problems:
        print(line, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
