"""orbits: geometric phase, exact motion and closed orbits of the asymmetric top.

Implements Mecholsky (2019), "Analytic formula for the Geometric Phase of
an Asymmetric Top" (LaTeX source in ``shared/seed``), with the paper's
errata corrected (see README, "Errata").
"""

from importlib.metadata import PackageNotFoundError, version as _version

from .bodies import PRESETS, Body, region_grid, region_sample
from .checks import montgomery, motion_phase, rotation_by_integration, verify
from .errors import (AngleError, InputError, NonPhysicalBodyError,
                     OrbitsError, SeparatrixError, SymmetricTopError)
from .motion import Motion, MotionState, herpolhode, polhode
from .phases import (PhaseLimits, critical_angle, phase_limits, phases,
                     spin_phases, total_phase)

try:
    __version__ = _version("orbits")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0+unknown"

__all__ = [
    "AngleError",
    "Body",
    "InputError",
    "Motion",
    "MotionState",
    "NonPhysicalBodyError",
    "OrbitsError",
    "PRESETS",
    "PhaseLimits",
    "SeparatrixError",
    "SymmetricTopError",
    "__version__",
    "critical_angle",
    "herpolhode",
    "montgomery",
    "motion_phase",
    "phase_limits",
    "phases",
    "polhode",
    "region_grid",
    "region_sample",
    "rotation_by_integration",
    "spin_phases",
    "total_phase",
    "verify",
]
