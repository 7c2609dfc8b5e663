"""Dynamic models of the driven payload."""

from ._spring_mass import SpringMass as SpringMass
from ._spring_mass import natural_frequency as natural_frequency
from ._spring_mass import period_ratio as period_ratio
