"""Resource bounds: memory budget, size and time estimates, and their messages.

Every command that could outgrow the machine asks this module first: the
memory one run may use (:func:`memory_budget`, half of physical memory),
the rough cost of a closed-orbit search (:func:`level_estimate`,
:func:`search_estimate`, refused by :func:`check_search_bounds` beyond the
budget or :data:`MAX_SECONDS`), the cost of a resolution grid
(:func:`check_resolution`), and the wording of sizes and durations in
those messages (:func:`format_bytes`, :func:`format_duration`,
:func:`about_bytes`, :func:`about_duration`, :func:`short_number`).

It imports nothing of the package above :mod:`orbits._args` and
:mod:`orbits.errors`, so every layer may use it.
"""

import math
import os

from ._args import integer, real_scalar
from .errors import InputError


# --------------------------------------------------------------- budget
def memory_budget():
    """Bytes one run may use: half the machine's physical memory."""
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        total = 8 << 30
    return total // 2


def input_limit():
    """Bytes an input file (bodies, point masses) may hold: 1/16 of :func:`memory_budget`.

    Parsing takes several times the text's size; a device or an endless pipe
    (``/dev/zero``) is refused at this size instead of filling the memory.
    """
    return memory_budget() // 16


def read_input_bytes(path, what, limit=None):
    """The bytes of an input file (at most ``limit`` when given).

    Links, pipes and devices are read as files (``/dev/stdin``); ``what``
    names the file in the one-line errors (``"catalog"``, ``"bodies file"``).

    Raises
    ------
    InputError
        No such file, a directory, unreadable, or larger than ``limit``.
    """
    from .atomic import read_limited

    try:
        if limit is None:
            with open(path, "rb") as handle:
                return handle.read()
        return read_limited(path, limit)
    except FileNotFoundError:
        raise InputError(f"no {what} at {path}") from None
    except IsADirectoryError:
        raise InputError(f"{path} is a directory, not a {what}") from None
    except OSError as error:
        raise InputError(f"cannot read {path}: {error.strerror}") from None


def read_input_text(path, what):
    """The UTF-8 text of an input file, at most :func:`input_limit` bytes.

    Links, pipes and devices are read as files (``/dev/stdin``); a leading
    UTF-8 byte-order mark is dropped; ``what`` names the file in the
    one-line errors (``"bodies file"``,
    ``"point-mass file"``).

    Raises
    ------
    InputError
        No such file, a directory, not UTF-8 text, unreadable, or larger
        than the limit.
    """
    data = read_input_bytes(path, what, input_limit())
    try:
        # utf-8-sig: a leading byte-order mark (Excel's "CSV UTF-8") is dropped
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(f"{path} is not a {what} (not UTF-8 text)") from None


# measured on the 2-core AMD EPYC VM (2026-11-28): phase_levels(2, 1000),
# 1,001,000 candidate fractions in 6.8 s; `orbits catalog --preset fig6
# --n-max 2 --q-max 600`, 139,281 rows in 4.5 s and 500 MB at peak; `orbits
# catalog --bodies` of 10,000 bodies at n <= 10, 27.4 s and 731 MB (one
# closed_orbits table per body, then joined).  A catalog row is bounded by
# two per level and body (the estimate's rows), about 0.3-0.6 of that are
# found.
_SECONDS_PER_CANDIDATE = 7e-6
_BYTES_PER_LEVEL = 400  # Fraction set, sorted list and level arrays
_BYTES_PER_ROW = 600  # catalog row (of the bound): search arrays, DataFrame, CSV text
_SECONDS_PER_ROW = 1e-5  # catalog row (of the bound): phases, DataFrame, CSV text
_BYTES_PER_BODY = 40e3  # one body's table and its part of the join
_SECONDS_PER_BODY = 3e-3  # one body's search and table, one core
_BYTES_PER_GRID_POINT = 200  # region_grid: meshgrid, moments and masks
MAX_SECONDS = 24 * 3600


def _as_float(number):
    """A count as a float; inf beyond the doubles (not OverflowError)."""
    try:
        return float(number)
    except OverflowError:
        return math.inf


# --------------------------------------------------------------- estimates
def level_estimate(n_max, q_max):
    """``(candidates, levels)``: fractions tried and kept by :func:`phase_levels`.

    The levels are the fractions ``p/q <= n_max`` with ``q <= q_max`` in
    lowest terms: about ``(6/pi^2) n_max q_max^2 / 2`` of them, built from
    ``n_max q_max (q_max + 1) / 2`` candidates.  Floats (inf beyond a double).
    """
    n, q = _as_float(n_max), _as_float(q_max)
    candidates = n * q * (q + 1.0) / 2.0
    return candidates, candidates * 6.0 / math.pi**2 + n


