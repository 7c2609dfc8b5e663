"""Motion laws: normalised rises ``s(tau)`` with exact derivatives and coefficients."""

from ._base import AbstractMotionLaw as AbstractMotionLaw
from ._base import AbstractSearchedPeaksLaw as AbstractSearchedPeaksLaw
from ._boundary import BoundaryPolynomial as BoundaryPolynomial
from ._boundary import ConstantVelocity as ConstantVelocity
from ._boundary import CorrectedPolynomial as CorrectedPolynomial
from ._io import from_dict as from_dict
from ._io import load as load
from ._io import save as save
from ._io import to_dict as to_dict
from ._polynomial import PolynomialLaw as PolynomialLaw
from ._registry import as_law as as_law
from ._registry import get as get
from ._registry import names as names
from ._registry import standard_laws as standard_laws
from ._rise_dwell_fall import LawBank as LawBank
from ._rise_dwell_fall import RiseDwellFall as RiseDwellFall
from ._scca import SCCA as SCCA
from ._scca import AbstractSCCA as AbstractSCCA
from ._scca import Cycloidal as Cycloidal
from ._scca import ModifiedSine as ModifiedSine
from ._scca import ModifiedTrapezoid as ModifiedTrapezoid
from ._scca import Parabolic as Parabolic
from ._scca import SimpleHarmonic as SimpleHarmonic
from ._spline import BSplineLaw as BSplineLaw
