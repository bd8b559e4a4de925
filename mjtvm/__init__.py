r"""mjtvm: joint torque-velocity pair based manipulability (Watanabe) on top of MuJoCo.

The core (this namespace) needs neither MuJoCo nor rerun: grasp states, operation
ranges, contacts, and Problem 2 (TVMMP). The MuJoCo coupling lives in its own modules.
"""

from .assembly import Assembly, assemble
from .contacts import CONTACT_TYPES, Contact, force_generators, tangent_basis
from .errors import MjtvmError, ModelError, SolverError, StateError
from .operation_range import OperationRange, default_operation_range, load_motor_data
from .state import GraspState, dump_state, load_state, parse_state, state_to_dict
from .tvmmp import Timings, TvmmpResult, Witness, tvmmp

__version__ = "0.1.0"

__all__ = [
    "CONTACT_TYPES",
    "Assembly",
    "Contact",
    "GraspState",
    "MjtvmError",
    "ModelError",
    "OperationRange",
    "SolverError",
    "StateError",
    "Timings",
    "TvmmpResult",
    "Witness",
    "assemble",
    "default_operation_range",
    "dump_state",
    "force_generators",
    "load_motor_data",
    "load_state",
    "parse_state",
    "state_to_dict",
    "tangent_basis",
    "tvmmp",
]
