r"""The grasp file and everything it loads: the ``mjtvm.grasp/1`` document and its checks, the
MJCF model with the object, the configuration (keyframe, joint values or IK), the contacts
MuJoCo detects, each joint's operation range (a motor or servo datasheet, ``<dcmotor>``, polygon) and the
[`GraspState`][mjtvm.core.state.GraspState] read from ``mjData``; datasets of configurations on one grasp
file ([`dataset`][mjtvm.sim.grasp.dataset], [`batch`][mjtvm.sim.grasp.batch]).
"""

from .actuator import operation_range_from_actuator
from .batch import BatchModels, hand_joints
from .checks import GraspError
from .dataset import DatasetGrasp, read_dataset
from .dcmotor import DCMotor
from .document import SCHEMA, format_toml, read_grasp_document
from .file import export_state, grasp_from_model, load_grasp, shipped_grasps
from .ik import IkResult, IkTarget, geom_contact_target, solve_ik
from .loaded import Grasp
from .model import build_spec
from .ranges import joint_ranges
from .rules import RuleMatch, expand_rules
from .servo import ServoDatasheet
from .state import DetectedContact, detected_contacts, grasp_state, object_weight

__all__ = [
    "SCHEMA",
    "BatchModels",
    "DCMotor",
    "DatasetGrasp",
    "DetectedContact",
    "Grasp",
    "GraspError",
    "IkResult",
    "IkTarget",
    "RuleMatch",
    "ServoDatasheet",
    "build_spec",
    "detected_contacts",
    "expand_rules",
    "export_state",
    "format_toml",
    "geom_contact_target",
    "grasp_from_model",
    "grasp_state",
    "hand_joints",
    "joint_ranges",
    "load_grasp",
    "object_weight",
    "operation_range_from_actuator",
    "read_dataset",
    "read_grasp_document",
    "shipped_grasps",
    "solve_ik",
]
