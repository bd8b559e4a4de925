r"""The hand variants of the shipped grasps: ``case2`` with the humanlike hand is the shipped
grasp ``case2-humanlike`` (``--hand``, ``docs/cli.md``).

Only the paper's grasps (`VARIANT_GRASPS`) have a second hand; any other grasp file or name is
loaded as given, with the hand ``"default"``. The grasp loader resolves the name, so a command
reaches every grasp, the paper's too, through [`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp].
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mjtvm.errors import ModelError

__all__ = ["HANDS", "VARIANT_GRASPS", "grasp_file_name", "with_hand"]

#: The shipped grasps (in ``models/paper_hand/``) that have a grasp of each hand in `HANDS`.
VARIANT_GRASPS = ("case1", "case1-s", "case2")
#: The paper's two hands: its default fingers and the humanlike ones (Fig. 8).
HANDS = ("default", "humanlike")


def grasp_file_name(name: str, hand: str) -> str:
    """The shipped grasp file of a paper grasp and hand: ``case2.toml``, ``case2-humanlike.toml``."""
    return f"{name}.toml" if hand == "default" else f"{name}-{hand}.toml"


def with_hand(source: str | Path | Mapping[str, Any], hand: str) -> str | Path | Mapping[str, Any]:
    """The grasp of ``source`` with the hand ``hand``: a paper grasp's name becomes the name of
    its grasp with that hand (``case2`` + ``humanlike``: ``case2-humanlike``); any other grasp as
    given, with the hand ``"default"`` only.

    Raises
    ------
    ModelError
        An unknown hand of a paper grasp, or a hand other than ``"default"`` for another grasp.
    """
    if isinstance(source, str) and source in VARIANT_GRASPS:
        if hand not in HANDS:
            raise ModelError(f"scenario {source!r}", f"no variant {hand!r} (has: {', '.join(HANDS)})")
        return grasp_file_name(source, hand)[: -len(".toml")]
    if hand != "default":
        raise ModelError("variant", f"applies to the shipped scenarios ({', '.join(VARIANT_GRASPS)}) only")
    return source
