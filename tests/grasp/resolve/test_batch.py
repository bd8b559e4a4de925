"""The bounded model cache of `BatchModels`."""

from __future__ import annotations

import pytest

from mjtvm.grasp.document.document import read_grasp_document
from mjtvm.grasp.resolve.batch import MODEL_CACHE_SIZE, BatchModels
from mjtvm.grasp.resolve.file import shipped_grasps


def test_the_model_cache_keeps_the_most_recently_used_and_recompiles_the_same() -> None:
    doc, path = read_grasp_document(shipped_grasps()["shadow_hand-sphere"])
    batch = BatchModels(doc, path, cache_size=2)
    m1, m2 = batch.model(scale=1.0), batch.model(scale=1.1)
    assert batch.model(scale=1.0) is m1  # a hit, and now the most recent
    m3 = batch.model(scale=1.2)  # evicts scale 1.1, the least recently used
    assert len(batch._models) == 2 and batch.model(scale=1.0) is m1 and batch.model(scale=1.2) is m3
    again = batch.model(scale=1.1)  # recompiled: another model, the same one
    assert again is not m2
    assert again.geom("ball").size[0] == pytest.approx(m2.geom("ball").size[0]) == pytest.approx(0.025 * 1.1)
    assert again.body("ball").mass[0] == m2.body("ball").mass[0]
    assert len(batch._models) == 2


def test_the_default_cache_is_bounded() -> None:
    doc, path = read_grasp_document(shipped_grasps()["shadow_hand-sphere"])
    batch = BatchModels(doc, path)
    for k in range(MODEL_CACHE_SIZE + 5):
        batch.model(scale=1.0 + 0.01 * k)
    assert batch.cache_size == MODEL_CACHE_SIZE and len(batch._models) == MODEL_CACHE_SIZE
