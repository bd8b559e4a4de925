r"""The grasp file and everything it loads: the ``mjtvm.grasp/1`` document and its checks, the
MJCF model with the object, the configuration (keyframe, joint values or IK), the contacts
MuJoCo detects, each joint's operation range (a motor or servo datasheet, ``<dcmotor>``, polygon) and the
[`GraspState`][mjtvm.model.state.GraspState] read from ``mjData``; datasets of configurations on one grasp
file ([`dataset`][mjtvm.grasp.document.dataset], [`batch`][mjtvm.grasp.resolve.batch]).

Floors, top first (import-linter keeps them): ``resolve`` (the loader, the state, IK,
batches) above ``actuation`` (operation ranges, transmissions) above ``contacts`` (what
touches) above ``document`` (the file's format, no MuJoCo model). The room may import
``mjtvm.model``, ``mjtvm.formats``, ``mjtvm.errors`` and MuJoCo. Everything else is
importable from its module.
"""

from mjtvm.grasp.actuation.dcmotor import DCMotor
from mjtvm.grasp.actuation.servo import ServoDatasheet
from mjtvm.grasp.document.checks import GraspError, NoContactError
from mjtvm.grasp.document.dataset import DatasetGrasp, read_dataset
from mjtvm.grasp.document.document import read_grasp_document
from mjtvm.grasp.resolve.batch import BatchModels, hand_joints
from mjtvm.grasp.resolve.file import export_state, load_grasp, shipped_grasps
from mjtvm.grasp.resolve.ik import solve_ik
from mjtvm.grasp.resolve.loaded import Grasp
from mjtvm.grasp.resolve.state import grasp_state

__all__ = [
    "BatchModels",
    "DCMotor",
    "DatasetGrasp",
    "Grasp",
    "GraspError",
    "NoContactError",
    "ServoDatasheet",
    "export_state",
    "grasp_state",
    "hand_joints",
    "load_grasp",
    "read_dataset",
    "read_grasp_document",
    "shipped_grasps",
    "solve_ik",
]
