r"""mjtvm: joint torque-velocity pair based manipulability (Watanabe) on top of MuJoCo.

The names here are what a user calls; each lives in a room (a subpackage, the layers of
``docs/architecture.md``): the grasp states, contacts, operation ranges and transmissions
(`mjtvm.model`), the state file (`mjtvm.formats`), Problem 2 (TVMMP, [`tvmmp()`][mjtvm.problem2.tvmmp.tvmmp];
`mjtvm.problem2`, on the LP engine `mjtvm.lp`), Problem 1 (TVMS, [`tvms()`][mjtvm.polytopes.tvms.tvms];
`mjtvm.polytopes`) and the errors (`mjtvm.errors`). The core needs neither MuJoCo nor rerun.
The MuJoCo coupling (`mjtvm.grasp`, `mjtvm.lift`, `mjtvm.paper_hand`; `mjtvm.physics`) and the
rerun recording (`mjtvm.viewer`) live in their own rooms. The grasp-file names here
([`load_grasp()`][mjtvm.grasp.resolve.file.load_grasp], [`export_state()`][mjtvm.grasp.resolve.file.export_state], [`Grasp`][mjtvm.grasp.resolve.loaded.Grasp], `GraspError`,
[`shipped_grasps()`][mjtvm.grasp.resolve.file.shipped_grasps]) are imported on first use, so that ``import mjtvm`` does not load MuJoCo;
so are Problem 1 and the classic grasp measures ([`classic_measures()`][mjtvm.measures.classic.classic_measures], [`GraspMeasures`][mjtvm.measures.classic.GraspMeasures],
`mjtvm.measures`), which a solve does not need. The rest of each room's API is in its own
package (`mjtvm.model.force_generators`, `mjtvm.problem2.assemble`, ...).
"""

from typing import TYPE_CHECKING

from mjtvm._lazy import lazy_attributes
from mjtvm.errors import MjtvmError, ModelError, OptionError, OutputError, ParamError, SolverError, StateError
from mjtvm.formats import dump_state, load_state, parse_state, state_to_dict
from mjtvm.model import (
    Contact,
    GraspState,
    OperationRange,
    Transmission,
    default_operation_range,
    load_motor_data,
)
from mjtvm.problem2 import Diagnosis, TvmmpResult, Witness, tvmmp

if TYPE_CHECKING:
    from mjtvm.grasp import Grasp, GraspError, export_state, load_grasp, shipped_grasps
    from mjtvm.measures import GraspMeasures, classic_measures
    from mjtvm.polytopes.tvms import TvmsResult, tvms

__version__ = "0.1.0"

# Names of the MuJoCo layer, imported by __getattr__ on first use.
_MUJOCO_NAMES = frozenset({"Grasp", "GraspError", "export_state", "load_grasp", "shipped_grasps"})
# The classic measures (mjtvm.measures), imported on first use too.
_MEASURE_NAMES = frozenset({"GraspMeasures", "classic_measures"})

__all__ = [
    "Contact",
    "Diagnosis",
    "Grasp",
    "GraspError",
    "GraspMeasures",
    "GraspState",
    "MjtvmError",
    "ModelError",
    "OperationRange",
    "OptionError",
    "OutputError",
    "ParamError",
    "SolverError",
    "StateError",
    "Transmission",
    "TvmmpResult",
    "TvmsResult",
    "Witness",
    "classic_measures",
    "default_operation_range",
    "dump_state",
    "export_state",
    "load_grasp",
    "load_motor_data",
    "load_state",
    "parse_state",
    "shipped_grasps",
    "state_to_dict",
    "tvmmp",
    "tvms",
]


# Problem 1 (scipy.spatial, cdd) and the classic measures are imported on first use too:
# `mjtvm solve` needs neither.
__getattr__ = lazy_attributes(
    __name__,
    {
        **dict.fromkeys(_MUJOCO_NAMES, "grasp"),
        **dict.fromkeys(_MEASURE_NAMES, "measures"),
        "TvmsResult": "polytopes.tvms",
        "tvms": "polytopes.tvms",
    },
)
