"""`mjtvm tvms` options of the anytime projection: --tolerance, --time-limit, --memory."""

from __future__ import annotations

import json

import pytest

from mjtvm.cli import main
from mjtvm.cli.values import memory_size
from mjtvm.polytopes.budget import available_memory


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--tolerance", "1"),
        ("--tolerance", "-0.1"),
        ("--tolerance", "nan"),
        ("--time-limit", "0"),
        ("--time-limit", "inf"),
        ("--memory", "0"),
        ("--memory", "12X"),
        ("--memory", "0%"),
        ("--memory", "150%"),
    ],
)
def test_bad_values_are_one_line_naming_the_option(option, value, capsys):
    assert main(["tvms", "case1", option, value]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and option in err[0] and repr(value) in err[0]


def test_memory_sizes():
    assert memory_size("512M") == 512 * 2**20
    assert memory_size("2G") == memory_size("2GiB") == memory_size("2gb") == 2 * 2**30
    assert memory_size("1000") == 1000
    assert memory_size("50%") == pytest.approx(available_memory() / 2, rel=0.2)


def test_tolerance_gives_an_approximate_document(capsys):
    assert main(["tvms", "allegro-sphere", "--tolerance", "0.05", "--quiet", "--indent", "0"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["status"] == "approximate" and doc["stopped_by"]["reason"] == "tolerance"
    lo, hi = doc["affine_volume_bracket"]
    assert 0 < lo <= hi and (hi - lo) / hi <= 0.05
    # The exact 3-D volume (one Qhull hull of the 1500 exact vertices) lies inside.
    assert lo <= 0.3819047 <= hi
