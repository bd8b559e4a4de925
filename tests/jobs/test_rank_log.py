"""``mjtvm.jobs.rank_log``: the append log of a ranking, its torn last line, the id digests."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mjtvm.errors import StateError
from mjtvm.jobs.rank_log import LOG_SCHEMA, IdSet, RankLog, id_hash


def test_rows_appended_read_back_by_offset(tmp_path: Path) -> None:
    log = RankLog(tmp_path / "r.partial.jsonl", every_s=0.0)
    assert log.start([{"id": "a", "x": 1.5}]) == 1
    log.append([{"id": "b", "x": float("nan")}, {"id": "c", "x": [1, None]}])
    log.close()
    lines = (tmp_path / "r.partial.jsonl").read_text().splitlines()
    assert json.loads(lines[0]) == {"schema": LOG_SCHEMA} and len(lines) == 4
    entries = list(log.entries())
    assert [r["id"] for _, r in entries] == ["a", "b", "c"]
    with log.reader() as read:
        assert read(entries[2][0]) == {"id": "c", "x": [1, None]}
        assert read(entries[0][0]) == {"id": "a", "x": 1.5}
    log.remove()
    assert not (tmp_path / "r.partial.jsonl").exists()


def test_a_torn_last_line_is_dropped_a_torn_middle_line_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "r.partial.jsonl"
    log = RankLog(path)
    log.start([{"id": "a"}, {"id": "b"}])
    log.close()
    whole = path.read_bytes()
    path.write_bytes(whole + b'{"id": "c", "x"')
    assert [r["id"] for _, r in log.entries()] == ["a", "b"]
    # start() keeps what it is given and drops the torn tail.
    kept = [r for _, r in log.entries()]
    log.start(kept)
    log.close()
    assert path.read_bytes() == whole
    path.write_bytes(whole.replace(b'{"id":"a"}', b'{"id":"a"'))
    with pytest.raises(StateError, match=r"line at byte \d+ is not a row .*run again without --resume"):
        list(log.entries())
    path.write_text('{"schema": "mjtvm.rank-checkpoint/1"}\n')
    with pytest.raises(StateError, match=r"not a checkpoint of schema mjtvm\.rank-checkpoint/2"):
        list(log.entries())


def test_id_set_holds_digests_and_positions() -> None:
    ids = [f"grasp-{i}" for i in range(1000)]
    s = IdSet((id_hash(i) for i in ids), range(1000, 2000))
    assert len(s) == 1000 and len(s.repeated()) == 0
    assert s.lookup("grasp-17") == 1017 and "grasp-999" in s
    assert s.lookup("grasp-1000") is None and "grasp-1000" not in s and 3 not in s
    twice = IdSet(id_hash(i) for i in ["a", "b", "a"])
    assert list(twice.repeated()) == [id_hash("a")]
    assert id_hash("a") == int.from_bytes(
        __import__("hashlib").blake2b(b"a", digest_size=8).digest(), "little"
    )
