"""camjax: differentiable, fast cam-mechanism dynamics in JAX.

Importing camjax turns on JAX's float64 mode (every accuracy figure in camjax holds in
float64), unless the environment sets ``JAX_ENABLE_X64=0``: then camjax runs in float32
and its accuracy is that of float32 (see the README's accuracy notes).

The public names below are imported on first use, so that ``import camjax`` (and the
command line's ``--help``) does not pay for JAX's import until something needs it.
"""

import importlib
import os
import sys

if os.environ.get("JAX_ENABLE_X64", "").lower() not in ("0", "false"):
    if "jax" in sys.modules:
        sys.modules["jax"].config.update("jax_enable_x64", True)
    else:
        # JAX reads this when it is first imported (by whichever camjax module needs it).
        os.environ["JAX_ENABLE_X64"] = "1"

_SUBMODULES = (
    "checks", "errors", "geometry", "law_design", "laws", "metrics", "models", "plot", "program", "registry",
    "sdof", "solvers", "studies", "sweep",
)
_ATTRIBUTES = {
    "TorsionFactorFit": "metrics",
    "ca_ct_crossings": "metrics",
    "fit_torsion_factor": "metrics",
    "RESULTS": "errors",
    "SolverError": "errors",
    "AbstractModel": "models",
    "Backlash": "models",
    "CoulombFriction": "models",
    "SpringMass": "models",
    "SwingingFollower": "models",
    "TwoMass": "models",
    "natural_frequency": "models",
    "period_ratio": "models",
    "CapError": "law_design",
    "Caps": "law_design",
    "design": "law_design",
    "Metrics": "models",
    "Response": "models",
    "residual_vibration": "models",
    "solve": "models",
    "torsion_factor": "models",
    "Program": "program",
    "CtCurve": "sweep",
    "ct_curve": "sweep",
    "ct_curves": "sweep",
}
__all__ = sorted([*_SUBMODULES, *_ATTRIBUTES])


def __getattr__(name: str):
    if name in _ATTRIBUTES:
        value = getattr(importlib.import_module(f".{_ATTRIBUTES[name]}", __name__), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module 'camjax' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return __all__
