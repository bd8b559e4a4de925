r"""The scripted lift (paper section 5, Fig. 7-8): the object's prescribed motion, the
predictor-corrector that keeps the fingers on its surface, and the grasp states along it.

Imports ``mjtvm.grasp`` (a loaded grasp), ``mjtvm.model`` and MuJoCo; the paper's hand
(``mjtvm.paper_hand``) only to load a scenario named by a string. Everything else is
importable from its module.
"""

from mjtvm.lift.motion import Motion
from mjtvm.lift.states import lift_state, slide_directions
from mjtvm.lift.trajectory import Lift, LiftSpec, scripted_lift

__all__ = [
    "Lift",
    "LiftSpec",
    "Motion",
    "lift_state",
    "scripted_lift",
    "slide_directions",
]
