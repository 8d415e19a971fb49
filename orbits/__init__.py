"""orbits: geometric phase, exact motion and closed orbits of the asymmetric top.

Implements N. A. Mecholsky, "Analytic formula for the geometric phase of
an asymmetric top", Am. J. Phys. 87, 245 (2019), with the paper's errata
corrected (see the documentation's Errata page, docs/errata.md).

The names below are loaded on first use (PEP 562 module ``__getattr__``):
``import orbits`` itself imports neither numba, SciPy nor pandas, so the
command line starts in a fraction of a second.
"""

import importlib
import os
import sys
import types

# OpenMP threads that sleep rather than spin while they wait: with another
# CPU-bound process on the machine, spinning threads of a parallel kernel
# steal the cores its working threads need (measured on 2 cores: 2.1x slower
# under one busy process with spinning, 1.8x with passive waiting; idle speed
# unchanged).  Read when numba first starts its OpenMP pool; a value the user
# set is kept.
os.environ.setdefault("OMP_WAIT_POLICY", "passive")

from ._version import __version__
from .errors import (
    AngleError,
    ArgumentTypeError,
    DeviceError,
    InputError,
    NonPhysicalBodyError,
    OrbitsError,
    SeparatrixError,
    SymmetricTopError,
)

# public name -> submodule that defines it
_LAZY = {
    "PRESETS": "bodies",
    "Body": "bodies",
    "region_grid": "bodies",
    "region_sample": "bodies",
    "InertialDefectWarning": "bodies",
    "closure_errors": "checks",
    "montgomery": "checks",
    "motion_phase": "checks",
    "rotation_by_integration": "checks",
    "verify": "checks",
    "verify_body": "checks",
    "AxesWarning": "motion",
    "Motion": "motion",
    "MotionState": "motion",
    "TumblingPeriods": "motion",
    "herpolhode": "motion",
    "polhode": "motion",
    "CATALOG_COLUMNS": "search",
    "UnresolvedOrbitsWarning": "search",
    "closed_orbits": "search",
    "minimum_phase": "search",
    "phase_levels": "search",
    "search_bodies": "search",
    "catalog": "catalog",
    "nearest_orbits": "catalog",
    "read_catalog": "catalog",
    "write_catalog": "catalog",
    "PhaseLimits": "phases",
    "critical_angle": "phases",
    "phase_limits": "phases",
    "phases": "phases",
    "spin_phases": "phases",
    "total_phase": "phases",
    "spins_with_period_ratio": "tumbling",
    "spins_with_periods": "tumbling",
    "spins_with_total_phase": "tumbling",
    "set_num_threads": "threads",
    "PoinsotAnimation": "animate",
    "AliasingWarning": "animate",
    "flip_motion": "animate",
    "orbit_row": "animate",
    "poinsot_animation": "animate",
    "get_num_threads": "threads",
}


class _Package(types.ModuleType):
    """The package's module type: a function keeps its name against its module.

    ``orbits.phases`` and ``orbits.catalog`` are functions defined in modules
    of the same name.  Importing such a module makes the import system set
    the package attribute to the module; this keeps the function (loaded
    by :func:`__getattr__`) instead, as the eager imports used to.
    """

    def __setattr__(self, name, value):
        if name in _LAZY and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)

    def __reduce__(self):
        # by reference, as cloudpickle sends a plain module: it looks its
        # module reducer up by exact type, so a function defined in a notebook
        # that uses ``orbits.`` could not be sent to dask workers
        return importlib.import_module, (self.__name__,)


sys.modules[__name__].__class__ = _Package


def __getattr__(name):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'orbits' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "AliasingWarning",
    "AngleError",
    "ArgumentTypeError",
    "AxesWarning",
    "Body",
    "CATALOG_COLUMNS",
    "DeviceError",
    "InertialDefectWarning",
    "InputError",
    "Motion",
    "MotionState",
    "NonPhysicalBodyError",
    "OrbitsError",
    "PRESETS",
    "PhaseLimits",
    "PoinsotAnimation",
    "SeparatrixError",
    "SymmetricTopError",
    "TumblingPeriods",
    "UnresolvedOrbitsWarning",
    "__version__",
    "catalog",
    "closed_orbits",
    "closure_errors",
    "critical_angle",
    "flip_motion",
    "get_num_threads",
    "herpolhode",
    "minimum_phase",
    "montgomery",
    "motion_phase",
    "nearest_orbits",
    "orbit_row",
    "phase_levels",
    "phase_limits",
    "phases",
    "poinsot_animation",
    "polhode",
    "read_catalog",
    "region_grid",
    "region_sample",
    "rotation_by_integration",
    "search_bodies",
    "set_num_threads",
    "spin_phases",
    "spins_with_period_ratio",
    "spins_with_periods",
    "spins_with_total_phase",
    "total_phase",
    "verify",
    "verify_body",
    "write_catalog",
]
