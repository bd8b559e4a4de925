r"""The grasp file and everything it loads: the ``mjtvm.grasp/1`` document and its checks, the
MJCF model with the object, the configuration (keyframe, joint values or IK), the contacts
MuJoCo detects, each joint's operation range (a motor or servo datasheet, ``<dcmotor>``, polygon) and the
[`GraspState`][mjtvm.model.state.GraspState] read from ``mjData``; datasets of configurations on one grasp
file ([`dataset`][mjtvm.grasp.document.dataset], [`batch`][mjtvm.grasp.resolve.batch]).
"""

from mjtvm.grasp.actuation.actuator import operation_range_from_actuator
from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.actuation.ranges import joint_ranges
from mjtvm.grasp.actuation.servo import ServoDatasheet
from mjtvm.grasp.document.checks import GraspError
from mjtvm.grasp.document.dataset import DatasetGrasp, read_dataset
from mjtvm.grasp.document.document import SCHEMA, format_toml, read_grasp_document
from mjtvm.grasp.resolve.batch import BatchModels, hand_joints
from mjtvm.grasp.resolve.file import export_state, grasp_from_model, load_grasp, shipped_grasps
from mjtvm.grasp.resolve.ik import IkResult, IkTarget, geom_contact_target, solve_ik
from mjtvm.grasp.resolve.loaded import Grasp
from mjtvm.grasp.resolve.model import build_spec
from mjtvm.grasp.resolve.rules import RuleMatch, expand_rules
from mjtvm.grasp.resolve.state import DetectedContact, detected_contacts, grasp_state, object_weight

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
