"""The formats on disk: the state file (``mjtvm.state/1`` and ``/2``), its JSON schema, and output files.

[`load_state()`][mjtvm.formats.state_file.load_state] reads and checks a state file into a
[`GraspState`][mjtvm.model.state.GraspState], [`dump_state()`][mjtvm.formats.state_file.dump_state]
writes one; ``schema`` holds the shipped JSON schemas, ``files`` the atomic writes and the
output directory's lock.

This room imports only ``mjtvm.model`` and the rooms below it (import-linter's layers in
``pyproject.toml``).
"""

from mjtvm.formats.files import atomic_write, write_files
from mjtvm.formats.schema import load_schema
from mjtvm.formats.state_file import dump_state, load_state, parse_state, state_to_dict

__all__ = [
    "atomic_write",
    "dump_state",
    "load_schema",
    "load_state",
    "parse_state",
    "state_to_dict",
    "write_files",
]
