r"""Classic grasp measures beside TVMMP, without MuJoCo (``docs/measures.md``).

[`classic_measures()`][mjtvm.measures.classic.classic_measures] gives a [`GraspMeasures`][mjtvm.measures.classic.GraspMeasures]: force closure, the Ferrari-Canny
epsilons, the grasp matrix's smallest singular value, Yoshikawa's hand-object
manipulability and the kinematic velocity polytope's volume of one
[`GraspState`][mjtvm.model.state.GraspState]. The wrench measures live in
[`wrenches`][mjtvm.measures.wrenches], the kinematic ones (such as
[`kinematic_polytope()`][mjtvm.measures.kinematics.kinematic_polytope]) in [`kinematics`][mjtvm.measures.kinematics].
This room imports only the rooms below it (``polytopes`` and lower), never MuJoCo, rerun or
matplotlib.
"""

from mjtvm.measures.classic import GraspMeasures, classic_measures

__all__ = ["GraspMeasures", "classic_measures"]
