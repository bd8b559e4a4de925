"""`binding_balance`: the deletion filter's answer in fewer LPs, the same as `binding_joints`'."""

from __future__ import annotations

import pytest

from mjtvm.grasp.document.dataset import read_dataset
from mjtvm.grasp.resolve.batch import BatchModels, hand_joints
from mjtvm.problem2 import relaxed
from mjtvm.problem2.relaxed import binding_balance, binding_joints, solve_pair

_DATA = "mjtvm/data/examples/shadow-sphere-dataset.npz"


@pytest.mark.parametrize("index", [0, 16, 17, 6])
def test_binding_balance_equals_the_plain_deletion_filter(
    index: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    batch = BatchModels.from_file("shadow_hand_coupled-sphere")
    model = batch.model(root=True)
    entry = read_dataset(_DATA, nq=int(model.nq), num_joints=len(hand_joints(model, "ball")))[index]
    state = batch.grasp(entry).state()
    w = state.refs[0]
    r = 0.0 * state.rvds[0] if state.rvds is not None else None
    assert r is not None
    plain = binding_joints(state, lambda s: solve_pair(s, w, r, "eliminated", "highs")[0] == "optimal")
    calls: list[int] = []
    real = relaxed.solve_point
    monkeypatch.setattr(relaxed, "solve_point", lambda *a: calls.append(1) or real(*a))
    fast = binding_balance(state, w, "eliminated", "highs")
    assert fast == plain
    if plain is None:  # 6: not balanced whatever the ranges (one LP)
        assert calls == [1]
    else:  # 0, 16, 17: torque limits bind; most joints are proven free by the balance point
        assert plain and len(calls) < 1 + len(state.operation_ranges)
