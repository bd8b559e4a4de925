r"""Case 1's TVMM over finger 1's feasible postures, and the factors between ours and the paper's.

Usage: ``python tools/case1_posture.py [OUT_PNG]`` (default ``docs/case1_tvmm_posture.png``).
Plots :func:`mjtvm.paper_hand.placement.finger1_tvmm_curve` (TVMM = the scaled 4-D affine volume of
Problem 1, 1/s^4, against the elbow angle psi for fingertip contacts and against the contact's
distance from link 2's joint for contacts on link 2) with the rule's posture, the posture IK from
hand-picked start angles gives and the paper's 8.4e5 marked; prints the curve's extremes.
``docs/paper-results.md`` explains it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from mjtvm.paper_hand.placement import finger1_tvmm_curve

PAPER = 8.4e5  # 1/s^4, Case 1, all F (section 5)
PREVIOUS = 1.7436e6  # at the posture IK from hand-picked start angles gives (4 mm capsules)


def main(argv: list[str] | None = None) -> int:
    """Compute the curve, write the figure; return the exit code."""
    args = sys.argv[1:] if argv is None else argv
    out = (
        Path(args[0]) if args else Path(__file__).resolve().parent.parent / "docs" / "case1_tvmm_posture.png"
    )
    rows = finger1_tvmm_curve()
    tip = sorted((np.degrees(r["parameter"]), r["tvmm"]) for r in rows if r["contact"] == "tip")
    side = [r for r in rows if r["contact"] == "side"]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    t = np.array(tip)
    a.plot(t[:, 0], t[:, 1], "o-", ms=3, label="fingertip on the point")
    rule = t[np.argmin(np.abs(t[:, 0]))]
    a.plot(*rule, "r*", ms=14, label=f"rule: planar, elbow up ({rule[1]:.3g})")
    b.set_xlabel("contact on link 2: distance from its joint along the link (mm)")
    for lo, hi, label in ((250.0, 315.0, "link 2, branch A"), (315.0, 360.0, "link 2, branch B")):
        pts = sorted(
            (1e3 * r["along"], r["tvmm"]) for r in side if lo <= np.degrees(r["parameter"]) % 360 < hi
        )
        if pts:
            p = np.array(pts)
            b.plot(p[:, 0], p[:, 1], "o-", ms=3, label=label)
    for ax in (a, b):
        ax.axhline(PAPER, color="k", ls="--", lw=1, label="paper: 8.4e5")
        ax.axhline(
            PREVIOUS, color="grey", ls=":", lw=1, label="earlier default (start angles, 4 mm links): 1.74e6"
        )
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower right" if ax is b else "lower left")
    a.set_xlabel("fingertip contact: elbow angle psi on its circle (deg; 0 = highest, the planar posture)")
    a.set_ylabel("Case 1 TVMM, scaled 4-D volume (1/s^4)")
    fig.suptitle(
        "Case 1: TVMM against finger 1's posture (its contact on the paper's point; joint ranges respected)"
    )
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    sys.stdout.write(f"wrote {out}\n")
    values = np.array([r["tvmm"] for r in rows])
    sys.stdout.write(
        f"{len(rows)} postures: TVMM {values.min():.4g} .. {values.max():.4g} 1/s^4; fingertip "
        f"{t[:, 1].min():.4g} .. {t[:, 1].max():.4g} (psi {t[:, 0].min():g} .. {t[:, 0].max():g} deg); "
        f"rule {rule[1]:.6g}\n"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
