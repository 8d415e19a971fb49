"""Argument checks shared by the public functions.

Every public function turns its numeric arguments into arrays here, so a
wrong type (a string, a complex number, ``None``, a ragged list) becomes an
:class:`~orbits.errors.ArgumentTypeError` that names the argument, instead
of a TypeError or ValueError from inside NumPy or numba.
"""

import itertools
import math
import numbers
import os
import sys
import threading
import warnings
from contextlib import contextmanager

import numpy as np

from .errors import ArgumentTypeError, InputError


def _describe(value):
    text = " ".join(repr(value).split())  # one line, for the CLI's messages
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{text} ({type(value).__name__})"


def _bool_inside(value):
    """A bool (Python or NumPy) anywhere in nested lists/tuples, or ``None``.

    ``np.asarray([True, 2.0])`` is ``[1.0, 2.0]``: the boolean is lost before
    the dtype can show it, so sequences are searched first.
    """
    level = [value]
    while level:
        kinds = set(map(type, level))
        if bool in kinds or np.bool_ in kinds:
            return next(v for v in level if isinstance(v, (bool, np.bool_)))
        if any(issubclass(kind, np.ndarray) for kind in kinds):
            for v in level:
                if isinstance(v, np.ndarray) and v.dtype.kind == "b":
                    return v
        sequences = [kind for kind in kinds if issubclass(kind, (list, tuple))]
        if not sequences:
            return None
        if len(kinds) == len(sequences):  # a level of sequences only: flatten it whole
            level = list(itertools.chain.from_iterable(level))
        else:
            level = [item for v in level if isinstance(v, (list, tuple)) for item in v]
    return None


def real_array(name, value, error=InputError):
    """``value`` as a float64 array, or an error naming ``name``.

    Accepts real numbers and (nested) sequences or arrays of them.  Booleans,
    strings, bytes, complex numbers, ``None`` and other objects raise
    :class:`ArgumentTypeError`; a ragged sequence raises ``error``.  Values
    are not checked for finiteness here (callers say what is allowed).
    """
    if isinstance(value, (str, bytes)) or value is None:
        raise ArgumentTypeError(f"{name} must be real numbers, got {_describe(value)}")
    masked = sys.modules.get("numpy.ma")  # no masked array exists before it is imported
    if masked is not None and isinstance(value, masked.MaskedArray) and masked.is_masked(value):
        # np.asarray would drop the mask and compute the hidden values
        raise ArgumentTypeError(
            f"{name} is a masked array with masked entries, which would be computed "
            f"as if unmasked; pass {name}.compressed() or {name}.filled(value)"
        )
    if isinstance(value, (list, tuple)):
        flag = _bool_inside(value)
        if flag is not None:
            what = "booleans: " if isinstance(flag, np.ndarray) else ""
            raise ArgumentTypeError(f"{name} must be real numbers, got {what}{_describe(flag)}")
    try:
        array = np.asarray(value)
    except (ValueError, TypeError):
        raise error(
            f"{name} must be a rectangular array of real numbers, got {_describe(value)}"
        ) from None
    kind = array.dtype.kind
    if kind == "O":
        flat = array.ravel()
        if not all(
            isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)) for v in flat
        ):
            bad = next(
                v
                for v in flat
                if not isinstance(v, numbers.Real) or isinstance(v, (bool, np.bool_))
            )
            raise ArgumentTypeError(f"{name} must be real numbers, got {_describe(bad)}")
        try:
            with np.errstate(over="ignore"):
                return np.array([float(v) for v in flat], dtype=float).reshape(array.shape)
        except (OverflowError, ValueError, TypeError):
            raise error(f"{name} holds a number that is not a double") from None
    if kind not in "iuf":
        what = {
            "b": "booleans",
            "c": "complex numbers",
            "U": "text",
            "S": "bytes",
            "M": "dates",
            "m": "time spans",
            "V": "records",
        }.get(kind, kind)
        raise ArgumentTypeError(f"{name} must be real numbers, got {what}: {_describe(value)}")
    with np.errstate(over="ignore"):
        return array.astype(float, copy=False)


def real_scalar(name, value, error=InputError):
    """One real number as a Python float (not checked for finiteness)."""
    if type(value) is float:  # the common case, without NumPy's overhead
        return value
    array = real_array(name, value, error)
    if array.shape != ():
        if array.size == 1:
            return float(array.reshape(()))
        raise error(f"{name} must be one number, got shape {array.shape}")
    return float(array)


