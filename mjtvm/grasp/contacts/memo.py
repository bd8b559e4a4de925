r"""The object's contacts of one configuration, detected once however many checks ask.

Loading a dataset row asks for the same contacts three times before its grasp state is built
(the contact rules' touching geoms, the selections' check, the penetration check, and
``mjtvm rank``'s penetration column): each a
[`detected_contacts()`][mjtvm.grasp.contacts.touch.detected_contacts] on a scratch copy of the data, with a
tolerance, so that MuJoCo runs its collision anew. Their result depends only on the model and
on where the bodies are: [`contacts_once()`][mjtvm.grasp.contacts.memo.contacts_once] keeps the last
[`MEMO_SIZE`][mjtvm.grasp.contacts.memo.MEMO_SIZE] results keyed on the model object, the detection's options,
the positions (``qpos``, the mocap bodies' poses) and the model's geometry arrays that a caller
could change in place (geom and body poses, sizes, margins).

Each detection runs on a scratch ``mjData`` ([`scratch_copy()`][mjtvm.grasp.contacts.memo.scratch_copy]): a
copy into one this thread keeps per model, instead of a new one per detection (a new
``mjData`` allocates the model's whole arena, 15 MiB and 0.55 ms on the five-finger Shadow
hand, where the copy takes 5 us).
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import Any

import mujoco

from mjtvm.grasp.contacts.touch import DetectedContact, detected_contacts

__all__ = ["MEMO_SIZE", "contacts_once", "scratch_copy"]

MEMO_SIZE = 4  #: configurations whose contacts are kept (the last ones asked for)

_MEMO: OrderedDict[tuple[Any, ...], tuple[mujoco.MjModel, tuple[DetectedContact, ...]]] = OrderedDict()
_LOCK = threading.Lock()
_SCRATCH = threading.local()  # per thread: slot -> (the model's sizes, a scratch mjData of them)
_SIZES: list[str] = []  # MjModel's size fields (its int attributes n*): they alone lay out an mjData


def _sizes(model: mujoco.MjModel) -> tuple[int, ...]:
    if not _SIZES:
        _SIZES.extend(n for n in dir(type(model)) if n.startswith("n") and isinstance(getattr(model, n), int))
    return tuple(getattr(model, n) for n in _SIZES)


def scratch_copy(model: mujoco.MjModel, data: mujoco.MjData, slot: str) -> mujoco.MjData:
    """``data`` copied (``mj_copyData``: the same contents as ``copy.copy(data)``) into this
    thread's scratch ``mjData`` of ``slot``, allocated anew only when ``model``'s sizes differ
    from those it was allocated for: MuJoCo lays an ``mjData`` out from the model's size
    fields alone (``mj_copyData`` reads only them), so the scratch serves every model of one
    structure, e.g. the grasp file's model compiled at each object scale of a dataset. Its
    ``model`` attribute may be another such model: pass ``model`` to MuJoCo explicitly. The
    copy is the slot's until its next call: a caller that calls another user of the same
    slot before it is done with it must take its own."""
    slots = _SCRATCH.__dict__.setdefault("slots", {})
    sizes = _sizes(model)
    held = slots.get(slot)
    if held is None or held[0] != sizes:
        held = slots[slot] = (sizes, mujoco.MjData(model))
    mujoco.mj_copyData(held[1], model, data)
    return held[1]


def _key(
    model: mujoco.MjModel, data: mujoco.MjData, object_body: str, one_per_body: bool, tolerance: float
) -> tuple[Any, ...]:
    return (
        id(model), object_body, one_per_body, float(tolerance),
        data.qpos.tobytes(), data.mocap_pos.tobytes(), data.mocap_quat.tobytes(),
        model.geom_pos.tobytes(), model.geom_quat.tobytes(), model.geom_size.tobytes(),
        model.geom_margin.tobytes(), model.body_pos.tobytes(), model.body_quat.tobytes(),
    )  # fmt: skip


def contacts_once(
    model: mujoco.MjModel, data: mujoco.MjData, *, object_body: str, one_per_body: bool, tolerance: float
) -> list[DetectedContact]:
    """[`detected_contacts()`][mjtvm.grasp.contacts.touch.detected_contacts] of ``data``'s configuration on a
    scratch copy (``data`` is not modified), detected anew only when the model, the options or
    the configuration differ from the last [`MEMO_SIZE`][mjtvm.grasp.contacts.memo.MEMO_SIZE] asked for."""
    key = _key(model, data, object_body, one_per_body, tolerance)
    with _LOCK:
        hit = _MEMO.get(key)
        if hit is not None and hit[0] is model:  # the same object, not one at a reused id
            _MEMO.move_to_end(key)
            return list(hit[1])
    work = scratch_copy(model, data, "contacts")
    found = detected_contacts(
        model, work, object_body=object_body, one_per_body=one_per_body, tolerance=tolerance
    )
    with _LOCK:
        _MEMO[key] = (model, tuple(found))
        while len(_MEMO) > MEMO_SIZE:
            _MEMO.popitem(last=False)
    return found
