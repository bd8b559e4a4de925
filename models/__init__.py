"""The shipped hands, one folder each: MJCF models and their ``mjtvm.grasp/1`` grasp files.

Installed as ``mjtvm.models`` (``pyproject.toml`` maps the package to this folder); a grasp
file here is loaded by name (``mjtvm solve allegro-ik``, :func:`mjtvm.load_grasp`).
"""
