"""Dynamic models of the driven payload, simplest first: the linear SDOF, then
friction, backlash, an elastic input drive and a flexible swinging follower."""

from ._spring_mass import SpringMass as SpringMass
from ._spring_mass import natural_frequency as natural_frequency
from ._spring_mass import period_ratio as period_ratio
from .backlash import Backlash as Backlash
from .backlash import BacklashResponse as BacklashResponse
from .backlash import KinematicImpact as KinematicImpact
from .backlash import impact_force as impact_force
from .backlash import kinematic_impact as kinematic_impact
from .backlash import kinematic_impact_table as kinematic_impact_table
from .backlash import normalised_backlash as normalised_backlash
from .backlash import normalised_deceleration as normalised_deceleration
from .backlash import solve_backlash as solve_backlash
from .friction import CoulombFriction as CoulombFriction
from .friction import FreeVibration as FreeVibration
from .friction import FrictionResponse as FrictionResponse
from .friction import free_vibration as free_vibration
from .friction import friction_response as friction_response
from .friction import solve_friction as solve_friction
from .swinging_follower import SwingingFollower as SwingingFollower
from .two_mass import TwoMass as TwoMass
from .two_mass import TwoMassResponse as TwoMassResponse
from .two_mass import two_mass_ct_curve as two_mass_ct_curve
from .two_mass import two_mass_response as two_mass_response
