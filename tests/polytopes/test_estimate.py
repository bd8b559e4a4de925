"""The randomized volume: the binomial interval in closed form, its coverage, and on a real TVMS.

* Clopper-Pearson with no or all successes has the closed form (alpha/2)^(1/n).
* A box S = [-s, s]^k inside O = [-1, 1]^k with an exact ray-shooting oracle: vol(S) = (2s)^k
  lies in the interval in at least the confidence's share of seeded runs (a union bound over
  the looks makes it conservative), and points broken by a hyperplane already found need no LP.
* The spatial random state's TVMS (5-D, its exact volume from the LP projection): the
  estimate from a coarse outer polytope, with the real LPs, holds the exact volume.
"""

from __future__ import annotations

import json
import math
from importlib import resources

import jsonschema
import numpy as np
import pytest

import mjtvm.polytopes.refine as refine_module
from benchmarks.synthetic import random_state
from mjtvm.errors import ParamError
from mjtvm.polytopes.bracket import outer_volume
from mjtvm.polytopes.budget import Budget, Limits
from mjtvm.polytopes.estimate import VolumeEstimate, clopper_pearson, estimate_volume
from mjtvm.polytopes.polar import PolarHull
from mjtvm.polytopes.tvms import tvms


def test_clopper_pearson_closed_forms():
    n, alpha = 10, 0.05
    assert clopper_pearson(0, n, alpha) == pytest.approx((0.0, 1 - (alpha / 2) ** (1 / n)), rel=1e-12)
    assert clopper_pearson(n, n, alpha) == pytest.approx(((alpha / 2) ** (1 / n), 1.0), rel=1e-12)
    lo, hi = clopper_pearson(50, 100, alpha)
    assert lo < 0.5 < hi and lo == pytest.approx(1 - hi, rel=1e-12)  # symmetric at p = 1/2


def box_shooter(s: float):
    """Ray shooting from 0 into [-s, s]^k: t = min(1, s / |d|_inf), the face's normal."""

    def shoot(d):
        i = int(np.argmax(np.abs(d)))
        t = min(1.0, s / abs(d[i]))
        a = np.zeros(len(d))
        a[i] = np.sign(d[i])
        return t, a

    return shoot


def test_interval_covers_a_box_at_the_confidence():
    k, s, confidence = 4, 0.9, 0.9
    eye = np.eye(k)
    lattice = PolarHull(np.vstack([eye, -eye]), np.ones(2 * k), np.zeros(k), 1e-12).lattice()
    truth = (2 * s) ** k
    runs, misses = 60, 0
    for seed in range(runs):
        e = estimate_volume(
            lattice,
            box_shooter(s),
            np.zeros(k),
            1e-12,
            (0.0, 2.0**k),
            Budget(),
            tolerance=0.05,
            confidence=confidence,
            seed=seed,
        )
        assert e.stopped_by == "tolerance" and e.width <= 0.05
        assert e.lower <= e.value <= e.upper
        assert e.lps < e.samples  # points beyond a face found already: no LP
        misses += not (e.lower <= truth <= e.upper)
    # At most 10 % misses expected; 15 of 60 has probability < 1e-3 at p = 0.1.
    assert misses <= 15


def test_interval_is_clipped_to_the_certified_bracket():
    k = 3
    eye = np.eye(k)
    lattice = PolarHull(np.vstack([eye, -eye]), np.ones(2 * k), np.zeros(k), 1e-12).lattice()
    truth = 1.8**k
    e = estimate_volume(
        lattice,
        box_shooter(0.9),
        np.zeros(k),
        1e-12,
        (truth * 0.999, truth * 1.001),
        Budget(),
        tolerance=0.01,
        confidence=0.999,
    )
    assert truth * 0.999 <= e.lower <= e.value <= e.upper <= truth * 1.001
    with pytest.raises(ParamError, match=r"^confidence: "):
        VolumeEstimate(1.0, 0.0, 2.0, 1.0, 1, 1, 1, 0.0, "tolerance")


