"""`contacts_once`: the same contacts as a fresh detection, detected anew when anything they depend on changes."""

from __future__ import annotations

import copy

import mujoco
import numpy as np

from mjtvm.grasp.contacts import memo
from mjtvm.grasp.contacts.memo import contacts_once
from mjtvm.grasp.contacts.touch import detected_contacts
from mjtvm.grasp.resolve.file import load_grasp


def _fresh(grasp, **kw):  # type: ignore[no-untyped-def]
    return detected_contacts(grasp.model, copy.copy(grasp.data), **kw)


def test_once_equals_a_fresh_detection_and_follows_the_configuration(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    grasp = load_grasp("allegro-sphere")
    kw = {"object_body": grasp.object_body, "one_per_body": True, "tolerance": grasp.contact_tolerance}
    calls = []
    real = memo.detected_contacts
    monkeypatch.setattr(memo, "detected_contacts", lambda *a, **k: calls.append(1) or real(*a, **k))
    memo._MEMO.clear()
    first, again = contacts_once(grasp.model, grasp.data, **kw), contacts_once(grasp.model, grasp.data, **kw)
    assert len(calls) == 1 and [c.geom for c in first] == [c.geom for c in again]
    want = _fresh(grasp, **kw)
    assert [(c.geom, c.distance) for c in first] == [(c.geom, c.distance) for c in want]
    assert np.array_equal(np.array([c.position for c in first]), np.array([c.position for c in want]))
    # another tolerance, another configuration, a geometry changed in place: detected anew
    contacts_once(grasp.model, grasp.data, **{**kw, "tolerance": 2 * grasp.contact_tolerance})
    assert len(calls) == 2
    data = copy.copy(grasp.data)
    data.qpos[:] = data.qpos + 0.05
    mujoco.mj_forward(grasp.model, data)
    moved = contacts_once(grasp.model, data, **kw)
    assert len(calls) == 3 and [c.geom for c in moved] == [c.geom for c in _fresh_of(grasp.model, data, kw)]
    saved = grasp.model.geom_size.copy()
    try:
        grasp.model.geom_size[:] = saved * 1.01
        contacts_once(grasp.model, grasp.data, **kw)
        assert len(calls) == 4
    finally:
        grasp.model.geom_size[:] = saved
    assert len(memo._MEMO) <= memo.MEMO_SIZE


def _fresh_of(model, data, kw):  # type: ignore[no-untyped-def]
    return detected_contacts(model, copy.copy(data), **kw)
