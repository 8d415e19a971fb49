"""orbits: geometric phase, exact motion and closed orbits of the asymmetric top.

Implements Mecholsky (2019), "Analytic formula for the Geometric Phase of
an Asymmetric Top" (LaTeX source in ``shared/seed``), with the paper's
errata corrected (see README, "Errata").
"""

from ._version import __version__
from .bodies import PRESETS, Body, region_grid, region_sample
from .checks import (closure_errors, montgomery, motion_phase,
                     rotation_by_integration, verify)
from .errors import (AngleError, InputError, NonPhysicalBodyError,
                     OrbitsError, SeparatrixError, SymmetricTopError)
from .motion import Motion, MotionState, herpolhode, polhode
from .search import (CATALOG_COLUMNS, UnresolvedOrbitsWarning, closed_orbits,
                     minimum_phase, phase_levels)
from .catalog import catalog, read_catalog, write_catalog
from .phases import (PhaseLimits, critical_angle, phase_limits, phases,
                     spin_phases, total_phase)

__all__ = [
    "AngleError",
    "CATALOG_COLUMNS",
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
    "UnresolvedOrbitsWarning",
    "__version__",
    "catalog",
    "closed_orbits",
    "closure_errors",
    "critical_angle",
    "herpolhode",
    "minimum_phase",
    "montgomery",
    "motion_phase",
    "phase_levels",
    "phase_limits",
    "phases",
    "polhode",
    "read_catalog",
    "region_grid",
    "region_sample",
    "rotation_by_integration",
    "spin_phases",
    "total_phase",
    "verify",
    "write_catalog",
]
