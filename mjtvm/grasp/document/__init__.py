"""The ``mjtvm.grasp/1`` document, without a MuJoCo model: reading a grasp (or dataset) file,
its value and section checks, `GraspError`, the JSON Schema check and the TOML writer. The
bottom floor of ``mjtvm.grasp``: it imports no other floor of the room.
"""

__all__: list[str] = []
