"""Exact propagation of linear models: the sample grid over a rise and the closed-form step.

The linear SDOF ``e'' + 2 zeta w e' + w^2 e = a(tau)`` is one complex mode
``q = e' - conj(lambda) e`` with ``q' = lambda q + a``; ``propagate`` steps it exactly
over a ``MotionGrid`` (degree-5 interpolant of the forcing on each interval).
"""

from ._exact import eigenvalue as eigenvalue
from ._exact import propagate as propagate
from ._exact import psi as psi
from ._grid import TARGET_PHASE_STEP as TARGET_PHASE_STEP
from ._grid import MotionGrid as MotionGrid
from ._grid import SampledLaw as SampledLaw
from ._grid import default_resolution as default_resolution
from ._grid import motion_grid as motion_grid