def search_estimate(n_max, q_max, bodies=1):
    """Rough memory (bytes) and time (s) of a closed-orbit search.

    Levels as :func:`level_estimate`; each body gives at most two orbits
    per level, and costs a table of its own (the constants above, measured).
    """
    candidates, levels = level_estimate(n_max, q_max)
    # bodies = 0 adds nothing (not inf * 0 = NaN when n_max overflows a double)
    rows = 2.0 * levels * bodies if bodies else 0.0
    memory = levels * _BYTES_PER_LEVEL + rows * _BYTES_PER_ROW + bodies * _BYTES_PER_BODY
    seconds = (
        candidates * _SECONDS_PER_CANDIDATE + rows * _SECONDS_PER_ROW + bodies * _SECONDS_PER_BODY
    )
    return memory, seconds


# --------------------------------------------------------------- refusals
def check_search_bounds(n_max, q_max, bodies=1, what="this search"):
    """Refuse a search whose memory or time would exceed the machine.

    Returns
    -------
    memory, seconds : float
        The estimate, for a progress message.

    Raises
    ------
    InputError
        The estimate exceeds :func:`memory_budget` or a day.
    """
    memory, seconds = search_estimate(n_max, q_max, bodies)
    budget = memory_budget()
    n_max, q_max = short_number(n_max), short_number(q_max)
    lower = "lower --n-max or --q-max"
    if bodies > 1:
        # a catalog holds every body's table at once; a survey writes chunks
        lower += " or give fewer bodies (orbits survey --bodies takes many, in chunks)"
    if not memory <= budget:  # also a NaN estimate (inf * 0 for a huge n_max)
        raise InputError(
            f"{what} (n_max={n_max}, q_max={q_max}, {plural(bodies, 'body', 'bodies')}) "
            f"would need {about_bytes(memory)} of memory, more than the "
            f"{format_bytes(budget)} allowed (half of this machine's); {lower}"
        )
    if not seconds <= MAX_SECONDS:
        raise InputError(
            f"{what} (n_max={n_max}, q_max={q_max}, {plural(bodies, 'body', 'bodies')}) "
            f"would take {about_duration(seconds)}; {lower}"
        )
    return memory, seconds


def check_resolution(resolution, name="resolution"):
    """Refuse a grid whose construction alone would exceed the machine.

    ``name``: the argument's name in messages (``--resolution`` on the
    command line).
    """
    resolution = integer(name, resolution, minimum=2)
    # integer arithmetic: float(resolution) ** 2 overflows for absurd grids
    memory = float(min(resolution * resolution * _BYTES_PER_GRID_POINT, 10**300))
    if memory > memory_budget():
        raise InputError(
            f"{name} {resolution} would need about {format_bytes(memory)} "
            f"of memory for the grid alone, more than the "
            f"{format_bytes(memory_budget())} allowed (half of this machine's)"
        )
    return int(resolution)


