"""Dynamic models of the driven payload, simplest first: the linear SDOF, then friction,
backlash, an elastic input drive and a flexible swinging follower.

Every model is an ``AbstractModel``; ``solve`` solves any of them and
``camjax.ct_curve`` sweeps the period ratio of any SDOF-family model, so a scene moves
up or down the hierarchy by changing one argument.

The linear SDOF (its exact path) is imported with this package; the models that solve with
diffrax are imported on first use, so that the exact path never pays for diffrax's import.
"""

import importlib

from ..registry import MODELS as MODELS
from ..registry import ModelEntry as ModelEntry
from ..registry import model_entry as model_entry
from ._base import AbstractMachineModel as AbstractMachineModel
from ._base import AbstractModel as AbstractModel
from ._base import Metrics as Metrics
from ._base import Options as Options
from ._base import Response as Response
from ._solve import solve as solve
from ._solve import trace_solve as trace_solve
from .spring_mass import SpringMass as SpringMass
from .spring_mass import SpringMassOptions as SpringMassOptions
from .spring_mass import SpringMassResponse as SpringMassResponse
from .spring_mass import batch_metrics as batch_metrics
from .spring_mass import natural_frequency as natural_frequency
from .spring_mass import period_ratio as period_ratio
from .spring_mass import residual_vibration as residual_vibration
from .spring_mass import response_metrics as response_metrics
from .spring_mass import torsion_factor as torsion_factor

_LAZY = {
    "Backlash": "backlash",
    "BacklashOptions": "backlash",
    "BacklashResponse": "backlash",
    "KinematicImpact": "backlash",
    "impact_force": "backlash",
    "kinematic_impact": "backlash",
    "kinematic_impact_table": "backlash",
    "normalised_backlash": "backlash",
    "normalised_deceleration": "backlash",
    "CoulombFriction": "friction",
    "FreeVibration": "friction",
    "FrictionOptions": "friction",
    "FrictionResponse": "friction",
    "free_vibration": "friction",
    "FollowerOptions": "swinging_follower",
    "FollowerResponse": "swinging_follower",
    "SwingingFollower": "swinging_follower",
    "TwoMass": "two_mass",
    "TwoMassOptions": "two_mass",
    "TwoMassResponse": "two_mass",
}
__all__ = sorted([
    "AbstractMachineModel", "AbstractModel", "MODELS", "ModelEntry", "model_entry", "Metrics", "Options", "Response", "solve", "trace_solve", "SpringMass",
    "SpringMassOptions", "SpringMassResponse", "natural_frequency", "period_ratio",
    "residual_vibration", "torsion_factor", "batch_metrics", "response_metrics", *_LAZY,
])


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module 'camjax.models' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return __all__
