"""Dynamic models of the driven payload, simplest first: the linear SDOF, then friction,
backlash, an elastic input drive and a flexible swinging follower.

Every model is an ``AbstractModel``; ``solve`` solves any of them and
``camjax.ct_curve`` sweeps the period ratio of any SDOF-family model, so a scene moves
up or down the hierarchy by changing one argument.
"""

from ._base import AbstractModel as AbstractModel
from ._base import Metrics as Metrics
from ._base import Options as Options
from ._base import Response as Response
from ._solve import solve as solve
from ._solve import trace_solve as trace_solve
from .backlash import Backlash as Backlash
from .backlash import BacklashOptions as BacklashOptions
from .backlash import BacklashResponse as BacklashResponse
from .backlash import KinematicImpact as KinematicImpact
from .backlash import impact_force as impact_force
from .backlash import kinematic_impact as kinematic_impact
from .backlash import kinematic_impact_table as kinematic_impact_table
from .backlash import normalised_backlash as normalised_backlash
from .backlash import normalised_deceleration as normalised_deceleration
from .friction import CoulombFriction as CoulombFriction
from .friction import FreeVibration as FreeVibration
from .friction import FrictionOptions as FrictionOptions
from .friction import FrictionResponse as FrictionResponse
from .friction import free_vibration as free_vibration
from .spring_mass import SpringMass as SpringMass
from .spring_mass import SpringMassOptions as SpringMassOptions
from .spring_mass import SpringMassResponse as SpringMassResponse
from .spring_mass import natural_frequency as natural_frequency
from .spring_mass import period_ratio as period_ratio
from .spring_mass import residual_vibration as residual_vibration
from .spring_mass import torsion_factor as torsion_factor
from .swinging_follower import FollowerOptions as FollowerOptions
from .swinging_follower import FollowerResponse as FollowerResponse
from .swinging_follower import SwingingFollower as SwingingFollower
from .two_mass import TwoMass as TwoMass
from .two_mass import TwoMassOptions as TwoMassOptions
from .two_mass import TwoMassResponse as TwoMassResponse
