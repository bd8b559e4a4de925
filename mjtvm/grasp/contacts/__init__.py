"""What touches the object in a MuJoCo model: contact detection and geom labels, exact
distances between geom pairs, contact normals, geom shapes and the contact report of a
loaded grasp. May import the ``document`` floor of ``mjtvm.grasp``, not the floors above.
"""

__all__: list[str] = []
