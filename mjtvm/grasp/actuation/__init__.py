"""How a model's joints are driven: operation ranges from actuators, DC motors and servo
datasheets, the file's ``ranges``, and the transmission of coupled actuators and equality
constraints. May import the ``contacts`` and ``document`` floors of ``mjtvm.grasp``.
"""

__all__: list[str] = []
