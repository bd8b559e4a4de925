"""A grasp file resolved against its MuJoCo model: the loader, the model with the object, the
configuration (keyframe, joint values, IK), contact rules, the grasp state and batches of
configurations. The top floor of ``mjtvm.grasp``: it may import every floor below.
"""

__all__: list[str] = []
