"""Exceptions raised by ``orbits``.

All derive from :class:`OrbitsError` and from :class:`ValueError`, so
``except ValueError`` keeps working for callers who do not care which
input was wrong.  The command line turns any of them into exit code 2 and
a one-line message.
"""


class OrbitsError(ValueError):
    """Base class: an input that ``orbits`` cannot turn into physics."""


class NonPhysicalBodyError(OrbitsError):
    """Moments that no rigid body has.

    Raised for moments that are not finite, not positive, or that break a
    triangle inequality (``I3 <= I1 + I2`` when sorted).
    """


class SymmetricTopError(OrbitsError):
    """Two equal principal moments.

    The total-phase formula (eqn:GeometricPhase) needs ``I1 < I2 < I3``:
    with two equal moments there is no separatrix, the elliptic parameter
    is identically 0 or 1, and the motion is a uniform precession.
    """


class AngleError(OrbitsError):
    """An initial-spin angle that is NaN, infinite or out of range."""


class SeparatrixError(OrbitsError):
    """An initial spin on the separatrix ``M^2 = 2 E I2``.

    There the period is infinite and the total phase diverges; pass an
    offset ``dtheta`` from the critical angle instead.  Also raised for a
    ``theta`` within the rounding error of the critical angle, whose side
    of the separatrix (SAM or LAM) double precision cannot tell.
    """


class InputError(OrbitsError):
    """Any other invalid argument (counts, file contents, options)."""


class ArgumentTypeError(InputError, TypeError):
    """An argument of the wrong type (a string, complex or ``None`` where a
    real number is needed); the message names the argument.

    Derives from :class:`TypeError` too, so ``except TypeError`` catches it.
    """


class DeviceError(OrbitsError):
    """A compute device that cannot be used: ``device="cuda"`` without an
    NVIDIA GPU and driver, without the ``orbits[cuda]`` extra (numba-cuda),
    or with a numba-cuda that cannot compile beside the installed NumPy; or
    a ``device`` that is neither ``"cpu"`` nor ``"cuda"``."""