def spatial():
    return random_state(0, space=3, fingers=3, joints_per_finger=3, friction_edges=6)


@pytest.fixture(scope="module")
def exact():
    state = spatial()
    r = tvms(state, rvds_cone=False)
    assert r.status == "bounded" and r.dimension == 5
    return state, r


def test_estimate_holds_the_exact_volume_of_a_tvms(exact, monkeypatch):
    """The cutting planes get no time (REFINE_SHARE = 0): the estimate starts from the first
    outer polytope (the support LPs' box and the seeds' hull) and must still hold the volume."""
    state, r = exact
    monkeypatch.setattr(refine_module, "REFINE_SHARE", 0.0)
    seen: list[dict] = []
    a = tvms(state, rvds_cone=False, tolerance=0.02, time_limit=600.0, progress=seen.append)
    assert a.status == "approximate" and a.stopped_by[0] == "time"
    e = a.volume_estimate
    assert e is not None and e.stopped_by == "tolerance" and e.width <= 0.02
    lo, hi = a.affine_volume_bracket
    assert lo <= e.lower <= e.value <= e.upper <= hi
    assert (hi - lo) / hi > 0.02  # the bracket alone was wider
    assert e.lower <= r.affine_volume <= e.upper
    assert any(d.get("phase") == "estimate" for d in seen)
    schema = json.loads(
        resources.files("mjtvm.data").joinpath("schema").joinpath("tvms.schema.json").read_text()
    )
    doc = json.loads(json.dumps(a.to_dict(), allow_nan=False))
    jsonschema.validate(doc, schema)
    assert doc["volume_estimate"]["value"] == 0.0  # 5-D in 6-D: no 6-D volume
    assert doc["volume_estimate"]["affine_interval"] == [e.lower, e.upper]
    # confidence 0: no estimate, the bracket alone
    b = tvms(state, rvds_cone=False, tolerance=0.02, time_limit=600.0, confidence=0.0)
    assert b.volume_estimate is None


def test_confidence_is_checked():
    with pytest.raises(Exception, match="confidence"):
        Limits(confidence=1.0)
    assert math.isclose(Limits().confidence, 0.0)


def test_loose_outer_polytope_is_cut_down_first():
    """S = [-0.3, 0.3]^3 in O = [-1, 1]^3 (2.7 % of it): the hyperplanes found cut O down, the
    certified outer volume comes down with it, and the interval still holds vol(S); when
    cutting is refused (too costly), the sampling goes on in the loose O."""
    k, s = 3, 0.3
    eye = np.eye(k)
    truth = (2 * s) ** k
    polar = PolarHull(np.vstack([eye, -eye]), np.ones(2 * k), np.zeros(k), 1e-12)
    calls: list[int] = []

    def tighten(normals, offsets):
        calls.append(len(offsets))
        polar.add(normals, offsets)
        return outer_volume(polar, Budget())  # the certified bound (the joggle's inflation)

    e = estimate_volume(
        polar.lattice(),
        box_shooter(s),
        np.zeros(k),
        1e-12,
        (0.0, 8.0),
        Budget(),
        tolerance=0.05,
        confidence=0.999,
        tighten=tighten,
    )
    assert calls and e.outer == pytest.approx(truth, rel=1e-6)  # the box's own faces were found
    assert e.lower <= truth <= e.upper and e.width <= 0.05
    loose = PolarHull(np.vstack([eye, -eye]), np.ones(2 * k), np.zeros(k), 1e-12).lattice()
    e = estimate_volume(
        loose,
        box_shooter(s),
        np.zeros(k),
        1e-12,
        (0.0, 8.0),
        Budget(),
        tolerance=0.2,
        confidence=0.999,
        tighten=lambda n, o: None,
    )
    assert e.outer == 8.0 and e.lower <= truth <= e.upper and e.width <= 0.2
