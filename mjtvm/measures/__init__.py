r"""Classic grasp measures beside TVMMP, without MuJoCo (``docs/measures.md``).

:func:`classic_measures` gives a :class:`GraspMeasures`: force closure, the Ferrari-Canny
epsilons, the grasp matrix's smallest singular value, Yoshikawa's hand-object
manipulability and the kinematic velocity polytope's volume of one
:class:`~mjtvm.core.state.GraspState`. The wrench measures live in
:mod:`~mjtvm.measures.wrenches`, the kinematic ones in :mod:`~mjtvm.measures.kinematics`.
"""

from .classic import GraspMeasures, classic_measures

__all__ = ["GraspMeasures", "classic_measures"]
