"""Documents one change away from a valid one, to test a loader against its JSON Schema."""

from __future__ import annotations

import copy
from collections.abc import Iterator, Mapping, Sequence
from typing import Any


def paths(node: Any, path: tuple[Any, ...] = (), *, every_item: bool = True) -> Iterator[tuple[Any, ...]]:
    """Every key path of ``node``; with ``every_item=False`` only the first and last item of
    every list (long numeric lists are alike)."""
    yield path
    items: Any = node.items() if isinstance(node, dict) else ()
    if isinstance(node, list):
        keep = range(len(node)) if every_item else sorted({0, len(node) - 1} if node else set())
        items = [(i, node[i]) for i in keep]
    for key, value in items:
        yield from paths(value, (*path, key), every_item=every_item)


def mutations(
    doc: dict[str, Any], values: Sequence[Any], extra: Mapping[str, Any], *, every_item: bool = True
) -> Iterator[dict[str, Any]]:
    """``doc`` with one field set to each of ``values``, or deleted, or one table joined by
    one key of ``extra`` it lacks."""
    for path in paths(doc, every_item=every_item):
        node: Any = doc
        for key in path:
            node = node[key]
        if path:
            for value in [*values, _DELETE]:
                out = copy.deepcopy(doc)
                parent = out
                for key in path[:-1]:
                    parent = parent[key]
                if value is _DELETE:
                    del parent[path[-1]]
                else:
                    parent[path[-1]] = copy.deepcopy(value)
                yield out
        if isinstance(node, dict):
            for key, value in extra.items():
                if key not in node:
                    out = copy.deepcopy(doc)
                    target = out
                    for k in path:
                        target = target[k]
                    target[key] = copy.deepcopy(value)
                    yield out


_DELETE = object()