# ------------------------------------------------------------------- verify
# orbits verify / orbits.checks.verify: memory per initial condition (the
# table's ~35 float columns, the route evaluations and the integrations'
# state) and time (measured here: 64,460 initial conditions in 1.5 s)
VERIFY_BYTES_PER_CONDITION = 2000
VERIFY_SECONDS_PER_CONDITION = 3e-5
# A discrepancy of up to PHASE_ULPS spacings of doubles at |Delta alpha|
# passes whatever the tolerance: a value correct to a few ulps is all that
# double precision can hold (near the sphere Delta alpha reaches 1e8..1e9
# rad, where doubles are 1e-8..1e-7 apart), and the closed form and the
# checks differ by up to 14 ulps (measured over 100,000 initial conditions
# of verify(10000, 10), and <= 4 ulps on the nearly spherical bodies of
# docs/checks.md); a real inaccuracy, like the 160 ulps of the earlier
# quadrature near the sphere, still fails.
PHASE_ULPS = 16
# The closed form as the public functions compute it must agree with the
# closed form the checks were compared with to this many spacings of
# doubles, whatever the tolerance: the same formula for the same orbit,
# differing only in the order of operations (the SIMD kernels' polynomial
# sine and cosine, cel's pair loop); measured at most 14 over the 100,000
# initial conditions of verify(10000, 10) and 200 random, thin-rod, nearly
# spherical and nearly prolate bodies (docs/checks.md).
ROUTE_ULPS = 64
# the relative tolerance of verify's ODE check (a) (DOP853)
VERIFY_ODE_RTOL = 1e-12
# Check (a)'s own error budget: verify allows it ODE_ERROR_FACTOR * rtol *
# |w0| T (rad), where T is the period the integration found and |w0| T the
# angle the body turns through at its initial rate in it (radians; the
# integration takes ~2.7 steps per radian).  DOP853's global error in the
# rotation about M grows in proportion to both: over the 644,600 initial
# conditions of verify(29300) and 330 more on thin rods, nearly prolate,
# oblate and nearly spherical bodies, |error| / (rtol |w0| T) was at most
# 0.62 wherever the error is the integrator's, falling ~10x per decade of
# rtol (e.g. (1, 1.0001, 1.0002) at theta = 0.0357: 5.1e-8, 5.0e-9,
# 4.7e-10 at rtol 1e-11, 1e-12, 1e-13, a ratio of 0.11; the 0.62 row, at
# relative separatrix gap 2.7e-2: 6.2e-12, 1.5e-12, 1.3e-13); the factor
# is ten times that.  Not covered: the rows within ~3e-5 (relative gap) of
# the separatrix whose error does not fall with rtol -- the rounding of
# the state, which the orbit's sensitivity there amplifies (ratios up to
# 25, 3.0e-9 rad, at gap 9e-8): GAP_ROUNDING_FACTOR covers those.
ODE_ERROR_FACTOR = 6.0
# Check (a)'s conditioning next to the separatrix: the orbit's distance
# from it, the gap M^2 - 2 E I2 = I3 (I3 - I2) w3^2 - I1 (I2 - I1) w1^2, is
# held by a double state only to about eps times its two terms, and any
# integration in doubles moves it by that much: in ln g, with g the gap
# over its two terms, by eps / g, which moves the phase by eps / g *
# |d Delta alpha / d ln g|.  verify also allows check (a)
# GAP_ROUNDING_FACTOR times that.  Measured over the 99 initial conditions
# of verify(29300) with g < 3e-4: the error does not fall with rtol there
# (at g = 3.0e-7, the row that failed at 3.0e-9 rad before this term, with
# atol 1e-16: 1.1e-8, 1.7e-8, 5.1e-9 rad at rtol 1e-12, 1e-13, 1e-14), and
# it is at most 4.1 times eps / g * |d Delta alpha / d ln g| at verify's
# rtol 1e-12 and atol 1e-14 (3.4 and 3.1 at rtol 1e-13 and 1e-14; 5.2 with
# atol 1e-16); the factor is about five times 4.1.  At
# g >= 3e-4 the term is below 7.1e-10 rad (verify's tolerance is 1e-9);
# it exceeds 1e-9 at 11 of the 644,600 rows, all with g < 1.2e-4.  Near
# the sphere the two terms are small too, so g is not: (1, 1.0001, 1.0002)
# gets at most 1.1e-9 rad from it, against 5.7e-7 from ODE_ERROR_FACTOR.
# Checks (b) and (c) take the gap exactly and are not given this.
GAP_ROUNDING_FACTOR = 20.0


def _count(n):
    """An integer for a message: its digits, or its power of ten when it has more than 15."""
    digits = str(n)
    return digits if len(digits) <= 15 else f"~1e{len(digits) - 1}"


def check_verify_size(n_bodies, n_angles):
    """Refuse a verification whose table would exceed the memory allowed.

    Returns ``(initial conditions, bytes)``; called by the command line
    before it imports SciPy, and by :func:`orbits.checks.verify`.
    """
    total = n_bodies * n_angles
    memory = total * VERIFY_BYTES_PER_CONDITION
    if memory > memory_budget():
        need = (
            f"about {format_bytes(memory)}"
            if memory < 2.0**1000  # a double can hold it (--angles 1e400 is an int)
            else "more bytes than a double can count"
        )
        raise InputError(
            f"verify with {_count(n_bodies)} bodies x {_count(n_angles)} angles = "
            f"{_count(total)} initial conditions would need {need} of memory, more than "
            f"the {format_bytes(memory_budget())} allowed (half of this machine's)"
        )
    return total, memory


# --------------------------------------------------------------- animations
# measured here (2-core VM, 2026-11-24): drawing one frame of a Poinsot
# animation takes ~0.2 s at dpi 40 to 160 alike (the 3-D artists dominate);
# a GIF keeps every frame (RGB and its palette image: 4 bytes a pixel), the
# scene ~2 KB a frame (8 sub-steps of the traced curves), and a rendered
# frame needs a few buffers of 4 bytes a pixel (Agg's RGBA, copies)
_SECONDS_PER_FRAME = 0.2
_SECONDS_PER_FRAME_PIXEL = 1e-8
_SCENE_BYTES_PER_FRAME = 2048
_RENDER_BUFFERS = 3
# matplotlib's Agg canvas refuses images of 2**16 pixels or more on a side
AGG_MAX_PIXELS = 2**16 - 1


