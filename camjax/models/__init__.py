"""Dynamic models of the driven payload, simplest first: the linear SDOF, then friction,
backlash, an elastic input drive and a flexible swinging follower.

Every model is an ``AbstractModel``; ``solve`` solves any of them and
``camjax.ct_curve`` sweeps the period ratio of any SDOF-family model, so a scene moves
up or down the hierarchy by changing one argument.

The linear SDOF (its exact path) is imported with this package; the models that solve with
diffrax are imported on first use, so that the exact path never pays for diffrax's import.
"""

import importlib
from typing import TYPE_CHECKING

from ..registry import MODELS as MODELS
from ..registry import ModelEntry as ModelEntry
from ..registry import model_entry as model_entry
from ._base import AbstractMachineModel as AbstractMachineModel
from ._base import AbstractModel as AbstractModel
from ._base import Metrics as Metrics
from ._base import Options as Options
from ._base import Response as Response
from ._solve import solve as solve
from ._solve import solve_program as solve_program
from ._solve import trace_solve as trace_solve
from ._spring_mass import TRACED_RESOLUTION as TRACED_RESOLUTION
from ._spring_mass import SpringMass as SpringMass
from ._spring_mass import SpringMassOptions as SpringMassOptions
from ._spring_mass import SpringMassResponse as SpringMassResponse
from ._spring_mass import batch_metrics as batch_metrics
from ._spring_mass import natural_frequency as natural_frequency
from ._spring_mass import period_ratio as period_ratio
from ._spring_mass import residual_vibration as residual_vibration
from ._spring_mass import response_metrics as response_metrics
from ._spring_mass import torsion_factor as torsion_factor

if TYPE_CHECKING:  # the lazy names, for type checkers and the API reference
    from ._backlash import DRIVING_FLANK as DRIVING_FLANK
    from ._backlash import FREE as FREE
    from ._backlash import IMPACT as IMPACT
    from ._backlash import NO_IMPACT as NO_IMPACT
    from ._backlash import NO_SEPARATION as NO_SEPARATION
    from ._backlash import OTHER_FLANK as OTHER_FLANK
    from ._backlash import STATUS_NAMES as STATUS_NAMES
    from ._backlash import Backlash as Backlash
    from ._backlash import BacklashOptions as BacklashOptions
    from ._backlash import BacklashResponse as BacklashResponse
    from ._backlash import KinematicImpact as KinematicImpact
    from ._backlash import impact_force as impact_force
    from ._backlash import impact_velocity as impact_velocity
    from ._backlash import kinematic_impact as kinematic_impact
    from ._backlash import kinematic_impact_table as kinematic_impact_table
    from ._backlash import normalised_backlash as normalised_backlash
    from ._backlash import normalised_deceleration as normalised_deceleration
    from ._friction import CoulombFriction as CoulombFriction
    from ._friction import FreeVibration as FreeVibration
    from ._friction import FrictionOptions as FrictionOptions
    from ._friction import FrictionResponse as FrictionResponse
    from ._friction import free_vibration as free_vibration
    from ._hybrid import AbstractHybridModel as AbstractHybridModel
    from ._swinging_follower import FollowerOptions as FollowerOptions
    from ._swinging_follower import FollowerResponse as FollowerResponse
    from ._swinging_follower import SwingingFollower as SwingingFollower
    from ._swinging_follower import spectral_peaks as spectral_peaks
    from ._swinging_follower import spectrum as spectrum
    from ._two_mass import TwoMass as TwoMass
    from ._two_mass import TwoMassOptions as TwoMassOptions
    from ._two_mass import TwoMassResponse as TwoMassResponse

_LAZY = {
    "AbstractHybridModel": "_hybrid",
    "Backlash": "_backlash",
    "BacklashOptions": "_backlash",
    "BacklashResponse": "_backlash",
    "KinematicImpact": "_backlash",
    "impact_force": "_backlash",
    "kinematic_impact": "_backlash",
    "kinematic_impact_table": "_backlash",
    "normalised_backlash": "_backlash",
    "normalised_deceleration": "_backlash",
    "STATUS_NAMES": "_backlash",
    "IMPACT": "_backlash",
    "NO_SEPARATION": "_backlash",
    "NO_IMPACT": "_backlash",
    "DRIVING_FLANK": "_backlash",
    "FREE": "_backlash",
    "OTHER_FLANK": "_backlash",
    "impact_velocity": "_backlash",
    "CoulombFriction": "_friction",
    "FreeVibration": "_friction",
    "FrictionOptions": "_friction",
    "FrictionResponse": "_friction",
    "free_vibration": "_friction",
    "FollowerOptions": "_swinging_follower",
    "FollowerResponse": "_swinging_follower",
    "SwingingFollower": "_swinging_follower",
    "spectral_peaks": "_swinging_follower",
    "spectrum": "_swinging_follower",
    "TwoMass": "_two_mass",
    "TwoMassOptions": "_two_mass",
    "TwoMassResponse": "_two_mass",
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