def positive_finite(name, value, error=InputError):
    """One positive, finite real number as a Python float, or an error naming ``name``."""
    number = real_scalar(name, value, error)
    if not (math.isfinite(number) and number > 0.0):
        raise error(f"{name} must be positive and finite, got {number}")
    return number


# registered as numbers.Real (or Integral) but no count or rate: booleans,
# and NumPy's timedelta64, which int() and float() refuse
NOT_NUMBERS = (bool, np.bool_, np.timedelta64, np.datetime64)


def listlike(value):
    """Whether ``value`` iterates as a list of items: not text, bytes, a
    scalar or a 0-d array (which has ``__iter__`` and raises when iterated)."""
    return (
        not isinstance(value, (str, bytes))
        and hasattr(value, "__iter__")
        and not (isinstance(value, np.ndarray) and value.ndim == 0)
    )


def integer(name, value, minimum=1, maximum=None):
    """A whole number ``>= minimum`` (and ``<= maximum``) as a Python int.

    Integral floats (``3.0``) are accepted; text, booleans and fractions
    are not.
    """
    if isinstance(value, NOT_NUMBERS) or not isinstance(value, numbers.Real):
        raise ArgumentTypeError(f"{name} must be an integer >= {minimum}, got {_describe(value)}")
    if isinstance(value, numbers.Integral):
        number = int(value)
    elif isinstance(value, numbers.Rational):
        # a Fraction as itself: float() overflowed beyond 1.8e308 (OverflowError)
        if value.denominator != 1:
            raise InputError(f"{name} must be an integer >= {minimum}, got {_describe(value)}")
        number = int(value.numerator)
    else:
        real = float(value)
        if not real.is_integer():
            raise InputError(f"{name} must be an integer >= {minimum}, got {_describe(value)}")
        number = int(real)
    if number < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {_describe(value)}")
    if maximum is not None and number > maximum:
        raise InputError(f"{name} must be an integer <= {maximum}, got {_describe(value)}")
    return number


def flag(name, value):
    """``True`` or ``False`` (Python or NumPy bool) as a Python bool.

    Anything else is refused: ``verify="no"`` is a true string, and an
    array has no single truth value.
    """
    if not isinstance(value, (bool, np.bool_)):
        raise ArgumentTypeError(f"{name} must be True or False, got {_describe(value)}")
    return bool(value)


def utf8_text(name, value):
    """``value`` (a str) if UTF-8 can encode it, else an :class:`InputError`.

    A lone surrogate (``"a\\ud800"``, from a file name decoded with
    ``surrogateescape``) passes as a str but fails when a catalog or a
    survey is written: after the first files, as a bare UnicodeEncodeError.
    """
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise InputError(
            f"{name} {value!r} is not text UTF-8 can hold (a lone surrogate)"
        ) from None
    return value


def callback(name, value):
    """A callable or ``None``, checked before any work is done."""
    if value is not None and not callable(value):
        raise ArgumentTypeError(
            f"{name} must be a callable ({name}(done)) or None, got {_describe(value)}"
        )
    return value


# the longest file name (one path component) of ext4, XFS, Btrfs and APFS, bytes
NAME_MAX = 255


def path_argument(name, value):
    """A file path (str or os.PathLike); an int (a file descriptor) is refused."""
    if isinstance(value, (str, os.PathLike)) and not isinstance(value, bytes):
        path = os.fspath(value)
        if isinstance(path, str) and path and "\x00" not in path:
            try:
                raw = os.fsencode(path)
            except UnicodeError:
                raise InputError(
                    f"{name} {_describe(value)} cannot be a file name on this "
                    "system (not encodable)"
                ) from None
            longest = max(len(part) for part in raw.split(os.fsencode(os.sep)))
            if longest > NAME_MAX:
                raise InputError(
                    f"{name}: a file or directory name of {longest} bytes is too long "
                    f"(at most {NAME_MAX} on Linux and macOS file systems)"
                )
            return path
        raise InputError(f"{name} must be a non-empty path, got {_describe(value)}")
    raise ArgumentTypeError(f"{name} must be a path (str or os.PathLike), got {_describe(value)}")


