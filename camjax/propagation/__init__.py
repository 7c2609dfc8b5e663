"""Solution paths for the SDOF response: exact propagation and diffrax."""

from ._exact import eigenvalue as eigenvalue
from ._exact import propagate as propagate
from ._exact import psi as psi
from ._grid import MotionGrid as MotionGrid
from ._grid import default_resolution as default_resolution
from ._grid import motion_grid as motion_grid
from ._ode import ADAPTIVE_SOLVERS as ADAPTIVE_SOLVERS
from ._ode import FIXED_STEP_SOLVERS as FIXED_STEP_SOLVERS
from ._ode import MAX_FREE_VIBRATION_GROWTH as MAX_FREE_VIBRATION_GROWTH
from ._ode import SOLVERS as SOLVERS
from ._ode import free_vibration_growth as free_vibration_growth
from ._ode import sdof_term as sdof_term
from ._ode import vector_field as vector_field
from ._response import Metrics as Metrics
from ._response import Response as Response
from ._response import SolveOptions as SolveOptions
from ._response import SolverError as SolverError
from ._response import batch_metrics as batch_metrics
from ._response import residual_vibration as residual_vibration
from ._response import response_metrics as response_metrics
from ._response import solve as solve
from ._response import torsion_factor as torsion_factor
