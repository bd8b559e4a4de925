r"""mjtvm: joint torque-velocity pair based manipulability (Watanabe) on top of MuJoCo.

The core (this namespace) needs neither MuJoCo nor rerun: grasp states, operation
ranges, contacts, Problem 2 (TVMMP, :func:`tvmmp`) and Problem 1 (TVMS, :func:`tvms`). The
MuJoCo coupling (``hand``, ``grasp``, ``ik``, ``scenario``, ``trajectory``, ``replay``,
``simulate``, ``verify``) and the rerun recording (``viz``, run beside the job by ``recording``)
live in their own modules.
"""

from .core.assembly import Assembly, assemble
from .core.contacts import CONTACT_TYPES, Contact, force_generators, tangent_basis
from .core.operation_range import OperationRange, default_operation_range, load_motor_data
from .core.state import GraspState, dump_state, load_state, parse_state, state_to_dict
from .core.tvmmp import Timings, TvmmpResult, Witness, tvmmp
from .errors import MjtvmError, ModelError, OptionError, OutputError, ParamError, SolverError, StateError
from .polytopes.tvms import TvmsResult, tvms

__version__ = "0.1.0"

__all__ = [
    "CONTACT_TYPES",
    "Assembly",
    "Contact",
    "GraspState",
    "MjtvmError",
    "ModelError",
    "OperationRange",
    "OptionError",
    "OutputError",
    "ParamError",
    "SolverError",
    "StateError",
    "Timings",
    "TvmmpResult",
    "TvmsResult",
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
    "tvms",
]
