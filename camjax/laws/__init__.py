"""Motion laws: normalised rises ``s(tau)`` with exact derivatives and coefficients."""

from ._base import AbstractMotionLaw as AbstractMotionLaw
from ._io import load as load
from ._io import save as save
from ._polynomial import PolynomialLaw as PolynomialLaw
from ._program import LawBank as LawBank
from ._program import MotionProgram as MotionProgram
from ._registry import as_law as as_law
from ._registry import get as get
from ._registry import names as names
from ._registry import standard_laws as standard_laws
from ._scca import SCCA as SCCA
from ._scca import AbstractSCCA as AbstractSCCA
from ._scca import Cycloidal as Cycloidal
from ._scca import ModifiedSine as ModifiedSine
from ._scca import ModifiedTrapezoid as ModifiedTrapezoid
from ._scca import Parabolic as Parabolic
from ._scca import SimpleHarmonic as SimpleHarmonic
from ._spline import BSplineLaw as BSplineLaw