def given_besides(**values):
    """Names of the arguments given other than as their defaults, in order.

    Each keyword is ``(value, default)``: with a default of None an argument
    counts as given when it is not None; with a number, when it is not equal
    to it (anything that does not compare as a number counts as given, to be
    refused by its own check).  For refusing options that would be ignored
    (angles given beside a :class:`orbits.Motion`, which has its own spin).
    """

    def equal(value, default):
        try:
            return bool(value == default)
        except (TypeError, ValueError):
            return False

    return [
        name
        for name, (value, default) in values.items()
        if not (value is default or (default is not None and equal(value, default)))
    ]


def broadcast(names_and_shapes):
    """The broadcast shape of named arrays, or an InputError naming them."""
    try:
        return np.broadcast_shapes(*(shape for _, shape in names_and_shapes))
    except ValueError:
        listed = ", ".join(f"{name} {shape}" for name, shape in names_and_shapes)
        raise InputError(f"shapes do not broadcast together: {listed}") from None


def finite_array(name, value, error=InputError):
    """A real array with every value finite, or ``error`` naming the first bad one."""
    array = real_array(name, value, error)
    if not np.all(np.isfinite(array)):
        flat = np.ravel(array)
        raise error(f"{name} must be finite, got {flat[~np.isfinite(flat)][0]}")
    return array


def flat_broadcast(array, shape):
    """``array`` broadcast to ``shape`` as a fresh contiguous 1-D float array."""
    return np.ascontiguousarray(np.broadcast_to(array, shape), dtype=float).ravel()


# the smallest normal double: below it a decimal keeps fewer than 53 bits
SMALLEST_NORMAL = 2.2250738585072014e-308


def below_normal(values):
    """Where a value is subnormal (``0 < |v| < 2.2e-308``): boolean array.

    A moment typed in decimal below the smallest normal double is stored
    with fewer than 53 bits (``1e-320`` becomes ``9.99988671826831e-321``),
    so the body computed would silently differ from the one typed.  The
    command line's ``--moments`` and the rows of a ``--bodies`` file both
    refuse such values, with :func:`below_normal_message`.
    """
    magnitude = np.abs(np.asarray(values, dtype=float))
    return (magnitude > 0.0) & (magnitude < SMALLEST_NORMAL)


def read_as_zero(text, value):
    """How a decimal that reads as 0 is out of range, or None when it is not one.

    ``1e-400`` parses to 0.0 though it is not zero: ``""`` (below the
    smallest normal double), ``"negative and "`` for ``-1e-400``; None for
    a value that is not 0.0 or a text that is a zero (``0.0e5``).  For the
    command line's ``--moments`` and a ``--bodies`` file alike, which name
    the value as typed rather than "moments (0, ...)".
    """
    if value != 0.0 or not any(digit in text.lower().split("e")[0] for digit in "123456789"):
        return None
    return "negative and " if text.strip().startswith("-") else ""


def below_normal_message(text):
    """Why a subnormal moment ``text`` is refused (one line)."""
    return (
        f"{text} is below the smallest normal double (2.2e-308) and would be "
        "stored with reduced precision; give the moments in larger units"
    )


# the innermost held_warnings list of each Python thread
_held = threading.local()


@contextmanager
def held_warnings():
    """Hold the package's own warnings (those issued by :func:`warn`) raised
    in this thread inside the block: they are appended, as ``(message,
    category)``, to the list this yields instead of being issued.

    Unlike ``warnings.catch_warnings`` this touches no global state: that
    one swaps the process's ``warnings.filters`` and ``showwarning``, so two
    Python threads inside it at once left the process with a filter list
    that sent every later warning to a dead list.  Blocks nest; the inner
    one holds.
    """
    before = getattr(_held, "caught", None)
    _held.caught = caught = []
    try:
        yield caught
    finally:
        _held.caught = before


def warn(message, category):
    """``warnings.warn`` at the first line outside the package, or held by
    the innermost :func:`held_warnings` of this thread."""
    caught = getattr(_held, "caught", None)
    if caught is not None:
        caught.append((str(message), category))
        return
    warnings.warn(message, category, stacklevel=caller_stacklevel())


def caller_stacklevel():
    """The ``stacklevel`` that names the first frame outside ``orbits``.

    For a warning raised by the function that calls this: it points at the
    user's line, however deep in the package the warning arises.
    """
    package = os.path.dirname(os.path.abspath(__file__)) + os.sep
    frame, level = sys._getframe(1), 1  # the function that warns
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(package):
        frame, level = frame.f_back, level + 1
    return level
