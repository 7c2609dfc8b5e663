"""camjax: differentiable, fast cam-mechanism dynamics in JAX.

Importing camjax turns on JAX's float64 mode (every accuracy figure in camjax holds in
float64), unless the environment sets ``JAX_ENABLE_X64=0``: then camjax runs in float32
and its accuracy is that of float32 (see the README's accuracy notes).
"""

import os

import jax

if os.environ.get("JAX_ENABLE_X64", "").lower() not in ("0", "false"):
    jax.config.update("jax_enable_x64", True)

from . import geometry as geometry  # noqa: E402
from . import laws as laws  # noqa: E402
from . import models as models  # noqa: E402
from .errors import RESULTS as RESULTS  # noqa: E402
from .errors import SolverError as SolverError  # noqa: E402
from .metrics import TorsionFactorFit as TorsionFactorFit  # noqa: E402
from .metrics import ca_ct_crossings as ca_ct_crossings  # noqa: E402
from .metrics import fit_torsion_factor as fit_torsion_factor  # noqa: E402
from .models import AbstractModel as AbstractModel  # noqa: E402
from .models import Backlash as Backlash  # noqa: E402
from .models import CoulombFriction as CoulombFriction  # noqa: E402
from .models import Metrics as Metrics  # noqa: E402
from .models import Response as Response  # noqa: E402
from .models import SpringMass as SpringMass  # noqa: E402
from .models import SwingingFollower as SwingingFollower  # noqa: E402
from .models import TwoMass as TwoMass  # noqa: E402
from .models import natural_frequency as natural_frequency  # noqa: E402
from .models import period_ratio as period_ratio  # noqa: E402
from .models import residual_vibration as residual_vibration  # noqa: E402
from .models import solve as solve  # noqa: E402
from .models import torsion_factor as torsion_factor  # noqa: E402
from .motion_design import CapError as CapError  # noqa: E402
from .motion_design import Caps as Caps  # noqa: E402
from .motion_design import design as design  # noqa: E402
from .program import Program as Program  # noqa: E402
from .sweep import CtCurve as CtCurve  # noqa: E402
from .sweep import ct_curve as ct_curve  # noqa: E402
from .sweep import ct_curves as ct_curves  # noqa: E402