def animation_estimate(frames, dpi, size=(9.0, 4.0), keep_frames=True):
    """Rough memory (bytes) and time (s) of writing a Poinsot animation.

    ``keep_frames``: the writer holds every frame (GIF) rather than
    streaming them (MP4).
    """
    pixels = max(1.0, size[0] * dpi) * max(1.0, size[1] * dpi)
    frames = _as_float(frames)
    memory = frames * _SCENE_BYTES_PER_FRAME + _RENDER_BUFFERS * 4.0 * pixels
    if keep_frames:
        memory += frames * 4.0 * pixels
    seconds = frames * (_SECONDS_PER_FRAME + pixels * _SECONDS_PER_FRAME_PIXEL)
    return memory, seconds


def check_animation(
    frames, dpi, size=(9.0, 4.0), keep_frames=True, frames_name="frames", dpi_name="dpi"
):
    """Refuse an animation whose frames would not fit the machine or a day.

    ``dpi`` must be a positive finite number with each side of a frame
    between 1 and :data:`AGG_MAX_PIXELS` pixels; the memory of one frame's
    buffers must fit :func:`memory_budget` (else ``dpi_name`` is named),
    and that of all frames (a GIF holds them all) too (else
    ``frames_name``).  The names are the caller's spelling (``--frames``
    on the command line).

    Returns
    -------
    memory, seconds : float
        The estimate, for a progress message.

    Raises
    ------
    ArgumentTypeError, InputError
    """
    dpi = real_scalar(dpi_name, dpi)
    low, high = 1.0 / min(size), AGG_MAX_PIXELS / max(size)
    if not (math.isfinite(dpi) and low <= dpi <= high):
        raise InputError(
            f"{dpi_name} must be a number from {low:g} to {math.floor(high)} (frames of "
            f"{size[0]:g} x {size[1]:g} in, at most {AGG_MAX_PIXELS} pixels a side), got {dpi:g}"
        )
    budget = memory_budget()
    one, _ = animation_estimate(0, dpi, size, keep_frames=False)
    if one > budget:
        raise InputError(
            f"{dpi_name} {dpi:g} would need {about_bytes(one)} of memory for one frame, "
            f"more than the {format_bytes(budget)} allowed (half of this machine's); "
            f"lower {dpi_name}"
        )
    memory, seconds = animation_estimate(frames, dpi, size, keep_frames)
    count = short_number(frames)
    if not memory <= budget:
        held = " (a GIF holds every frame; an .mp4 streams them)" if keep_frames else ""
        raise InputError(
            f"{count} frames at {dpi_name} {dpi:g} would need {about_bytes(memory)} of memory"
            f"{held}, more than the {format_bytes(budget)} allowed (half of this machine's); "
            f"lower {frames_name} or {dpi_name}"
        )
    if not seconds <= MAX_SECONDS:
        raise InputError(
            f"{count} frames would take {about_duration(seconds)} to draw; lower {frames_name}"
        )
    return memory, seconds


# --------------------------------------------------------------- wording
def plural(count, singular, many=None):
    """``"1 body"``, ``"2 bodies"``: the count and the word in the right number.

    ``many`` defaults to ``singular + "s"``.
    """
    word = singular if count == 1 else (many or singular + "s")
    return f"{count} {word}"


def short_number(number):
    """A count for a message: digits up to 1e15, else ~1.2e+30."""
    if abs(number) < 10**15:
        return str(number)
    try:
        return f"~{float(number):.2g}"
    except OverflowError:
        return "beyond 1e308"


def format_bytes(count):
    """``3.2 GiB``: a byte count with three significant digits and a binary unit."""
    try:
        count = float(count)
    except OverflowError:  # an int beyond a double
        count = math.inf
    if not math.isfinite(count):
        return "more bytes than a double can count"
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if unit == "PiB":
            return f"{count:.3g} {unit}"
        if count < 1023.5:  # else it would print as 1024 of this unit
            # 999.5 to 1023.5 in whole units: %.3g would write 1e+03
            return f"{count:.3g} {unit}" if count < 999.5 else f"{count:.0f} {unit}"
        count /= 1024
    return f"{count:.3g} EiB"


def about_bytes(count):
    """``about 3.2 GiB``, or a phrase for an estimate beyond a double."""
    return (
        f"about {format_bytes(count)}" if math.isfinite(count) else "more than a double can count"
    )


def about_duration(seconds):
    """``about 5 min``, or ``forever`` for an estimate beyond a double."""
    return f"about {format_duration(seconds)}" if math.isfinite(seconds) else "forever"


def format_duration(seconds):
    """``42 s``, ``17 min``, ``3.5 h`` or ``12 days``: a duration for a message."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 3 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.3g} days"
