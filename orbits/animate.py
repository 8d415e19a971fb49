"""Poinsot animations: the body tumbling, its inertia ellipsoid rolling on the plane.

Poinsot's construction (Landau & Lifshitz, Mechanics, Sec. 37; Goldstein,
Sec. 5.6).  With ``I`` the body's inertia tensor (principal moments as
given, e.g. in kg m^2 = J s^2), ``omega`` the angular velocity (rad/s),
``E = omega.I.omega / 2`` (J) and ``M = |I omega|`` (J s):

* the **inertia ellipsoid** ``x.I.x = 1`` (body frame; ``x`` in units of
  ``(J s^2)^(-1/2)``, semi-axes ``1/sqrt(I_k)``) moves with the body;
* the point ``rho = omega / sqrt(2E)`` (same units) lies on it, since
  ``rho.I.rho = omega.I.omega / 2E = 1``; the ellipsoid's normal there is
  ``I rho``, parallel to the fixed angular momentum;
* so the ellipsoid touches the **invariable plane** ``x.M_hat = sqrt(2E)/M``
  (perpendicular to M, at the fixed distance
  ``rho.M_hat = omega.I.omega / (sqrt(2E) M) = sqrt(2E)/M``) at ``rho``;
* ``rho`` is on the instantaneous rotation axis, so the contact point is at
  rest: the ellipsoid **rolls without slipping**.  ``rho`` traces the
  **polhode** on the ellipsoid (body frame) and the **herpolhode** on the
  plane (space frame, ``omega_space / sqrt(2E)``).

The space frame is :class:`orbits.Motion`'s: z along M, so the plane is
``z = sqrt(2E)/M``.  The solid (T-handle, box, mesh or the equivalent
ellipsoid) is drawn inside the inertia ellipsoid, scaled from its length
units by the factor stated in the panel title.

Public API
----------
:func:`poinsot_animation`
    Build (and optionally write) the animation of any body and spin, of a
    :class:`~orbits.Motion`, or of a catalog row.
:func:`orbit_row`
    The catalog row of a body's closed orbit by its ``n`` or ``p/q``.
:func:`flip_motion`
    A spin near the intermediate axis (the Dzhanibekov / tennis-racket flip).
:class:`PoinsotAnimation`
    The figure, the frames' drawn data and ``save``.

The geometry drawn (solids, wire frame, contact point and traced curves
per frame) is computed in :mod:`orbits.animation_scene`, without
matplotlib; this module turns it into artists, frames and files.
"""

import io
import math
import numbers
import os
import threading
import warnings
from pathlib import Path

import numpy as np

from ._args import (
    NOT_NUMBERS,
    caller_stacklevel,
    finite_array,
    flag,
    given_besides,
    held_warnings,
    integer,
    path_argument,
    real_scalar,
    warn,
)
from .animation_scene import (
    FrameData,
    PoinsotScene,
    frame_times,
    inertia_ellipsoid_lines,
    solid_faces,
    t_handle_boxes,
)
from .atomic import atomic_path, ensure_writable
from .bodies import Body
from .cells import literal_text
from .errors import AngleError, ArgumentTypeError, InputError, OrbitsError
from .limits import AGG_MAX_PIXELS, check_animation, short_number
from .motion import Motion, as_body

FORMATS = ("gif", "mp4")
# 9 x 4 in frames at 120 dpi: 1080 x 480 px, text 14 px (small) to 17 px (title)
DEFAULT_DPI = 120
DEFAULT_FPS = 20
# a GIF stores each frame's delay in whole hundredths of a second, and browsers
# play a delay of 0 or 1 as 10: only these rates play as given (100/fps >= 2 cs)
GIF_FPS = (1, 2, 4, 5, 10, 20, 25, 50)
# mathtext draws a subscript (I_1 on the axes) at 0.7 of its text's size
_SUBSCRIPT = 0.7
# colours of the drawing (one place, so that the two panels agree)
COLOURS = {
    "solid": "tab:green",
    "ellipsoid": "0.45",
    "plane": "tab:blue",
    "omega": "tab:red",
    "momentum": "black",
    "herpolhode": "tab:purple",
    "polhode": "tab:orange",
    "axes": ("tab:red", "tab:green", "tab:blue"),
}


# the most the body may turn between frames before a warning: the drawn
# solids (ellipsoid, box, cylinder) look alike after a half turn about an
# axis, so past a quarter turn a frame can read as a turn the other way
ALIASING_TURN = 0.5 * math.pi
# the turn between frames the warning's suggested frame count keeps to
SMOOTH_TURN = 0.25 * math.pi


class AliasingWarning(UserWarning):
    """The body turns more than a quarter turn (:data:`ALIASING_TURN`) between frames.

    The drawn solid can then seem to turn slowly, stand still or turn
    backwards (the wagon-wheel effect); the traced curves stay right.  The
    message gives a frame count that keeps the turn under 45 degrees.
    """


# ----------------------------------------------------------------- inputs
def min_dpi():
    """The smallest dpi at which every text of the frames can be drawn.

    FreeType sets a font at ``points x int(dpi) / 72`` pixels rounded to a
    whole number, and refuses 0 (``invalid ppem value``).  The smallest text
    of the frames is a subscript (0.7 of the size) in a ``small`` caption
    (the body axes' ``I_1``): it needs at least half a pixel.  With
    matplotlib's default font size (10 pt: small is 8.33 pt) that is 7.

    Returns
    -------
    int
    """
    from matplotlib.font_manager import FontProperties

    points = FontProperties(size="small").get_size_in_points() * _SUBSCRIPT
    return max(1, math.ceil(36.0 / points))


def check_dpi(dpi, name="dpi", size=(9.0, 4.0)):
    """``dpi`` as a float, or an :class:`InputError` naming ``name``.

    From :func:`min_dpi` (7: the frames' smallest text) to
    ``AGG_MAX_PIXELS / max(size)`` (7281 for 9 x 4 in frames: matplotlib's
    Agg draws at most 65535 pixels a side).  ``name`` is the caller's
    spelling (``--dpi`` on the command line).
    """
    dpi = real_scalar(name, dpi)
    low, high = min_dpi(), AGG_MAX_PIXELS / max(size)
    if not (math.isfinite(dpi) and low <= dpi <= high):
        raise InputError(
            f"{name} must be a number from {low} to {math.floor(high)} (the frames' smallest "
            f"text needs {low} pixels per inch; frames of {size[0]:g} x {size[1]:g} in have "
            f"at most {AGG_MAX_PIXELS} pixels a side), got {dpi:g}"
        )
    return dpi


def check_size(size):
    """``size`` as ``(width, height)`` floats in inches, or an :class:`InputError`.

    Each side positive and at most what Agg draws at the smallest legible
    dpi (``AGG_MAX_PIXELS / min_dpi()``, 9362 in).
    """
    if isinstance(size, (str, bytes)) or not hasattr(size, "__len__") or len(size) != 2:
        raise InputError(f"size must be (width, height) in inches, got {size!r}")
    width, height = (real_scalar("size", side) for side in size)
    largest = AGG_MAX_PIXELS / min_dpi()
    if not all(math.isfinite(side) and 0.0 < side <= largest for side in (width, height)):
        raise InputError(
            f"size must be two positive numbers of inches, each at most {math.floor(largest)} "
            f"(Agg draws {AGG_MAX_PIXELS} pixels a side, the text needs {min_dpi()} dpi), "
            f"got {size!r}"
        )
    return width, height


def check_fps(fps, fmt=None, name="fps"):
    """``fps`` as an int from 1 to 100, one a GIF can play when ``fmt`` is ``"gif"``.

    A GIF stores each frame's delay in whole hundredths of a second, and
    browsers play a delay of 1 (or 0) as 10: only the rates of
    :data:`GIF_FPS` (delays 100/fps of 2 cs and more) play at their speed.
    An MP4 takes any rate.

    Raises
    ------
    InputError
        Naming ``name`` (``--fps`` on the command line).
    """
    if (
        isinstance(fps, NOT_NUMBERS)
        or not isinstance(fps, numbers.Real)
        or not 1 <= fps <= 100  # first: math.isfinite(10**400) overflowed
        or fps != int(fps)
    ):
        raise InputError(f"{name} must be an integer from 1 to 100, got {fps!r}")
    fps = int(fps)
    if fmt == "gif" and fps not in GIF_FPS:
        rates = ", ".join(str(v) for v in GIF_FPS[:-1]) + f" or {GIF_FPS[-1]}"
        raise InputError(
            f"{name} {fps} cannot play at its speed in a GIF: a GIF holds each frame's "
            f"delay in whole hundredths of a second (100/{fps} = {100 / fps:.3g}) and "
            f"browsers play 1 as 10; give {name} {rates}, or write an .mp4"
        )
    return fps


def real_time_frames(seconds, fps):
    """The frames of ``seconds`` played at ``fps``: ``round(seconds x fps) + 1``.

    Not checked; a product beyond 2**62 counts as 2**62.
    """
    product = seconds * fps
    return int(round(product)) + 1 if product < 2.0**62 else 2**62


def check_real_time(seconds, fps, seconds_name="seconds", fps_name="fps"):
    """The frame count of a real-time animation, from 2 to :data:`MAX_FRAMES`.

    Raises
    ------
    InputError
        Fewer or more frames, naming ``seconds_name`` and ``fps_name``
        (``--seconds`` and ``--fps`` on the command line).
    """
    seconds = real_scalar(seconds_name, seconds)
    if not (math.isfinite(seconds) and seconds > 0):
        raise InputError(f"{seconds_name} must be positive, got {seconds!r}")
    frames = real_time_frames(seconds, fps)
    # the count itself where real_time_frames caps it (beyond 2**62), also
    # beyond a double (--seconds 1e308)
    count = short_number(frames)
    if frames >= 2**62:
        exponent = math.log10(seconds) + math.log10(fps)
        power = math.floor(exponent)
        mantissa = round(10.0 ** (exponent - power), 1)
        if mantissa >= 10.0:  # 9.96 rounds up to the next power
            mantissa, power = mantissa / 10.0, power + 1
        count = f"~{mantissa:.1f}e+{power}"
    what = (
        f"{seconds_name} {seconds:g} at {fps_name} {fps} is {count} "
        f"{'frame' if frames == 1 else 'frames'} (round(seconds x fps) + 1)"
    )
    if frames > MAX_FRAMES:
        lower_fps = f" or {fps_name}" if real_time_frames(seconds, 1) <= MAX_FRAMES else ""
        raise InputError(
            f"{what}, more than {MAX_FRAMES}: lower {seconds_name} (at most "
            f"{(MAX_FRAMES - 1) / fps:g}){lower_fps}"
        )
    if frames < 2:
        raise InputError(
            f"{what}, and an animation needs at least 2: give {seconds_name} of at least "
            f"{1 / fps:g} (one frame at {fps_name} {fps})"
        )
    return frames


def check_output(out, name="out", fmt=None):
    """The animation file ``out`` as ``(Path, format)``, checked before any drawing.

    The name has no control characters; the format (``fmt``, else the
    suffix) is ``gif`` or ``mp4``, and an MP4 has its ffmpeg writer; the
    directory exists and is writable, and ``out`` is not a directory or
    another file that is not a regular file.

    Raises
    ------
    InputError
        Naming ``name`` (``--out`` on the command line) or the path.
    """
    text = path_argument(name, out)
    bad = [c for c in text if ord(c) < 32 or ord(c) == 127]
    if bad:
        raise InputError(
            f"{name} {text!r} contains the control character {bad[0]!r}: "
            "give a file name without control characters"
        )
    path = Path(text)
    if path.is_dir() or text.endswith(("/", os.sep)):
        raise InputError(f"cannot write {text}: it names a directory (give a .gif or .mp4 file)")
    if fmt is None:
        fmt = path.suffix.lstrip(".").lower()
        if fmt not in FORMATS:
            if not path.suffix:
                # "-" (standard output elsewhere) or a bare name: no format to write
                raise InputError(
                    f"{name} {text!r} has no .gif or .mp4 suffix to choose the format "
                    "(an animation is written to a file, never to standard output)"
                )
            raise InputError(f"unknown animation format {path.suffix!r}; use .gif or .mp4")
    elif not isinstance(fmt, str) or fmt.lower() not in FORMATS:
        raise InputError(f"unknown animation format {fmt!r}; use {', '.join(FORMATS)}")
    fmt = fmt.lower()
    if fmt == "mp4" and not mp4_available():
        raise InputError(
            "MP4 needs an ffmpeg writer: pip install 'orbits[animation]' "
            "(imageio-ffmpeg), or write a .gif"
        )
    # the first folder above that exists must be a directory (not "does not exist")
    for folder in path.parents:
        if os.path.exists(folder):
            if not os.path.isdir(folder):
                raise InputError(f"cannot write {path}: {folder} is not a directory")
            break
    ensure_writable(path, stdout_hint=False)  # an animation has no standard-output form
    return path, fmt


def clock_text(t, times):
    """``t`` (s) with the decimals that tell the frames ``times`` apart (at least 3).

    A motion of period 1e-4 s (``--speed 1e4``) showed ``t = 0.000 s`` on
    every frame at three decimals.
    """
    steps = np.diff(np.asarray(times, dtype=float))
    step = float(steps[steps > 0].min()) if np.any(steps > 0) else 1.0
    decimals = 3 if step >= 1e-3 else math.ceil(-math.log10(step)) + 1
    if decimals > 12:
        return f"{t:.3e}"
    return f"{t:.{decimals}f}"


def orbit_row(body, *, n=None, p=None, q=1, branch=None, orbits=None):
    """The catalog row of one closed orbit of ``body``.

    Parameters
    ----------
    body : Body or array_like, shape (3,)
    n : int, optional
        The multiple of an integer orbit ``Delta alpha = 2 pi n`` (same as
        ``p`` with ``q = 1``).
    p, q : int, optional
        The orbit ``Delta alpha = 2 pi p/q`` (in lowest terms).
    branch : {"SAM", "LAM"}, optional
        Needed when both branches have the orbit (they usually do).
    orbits : DataFrame, optional
        A catalog to pick from (:func:`orbits.closed_orbits` or
        :func:`orbits.read_catalog`); computed if omitted.

    Returns
    -------
    pandas.Series
        The row, with the columns of :data:`orbits.CATALOG_COLUMNS`.

    Raises
    ------
    InputError
        Neither or both of ``n`` and ``p``; no such orbit; an orbit that
        exists but lies closer than ``|dtheta| = 2.2e-308`` to the
        separatrix (a double cannot hold it: the message gives the largest
        ``n`` drawable on the branch); two orbits match and no ``branch``
        was given; ``n`` with ``q`` other than 1; ``orbits`` not a catalog
        frame, or without rows of ``body`` (rows of other bodies are left
        out).
    """
    from .search import UnresolvedOrbitsWarning, closed_orbits

    if (n is None) == (p is None):
        raise InputError("give exactly one of n and p")
    label_p = "n" if n is not None else "p"
    q = integer("q", q)
    if n is not None:
        if q != 1:
            raise InputError(f"n is the orbit 2 pi n (q = 1); for 2 pi p/{q} give p and q")
        p = n
    p = integer(label_p, p)
    body = as_body(body)
    if math.gcd(p, q) != 1:
        raise InputError(f"p/q = {p}/{q} is not in lowest terms")
    if branch is not None and (not isinstance(branch, str) or branch not in ("SAM", "LAM")):
        raise InputError(f"branch must be SAM or LAM, got {branch!r}")
    # the search's warnings are held back: an error below is one line (an
    # unresolved orbit is said there), a row found gets them as they came
    with held_warnings() as caught:  # not catch_warnings: not thread-safe
        if orbits is None:
            # ceil(p/q) in integers: p / q overflowed a double for p = 10**400
            orbits = closed_orbits(body, n_max=max(1, -(-p // q)), q_max=q)
        else:
            orbits = _rows_of(body, orbits)
    match = orbits[(orbits["n"] == p) & (orbits["q"] == q)]
    if branch is not None:
        match = match[match["branch"] == branch]
    multiple = f"{p}" if q == 1 else f"{p}/{q}"
    for message, category in caught:
        # orbits left out are told when the row is missing (below) or when
        # the branch was not chosen (the other branch's may be among them);
        # with the chosen branch's row found they are other orbits than the one drawn
        unresolved = issubclass(category, UnresolvedOrbitsWarning)
        if not unresolved or (len(match) > 0 and branch is None):
            warn(message, category)
    if len(match) == 0:
        _refuse_unresolved(body, p, q, branch, multiple)
        where = f" on {branch}" if branch else ""
        raise InputError(f"the body has no closed orbit Delta alpha = 2 pi {multiple}{where}")
    if len(match) > 1:
        branches = ", ".join(sorted(set(match["branch"])))
        raise InputError(
            f"{len(match)} orbits have Delta alpha = 2 pi {multiple} "
            f"({branches}); choose one with branch='SAM' or 'LAM' (--branch)"
        )
    return match.iloc[0]


def _rows_of(body, orbits):
    """The rows of a catalog given to :func:`orbit_row` that are ``body``'s.

    A catalog of another body (or of several) gave another body's orbit, or
    asked for a branch that had been given.
    """
    import pandas as pd

    columns = ("I1", "I2", "I3", "n", "q", "branch")
    if not isinstance(orbits, pd.DataFrame) or not all(c in orbits.columns for c in columns):
        raise InputError(
            "orbits must be a catalog DataFrame (orbits.closed_orbits or "
            f"orbits.read_catalog), got {type(orbits).__name__}"
        )
    mine = _same_moments(body, orbits[["I1", "I2", "I3"]].to_numpy(dtype=float))
    if len(orbits) and not mine.any():
        raise InputError(
            "the catalog has no rows of this body (its moments, normalised, "
            f"are {body.normalized_moments.tolist()})"
        )
    return orbits[mine]


def _refuse_unresolved(body, p, q, branch, multiple):
    """Refuse the orbit ``2 pi p/q`` where it exists but a double cannot hold it.

    The search's own bound (:mod:`orbits.core.search`): a level above the
    phase at ``|dtheta| = 2.2e-308`` (``INFO_TOP_*``) is reached only closer
    to the separatrix than the smallest normal double, and is counted
    unreached (``INFO_UNREACHED_*``; :func:`orbits.closed_orbits` warns of
    it and leaves it out).  A level below the branch's minimum phase has no
    orbit at all: nothing is raised here, and the caller says so.
    """
    from .bodies import unit_moments
    from .core import search as kernels
    from .search import TWO_PI, find_roots_at

    moments, _ = unit_moments(as_body(body))
    level = 2.0 * np.pi * np.array([p], dtype=np.int64) / np.array([q], dtype=np.int64)
    _, _, _, info = find_roots_at(
        moments, np.array([p], dtype=np.int64), np.array([q], dtype=np.int64), level
    )
    slots = {
        "SAM": (kernels.INFO_UNREACHED_SAM, kernels.INFO_TOP_SAM),
        "LAM": (kernels.INFO_UNREACHED_LAM, kernels.INFO_TOP_LAM),
    }
    names = [branch] if branch is not None else ["SAM", "LAM"]
    unresolved = [name for name in names if info[slots[name][0]] > 0]
    if not unresolved:
        return
    largest = []
    for name in unresolved:
        top = float(info[slots[name][1]])
        # the largest whole n whose level 2 pi n (as phase_levels forms it)
        # the search reaches: not above the phase at the smallest offset
        count = math.floor(top / TWO_PI)
        while 2.0 * np.pi * (count + 1) <= top:
            count += 1
        while count > 0 and 2.0 * np.pi * count > top:
            count -= 1
        largest.append(
            f"the largest n drawable on {name} is {count}"
            if count >= 2
            else f"no closed orbit Delta alpha = 2 pi n is drawable on {name}"
        )
    where = " and ".join(unresolved)
    raise InputError(
        f"the closed orbit Delta alpha = 2 pi {multiple} on {where} lies closer than "
        "|dtheta| = 2.2e-308 to the separatrix and cannot be held in double "
        f"precision; {'; '.join(largest)}"
    )


def check_span(motion, span):
    """Refuse an animation whose times ``[0, span]`` the motion cannot place.

    :meth:`orbits.Motion.state`'s own check, before anything is drawn:
    ``|t|`` beyond ``2**50`` periods (the orientation there is lost to
    rounding), or ``t |omega0|`` beyond a double.

    Raises
    ------
    InputError
        With :class:`~orbits.Motion`'s message.
    """
    motion.check_times(np.array([0.0, float(span)]))


def flip_motion(body=None, *, offset=0.05, speed=1.0):
    """A spin close to the intermediate axis: the Dzhanibekov / tennis-racket flip.

    ``omega0 = speed (sin t cos p, sin t sin p, cos t)`` with
    ``t = pi/2 - offset`` and ``p = pi/2 - offset``, i.e.
    ``speed (sin(offset) cos(offset), cos(offset)^2, sin(offset))``: almost
    along I2, tipped by ``offset`` towards I1 and by ``offset`` towards I3,
    so at ``arccos(cos(offset)^2)``, about ``sqrt(2) offset``, from I2
    (0.0707 rad for the default 0.05).  The motion lies close to the
    separatrix; once per half period the body turns over (the I2 axis
    reverses), the longer the wait the smaller ``offset``
    (``T ~ log(1/offset)``).  The vector is formed from ``offset`` itself,
    so it keeps its digits (on the T-handle the period is that of the exact
    offset to ~1e-15 relative at ``offset = 1e-300``; on a thin rod such as
    ``(1e-12, 1, 1 + 1e-12)``, whose orbit is far more sensitive to the
    rounding of ``cos(offset)^2``, to 4.5e-7 at 1e-6 and 7.5e-7 at 1e-8;
    the motion is exact for the ``omega0`` it returns) down to where the
    orbit's ``k_c = sqrt(1 - k^2)`` would fall below
    ``orbits.core.phase.KC_FLOOR`` (4.9e-312): an offset of 3.5e-312 on
    the T-handle, 3.5e-306 on a thin rod; a smaller one is refused
    (:class:`~orbits.SeparatrixError`).

    Parameters
    ----------
    body : Body, optional
        Default: the paper's T-handle (8, 4, 1), whose I2 axis is its shaft.
    offset : float
        Radians, ``0 < offset < pi/4``: the tilt towards each of I1 and I3.
    speed : float
        ``|omega0|``, positive, in radians per unit of the motion's time
        (rad/s gives times in s); default 1.

    Returns
    -------
    Motion

    Raises
    ------
    InputError
        ``offset`` outside (0, pi/4).
    AngleError
        ``speed`` not positive and finite.
    SeparatrixError
        ``offset`` too small for a double (see above).
    """
    offset = real_scalar("offset", offset, InputError)
    if not (math.isfinite(offset) and 0.0 < offset < 0.25 * math.pi):
        raise InputError(f"offset must be in (0, pi/4), got {offset!r}")
    speed = real_scalar("speed", speed, AngleError)
    if not (math.isfinite(speed) and speed > 0.0):
        raise AngleError(f"speed must be positive, got {speed}")
    body = Body.preset("t-handle") if body is None else as_body(body)
    # the vector from the offset itself, not from the angle pi/2 - offset:
    # that angle rounded keeps only about offset/1e-16 of the offset's
    # digits (T 5e-6 off at 1e-12) and none below 6e-17 (every smaller
    # offset was the same spin)
    sin_o, cos_o = math.sin(offset), math.cos(offset)
    return Motion(body, speed * np.array([sin_o * cos_o, cos_o * cos_o, sin_o]))


class PoinsotAnimation:
    """A Poinsot animation: a figure with a space-frame and a body-frame panel.

    Built by :func:`poinsot_animation`.  ``frame(k)`` draws frame k and
    returns its :class:`FrameData`; ``save(path)`` writes a GIF or MP4.

    Attributes
    ----------
    motion : Motion
    scene : PoinsotScene
        The geometry of every frame (:mod:`orbits.animation_scene`).
    times : ndarray (frames,)
        Frame times, from 0 to the animation's duration, both included (so
        the last frame of a closed orbit drawn over q periods is its first).
    fps : int
        1 to 100; :meth:`save` writes a GIF only at a rate of
        :data:`GIF_FPS`.
    figure : matplotlib.figure.Figure
    space_axes, body_axes : Axes3D
    artists : dict
        The drawn artists (updated in place by :meth:`frame`): ``axes``
        (three Line3D, the body axes in the space frame), ``ellipsoid``
        (Line3D wire frame), ``solid`` (Poly3DCollection), ``omega``,
        ``momentum`` (Line3D), ``contact`` (Line3D marker), ``herpolhode``
        (Line3D), ``plane`` (Poly3DCollection) and ``plane_edge`` (its
        outline, Line3D), ``polhode`` and
        ``body_contact`` (Line3D, body panel).
    solid_kind : str
    solid_scale : float
        Length units of the solid -> ellipsoid units (display only).

    Raises
    ------
    InputError
        ``times`` not finite, increasing and at least 2
        (:func:`orbits.animation_scene.frame_times`); ``fps`` not an
        integer from 1 to 100; ``dpi`` out of :func:`check_dpi`'s range or
        too large for the machine; a bad ``solid``.

    Warns
    -----
    AliasingWarning
        The body turns more than a quarter turn between two frames
        (:data:`ALIASING_TURN`); the message gives a frame count that keeps
        each turn under 45 degrees.
    """

    def __init__(
        self,
        motion,
        times,
        *,
        fps=DEFAULT_FPS,
        solid="auto",
        title=None,
        size=(9.0, 4.0),
        dpi=DEFAULT_DPI,
        pyplot=False,
        subsamples=8,
    ):
        self.motion = motion
        self.fps = check_fps(fps)
        size = check_size(size)
        if title is not None and not isinstance(title, str):
            raise ArgumentTypeError(f"title must be a str or None, got {type(title).__name__}")
        pyplot = flag("pyplot", pyplot)
        times = frame_times(times)
        # a dpi that draws the text and whose frame buffers fit the machine
        self.dpi = check_dpi(dpi, size=size)
        check_animation(len(times), dpi, size, keep_frames=False)
        self.scene = PoinsotScene(motion, times, solid=solid, subsamples=subsamples)
        self.times = self.scene.times
        _warn_aliasing(self.scene.frame_turns, self.times)
        self.plane_height = self.scene.plane_height
        self.solid_kind = self.scene.solid_kind
        self.solid_scale = self.scene.solid_scale
        self._build_figure(title, size, pyplot)
        self._animation = None
        self._lock = threading.RLock()

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_animation"] = None  # a FuncAnimation holds a lambda; built again on use
        del state["_lock"]
        return state

    def __setstate__(self, state):
        # an unpickled figure has a bare FigureCanvasBase (render() failed
        # with "no attribute buffer_rgba"): draw it with Agg again
        self.__dict__.update(state)
        self._lock = threading.RLock()
        if not hasattr(self.figure.canvas, "buffer_rgba"):
            from matplotlib.backends.backend_agg import FigureCanvasAgg

            FigureCanvasAgg(self.figure)

    # -- drawing --------------------------------------------------------
    def _build_figure(self, title, size, pyplot):
        from matplotlib.figure import Figure
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        if pyplot:
            import matplotlib.pyplot as plt

            figure = plt.figure(figsize=size, dpi=self.dpi)
        else:
            from matplotlib.backends.backend_agg import FigureCanvasAgg

            figure = Figure(figsize=size, dpi=self.dpi)
            FigureCanvasAgg(figure)
        self.figure = figure
        # explicit panels under the titles (3-D axes leave wide margins); each extra
        # line of the heading takes ~0.045 of the 4 in figure's height
        extra = 0.045 * (title.count("\n") if title else 0)
        space = figure.add_axes(
            (0.0, 0.0, 0.5, 0.84 - extra), projection="3d", computed_zorder=False
        )
        body_ax = figure.add_axes(
            (0.5, 0.0, 0.5, 0.84 - extra), projection="3d", computed_zorder=False
        )
        self.space_axes, self.body_axes = space, body_ax
        scene = self.scene
        h = self.plane_height
        semi = scene.semi_axes
        half, reach = scene.extents()
        artists = {}
        plane = np.array([[-half, -half, h], [half, -half, h], [half, half, h], [-half, half, h]])
        artists["plane"] = Poly3DCollection(
            [plane], facecolor=COLOURS["plane"], alpha=0.12, edgecolor="none"
        )
        space.add_collection3d(artists["plane"])
        outline = np.concatenate([plane, plane[:1]])
        (artists["plane_edge"],) = space.plot(
            *outline.T, color=COLOURS["plane"], linewidth=0.6, alpha=0.6
        )
        (artists["herpolhode"],) = space.plot(
            [], [], [], color=COLOURS["herpolhode"], linewidth=1.4, zorder=4
        )
        start = scene.rho_space[0]
        space.plot(
            [start[0]],
            [start[1]],
            [start[2]],
            "o",
            color=COLOURS["herpolhode"],
            markersize=4,
            zorder=5,
        )
        artists["ellipsoid"] = [
            space.plot([], [], [], color=COLOURS["ellipsoid"], linewidth=0.5, alpha=0.6, zorder=2)[
                0
            ]
            for _ in scene.wire
        ]
        # a fine mesh's edges would paint it solid dark: draw them faint
        fine = len(scene.faces) > 200
        edge = dict(
            edgecolor=(0.0, 0.39, 0.0, 0.12) if fine else "darkgreen",
            linewidths=0.2 if fine else 0.4,
        )
        artists["solid"] = Poly3DCollection(
            [], facecolor=COLOURS["solid"], alpha=0.55, zorder=3, **edge
        )
        space.add_collection3d(artists["solid"])
        artists["axes"] = [
            space.plot([], [], [], color=c, linewidth=1.0, zorder=4)[0] for c in COLOURS["axes"]
        ]
        (artists["momentum"],) = space.plot(
            [0.0, 0.0],
            [0.0, 0.0],
            [0.0, 1.25 * h],
            color=COLOURS["momentum"],
            linewidth=2.0,
            zorder=6,
        )
        space.text(0.0, 0.0, 1.3 * h, "L", color=COLOURS["momentum"], zorder=7)
        (artists["omega"],) = space.plot(
            [], [], [], color=COLOURS["omega"], linewidth=2.0, zorder=6
        )
        (artists["contact"],) = space.plot(
            [], [], [], "o", color=COLOURS["omega"], markersize=5, zorder=7
        )
        # the inertia ellipsoid lies between its two tangent planes z = +-h
        _cube(space, half, (-1.08 * h, 1.4 * h), zoom=1.75)
        space.view_init(elev=24, azim=-60)
        # body panel: the fixed inertia ellipsoid, the solid, the polhode
        for curve in scene.wire:
            body_ax.plot(*curve.T, color=COLOURS["ellipsoid"], linewidth=0.5, alpha=0.5)
        body_ax.add_collection3d(
            Poly3DCollection(scene.faces, facecolor=COLOURS["solid"], alpha=0.25, **edge)
        )
        for k, colour in enumerate(COLOURS["axes"]):
            tip = np.zeros(3)
            tip[k] = 1.15 * semi[k]
            body_ax.plot(*np.stack([-tip, tip]).T, color=colour, linewidth=0.8)
            body_ax.text(*(1.2 * tip), f"$I_{k + 1}$", color=colour, fontsize="small")
        (artists["polhode"],) = body_ax.plot([], [], [], color=COLOURS["polhode"], linewidth=1.6)
        (artists["body_contact"],) = body_ax.plot(
            [], [], [], "o", color=COLOURS["omega"], markersize=5
        )
        _cube(body_ax, reach, (-reach, reach), zoom=1.6)
        body_ax.view_init(elev=22, azim=-50)
        self.artists = artists
        body = self.motion.body
        name = literal_text(body.name or "body")
        heading = (
            title
            if title is not None
            else (
                f"{name}: Poinsot construction, {self.motion.branch}, "
                f"T = {self.motion.period:.4g} s at "
                f"|omega0| = {np.linalg.norm(self.motion.omega0):.4g} rad/s"
            )
        )
        self._title = figure.suptitle(heading, fontsize="medium", y=0.985)
        figure.text(
            0.25,
            0.905 - extra,
            "space frame (L fixed, along z): inertia ellipsoid rolling\n"
            "on the invariable plane; herpolhode (purple), "
            r"$\omega$ (red)",
            fontsize="small",
            ha="center",
            va="center",
        )
        figure.text(
            0.75,
            0.905 - extra,
            "body frame: polhode (orange) on the inertia ellipsoid\n"
            f"{self.solid_kind} drawn x{self.solid_scale:.3g}",
            fontsize="small",
            ha="center",
            va="center",
        )
        self._clock = figure.text(0.01, 0.02, "", fontsize="medium")

    def frame(self, k):
        """Draw frame ``k`` and return its :class:`FrameData`."""
        with self._lock:  # one figure: renders from two threads mixed frames
            data = self.scene.frame(k)
            rotation = data.rotation
            artists = self.artists
            for line, points in zip(artists["ellipsoid"], self.scene.ellipsoid_lines(rotation)):
                line.set_data_3d(points[:, 0], points[:, 1], points[:, 2])
            artists["solid"].set_verts(self.scene.solid_polygons(rotation))
            for line, tip in zip(artists["axes"], self.scene.axis_tips(rotation)):
                line.set_data_3d([-tip[0], tip[0]], [-tip[1], tip[1]], [-tip[2], tip[2]])
            contact, contact_body = data.contact, data.contact_body
            artists["omega"].set_data_3d([0.0, contact[0]], [0.0, contact[1]], [0.0, contact[2]])
            artists["contact"].set_data_3d([contact[0]], [contact[1]], [contact[2]])
            artists["herpolhode"].set_data_3d(*data.herpolhode.T)
            artists["polhode"].set_data_3d(*data.polhode.T)
            artists["body_contact"].set_data_3d(
                [contact_body[0]], [contact_body[1]], [contact_body[2]]
            )
            fraction = data.t / self.motion.period
            self._clock.set_text(
                f"t = {clock_text(data.t, self.scene.times)} s = {fraction:.3f} T"
            )
            return data

    @property
    def animation(self):
        """A :class:`matplotlib.animation.FuncAnimation` of the frames.

        For notebooks (``to_jshtml``) and sphinx-gallery (build the
        animation with ``pyplot=True`` and keep this object in a variable).
        """
        if self._animation is None:
            from matplotlib.animation import FuncAnimation

            self._animation = FuncAnimation(
                self.figure,
                lambda k: self.frame(k),
                frames=len(self.times),
                interval=1000.0 / self.fps,
                blit=False,
            )
        return self._animation

    def to_html(self):
        """The animation as an HTML player (matplotlib's ``to_jshtml``), shown once.

        Frames are embedded as JPEG (about 80 kB a frame at the default
        size and dpi; as PNG they took about 175 kB, and a default
        120-frame animation passed matplotlib's 20 MB
        ``animation.embed_limit``, which drops every later frame).  The
        figure is closed after the HTML is built, so that a notebook (or
        sphinx-gallery) does not show it a second time as a static image
        under the player.

        Warns
        -----
        UserWarning
            The player holds fewer frames than the animation (matplotlib's
            ``animation.embed_limit`` reached): fewer frames or a lower
            ``dpi``, or a larger ``matplotlib.rcParams["animation.embed_limit"]``
            (MB), show them all.
        """
        with self._lock:  # one figure: renders from two threads mixed frames
            import re

            import matplotlib
            import matplotlib.pyplot as plt

            with matplotlib.rc_context({"animation.frame_format": "jpeg"}):
                html = self.animation.to_jshtml(fps=self.fps)
            plt.close(self.figure)
            # matplotlib's player declares the frames it holds (0 when even the
            # first passed the limit)
            declared = re.search(r"var frames = new Array\((\d+)\)", html)
            held = int(declared.group(1)) if declared else len(self.times)
            if held < len(self.times):
                limit = matplotlib.rcParams["animation.embed_limit"]
                warn(
                    f"the HTML player holds {held} of the animation's {len(self.times)} frames: "
                    f"matplotlib's animation.embed_limit ({limit:g} MB) was reached; give fewer "
                    "frames or a lower dpi, or raise matplotlib.rcParams['animation.embed_limit']",
                    UserWarning,
                )
            return html

    def _repr_html_(self):
        return self.to_html()

    def render(self, k):
        """Frame ``k`` as an RGB array (height, width, 3), uint8.

        Raises
        ------
        InputError
            A text too small for FreeType at this dpi (a ``title`` with
            nested sub- or superscripts: :func:`min_dpi` covers the
            frames' own texts).
        """
        with self._lock:  # one figure: renders from two threads mixed frames
            self.frame(k)
            canvas = self.figure.canvas
            try:
                canvas.draw()
            except RuntimeError as error:
                if "FT_Set_Char_Size" not in str(error):
                    raise
                raise InputError(
                    f"dpi {self.dpi:g} is too small for a text of the frames (FreeType cannot "
                    "set a font below 1 pixel; nested sub- or superscripts of the title are "
                    "smallest): give a larger dpi or a simpler title"
                ) from None
            return np.asarray(canvas.buffer_rgba())[..., :3].copy()

    def save(self, path, *, fmt=None):
        """Write the animation to ``path`` atomically and deterministically.

        Parameters
        ----------
        path : path
            ``.gif`` (Pillow, always available) or ``.mp4`` (needs
            imageio-ffmpeg, the optional extra ``animation``).
        fmt : {"gif", "mp4"}, optional
            Default: from the suffix.

        Returns
        -------
        Path

        Raises
        ------
        InputError
            Unknown format, unwritable path or one with a control character,
            MP4 without an ffmpeg writer, or a GIF at an ``fps`` it cannot
            play (:func:`check_fps`).
        """
        with self._lock:  # one figure: renders from two threads mixed frames
            path, fmt = check_output(path, "path", fmt)
            check_fps(self.fps, fmt)
            with atomic_path(path) as temporary:
                if fmt == "gif":
                    self._write_gif(temporary)
                else:
                    self._write_mp4(temporary, path)
            return path

    def _write_gif(self, target):
        from PIL import Image

        frames = [Image.fromarray(self.render(k)) for k in range(len(self.times))]
        # one fixed palette for all frames, from a montage of frames spread over
        # the animation (the traced curves are absent from frame 0); no dithering
        picks = sorted({int(round(j)) for j in np.linspace(0, len(frames) - 1, 6)})
        montage = Image.new("RGB", (frames[0].width, frames[0].height * len(picks)))
        for slot, k in enumerate(picks):
            montage.paste(frames[k], (0, slot * frames[0].height))
        palette = montage.quantize(
            colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
        )
        indexed = [f.quantize(palette=palette, dither=Image.Dither.NONE) for f in frames]
        buffer = io.BytesIO()
        indexed[0].save(
            buffer,
            format="GIF",
            save_all=True,
            append_images=indexed[1:],
            # whole hundredths of a second: self.fps is one of GIF_FPS
            duration=1000 // self.fps,
            loop=0,
            optimize=False,
        )
        Path(target).write_bytes(buffer.getvalue())

    def _write_mp4(self, target, path):
        """Frames piped to imageio-ffmpeg's ffmpeg as raw RGB, H.264 in MP4.

        ffmpeg runs as our own child so that its exit status is read: a
        full disk or a file-size limit ended its run while the MP4 was
        still called written, exit 0, and the broken file replaced the
        old one.  Its messages are kept and the last one is said in the
        error, naming ``path`` (not the temporary ``target``).
        """
        import errno
        import signal
        import subprocess

        import imageio_ffmpeg

        first = self.render(0)
        height, width = first.shape[:2]
        # libx264 needs even sizes; pad by repeating the last row/column
        pad_h, pad_w = height % 2, width % 2
        try:
            executable = imageio_ffmpeg.get_ffmpeg_exe()
        except RuntimeError as error:  # none found (also: no descriptor left to look)
            raise InputError(
                f"cannot write {path}: no usable ffmpeg ({' '.join(str(error).split())})"
            ) from None
        command = [
            executable,
            "-y",
            "-loglevel",
            "error",
            "-f",
            "rawvideo",
            "-vcodec",
            "rawvideo",
            "-s",
            f"{width + pad_w}x{height + pad_h}",
            "-pix_fmt",
            "rgb24",
            "-r",
            f"{self.fps:.02f}",
            "-i",
            "-",
            "-an",
            "-vcodec",
            "libx264",
            "-pix_fmt",
            "yuv420p",
            "-crf",
            "20",
            "-threads",
            "1",
            "-fflags",
            "+bitexact",
            "-flags:v",
            "+bitexact",
            "-map_metadata",
            "-1",
            "-f",
            "mp4",
            str(target),
        ]
        process = subprocess.Popen(
            command, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
        )
        # its messages drained beside the frames (a pipe, not a temporary
        # file: on a full disk that could not hold them either)
        said = []
        reader = threading.Thread(target=lambda: said.append(process.stderr.read()), daemon=True)
        reader.start()
        try:
            try:
                for k in range(len(self.times)):
                    image = first if k == 0 else self.render(k)
                    if pad_h or pad_w:
                        image = np.pad(image, ((0, pad_h), (0, pad_w), (0, 0)), mode="edge")
                    process.stdin.write(np.ascontiguousarray(image).tobytes())
                process.stdin.close()
            except BrokenPipeError:
                pass  # ffmpeg ended early: its status says why
            code = process.wait()
        except BaseException:
            process.kill()
            process.wait()
            raise
        finally:
            reader.join()
            process.stderr.close()
        if code == 0:
            return
        text = b"".join(said).decode("utf-8", "replace")
        lines = [" ".join(line.split()) for line in text.split("\n") if line.strip()]
        text = " ".join(lines)
        # ffmpeg exits with 256 - errno where a write failed (its AVERROR)
        failed = 256 - code if 0 < code < 256 else None
        if (
            code == -getattr(signal, "SIGXFSZ", 0)
            or failed == errno.EFBIG
            or "File too large" in text
        ):
            raise OSError(errno.EFBIG, os.strerror(errno.EFBIG))
        if failed == errno.ENOSPC or "No space left on device" in text:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        if failed == errno.EDQUOT or "Disk quota exceeded" in text:
            raise OSError(errno.EDQUOT, os.strerror(errno.EDQUOT))
        reason = lines[-1] if lines else f"exit status {code}"
        raise InputError(f"cannot write {path}: ffmpeg failed ({reason})")


def _warn_aliasing(turns, times):
    """An :class:`AliasingWarning` where the body turns past :data:`ALIASING_TURN` a frame."""
    largest = float(turns.max())
    if not largest > ALIASING_TURN:
        return
    # evenly spaced frames turn at most `largest` each: scale their number
    # (5 % more: the fastest interval moves as the frames do)
    enough = 1 + math.ceil(1.05 * len(turns) * largest / SMOOTH_TURN)
    warnings.warn(
        f"the body turns up to {math.degrees(largest):.0f} degrees between frames, more "
        "than a quarter turn: the solid can seem to turn slowly or backwards (aliasing); "
        f"about {enough} frames over these {times[-1] - times[0]:.4g} s keep each turn "
        "under 45 degrees (more frames, or a higher fps in real time)",
        AliasingWarning,
        stacklevel=caller_stacklevel(),
    )


def _cube(ax, half, zrange, zoom=1.45):
    ax.set_xlim(-half, half)
    ax.set_ylim(-half, half)
    ax.set_zlim(*zrange)
    ax.set_box_aspect((1, 1, (zrange[1] - zrange[0]) / (2 * half)), zoom=zoom)
    ax.set_axis_off()


def mp4_available():
    """True when an ffmpeg writer (imageio-ffmpeg) is installed."""
    import importlib.util

    return importlib.util.find_spec("imageio_ffmpeg") is not None


# ----------------------------------------------------------------- the entry point
def poinsot_animation(
    source,
    theta=None,
    *,
    dtheta=None,
    phi=0.0,
    speed=1.0,
    periods=None,
    frames=None,
    fps=DEFAULT_FPS,
    out=None,
    solid="auto",
    title=None,
    dpi=DEFAULT_DPI,
    pyplot=False,
    body=None,
    seconds=None,
):
    """The Poinsot animation of a body's torque-free motion.

    Parameters
    ----------
    source : Body, array_like (3,), Motion, or a catalog row
        A body (with ``theta``/``dtheta``/``phi``/``speed`` for the spin,
        as :meth:`Motion.from_spin`), a ready :class:`~orbits.Motion`, or a
        catalog row (pandas Series / itertuples row with ``I1``, ``I2``,
        ``I3``, ``dtheta``, ``q`` and ``closes_after`` or ``n``; e.g. from
        :func:`orbit_row`).  A row is animated over its unit-norm moments,
        ``|omega0| = 1``, as in the catalog.
    theta, dtheta, phi, speed : float
        The initial spin when ``source`` is a body.
    periods : float, optional
        Duration in periods T.  Default: ``q`` for a catalog row (the body
        is back at its start, so the last frame equals the first), else 1.
    frames : int, optional
        Number of frames (>= 2), evenly spaced in time, both ends included
        (default 120; not with ``seconds``).
    fps : int
        Frames per second of the written file, 1 to 100 (default 20); a
        GIF plays only 1, 2, 4, 5, 10, 20, 25 or 50 at their speed (its
        frame delays are whole hundredths of a second, and 1 plays as 10):
        other rates are refused for a ``.gif``.
    seconds : float, optional
        Real time: the animation lasts ``seconds`` of the motion's time
        (seconds when omega is in rad/s) and plays at that speed,
        ``round(seconds * fps) + 1`` frames; not with ``periods`` or
        ``frames``.
    out : path, optional
        Write the animation there (``.gif``, or ``.mp4`` with an ffmpeg
        writer); atomic and deterministic (the same call gives the same
        bytes).  Checked before anything is drawn (:func:`check_output`).
    solid : "auto", "ellipsoid" or tuple
        The solid drawn; see :func:`solid_faces`.
    title : str, optional
        The heading above the two panels.  Default (None): the body, branch
        and period, or a catalog row's orbit and closure; ``""``: none.
    dpi : float
        Pixel density of the frames (figure 9 x 4 in; the default 120 gives
        1080 x 480 px): from 7 to 7281 (:func:`check_dpi`: FreeType
        cannot set the smallest text, a subscript of the captions, below 7
        at matplotlib's default font size; Agg draws at most 65535 pixels
        a side), and one frame's buffers must fit half the machine's
        memory.
    pyplot : bool
        Create the figure through ``matplotlib.pyplot`` (for notebooks and
        sphinx-gallery's animation scraper); default headless Agg.
    body : Body, optional
        With a catalog row: the row's body as built (e.g. :meth:`Body.box`),
        so that its solid and its units are drawn; its normalised moments
        must be the row's ``I1, I2, I3``.

    Returns
    -------
    PoinsotAnimation
        ``.figure``, ``.times``, ``.frame(k)`` (the drawn data of frame k),
        ``.animation`` (FuncAnimation), ``.save(path)``.

    Raises
    ------
    InputError
        Bad ``frames``, ``fps``, ``periods``, ``seconds`` (fewer than 2 or
        more than 2000 frames), ``dpi``, ``solid`` or output path (a
        control character in its name); frames whose memory or drawing
        time would exceed the machine (:func:`orbits.limits.check_animation`;
        a GIF holds every frame).  A catalog row whose spin's total phase
        is not ``2 pi n/q`` (an edited or hand-made row), or whose
        ``branch`` or ``closes_after`` contradicts it.
    AngleError, SeparatrixError
        Bad spin, as :meth:`Motion.from_spin`.

    Warns
    -----
    AliasingWarning
        The body turns more than a quarter turn between two frames (a
        catalog row of large ``n`` over the default 120 frames: about 105
        degrees at n = 30); the message says how many frames keep each turn
        under 45 degrees.

    Examples
    --------
    >>> from orbits import Body
    >>> from orbits.animate import orbit_row, poinsot_animation, flip_motion
    >>> body = Body.preset("fig6")
    >>> anim = poinsot_animation(orbit_row(body, n=5, branch="SAM"), out="n5.gif")
    >>> flip = poinsot_animation(flip_motion(), out="flip.gif")   # Dzhanibekov
    """
    fmt = None
    if out is not None:
        path, fmt = check_output(out)
    fps = check_fps(fps, fmt)
    motion, default_periods, label = animation_motion(
        source, theta, dtheta=dtheta, phi=phi, speed=speed, body=body
    )
    if seconds is not None:
        if periods is not None or frames is not None:
            raise InputError("give seconds (real time) or periods and frames, not both")
        frames = check_real_time(seconds, fps)
        # as check_real_time reads it ([3.0] and a 1-element array too)
        periods = real_scalar("seconds", seconds) / motion.period
    frames = 120 if frames is None else integer("frames", frames, minimum=2)
    periods = default_periods if periods is None else real_scalar("periods", periods)
    if not (np.isfinite(periods) and periods > 0):
        raise InputError(f"periods must be positive, got {periods!r}")
    duration = periods * motion.period
    if not np.isfinite(duration):
        raise InputError(f"periods {periods:g} of T = {motion.period:g} s overflow a double")
    check_span(motion, duration)
    # before any array of frames exists: the text draws, the frames fit memory and a day
    check_dpi(dpi)
    check_animation(frames, dpi, keep_frames=fmt == "gif")
    times = np.linspace(0.0, duration, frames)
    animation = PoinsotAnimation(
        motion,
        times,
        fps=fps,
        solid=solid,
        title=label if title is None else title,
        dpi=dpi,
        pyplot=pyplot,
    )
    if out is not None:
        animation.save(path, fmt=fmt)
    return animation


# the most frames of a real-time animation (100 s at 20 frames/s)
MAX_FRAMES = 2000


def animation_motion(source, theta=None, *, dtheta=None, phi=0.0, speed=1.0, body=None):
    """What :func:`poinsot_animation` draws: ``(motion, default periods, title)``.

    ``source`` is a body (with ``theta`` or ``dtheta``, ``phi``, ``speed``),
    a :class:`~orbits.Motion` (1 period by default) or a catalog row (its
    spin at ``|omega0| = 1``, drawn over its ``q`` periods by default, with
    a title; ``body``, when given, must be the row's).
    """
    row_body = body
    row = None if isinstance(source, Motion) else _as_row(source)
    if isinstance(source, Motion) or row is not None:
        # the spin is the Motion's or the row's: a spin given too would be ignored
        given = given_besides(
            theta=(theta, None), dtheta=(dtheta, None), phi=(phi, 0.0), speed=(speed, 1.0)
        )
        if given:
            what = "a Motion" if row is None else "a catalog row"
            raise InputError(
                f"{', '.join(given)} given with {what}, which has its own spin; "
                "give the spin with a body instead"
            )
    if isinstance(source, Motion):
        if body is not None and body is not source.body:
            # the Motion's own body is drawn (its solid, its units): another
            # one, even of the same moments, would be ignored
            raise InputError(
                "body given with a Motion, whose own body is drawn; build the Motion "
                "from that body (Motion.from_spin(body, ...)) and leave body out"
            )
        return source, 1.0, None
    if row is not None:
        moments = finite_array("the row's I1, I2, I3", [row["I1"], row["I2"], row["I3"]])
        if row_body is None:
            body = Body(moments, name=_row_name(row))
        else:
            body = as_body(row_body)
            if not _same_moments(body, moments):
                raise InputError(
                    "the catalog row is not of the given body: its moments "
                    f"{moments.tolist()} differ from the body's normalised "
                    f"{body.normalized_moments.tolist()}"
                )
        motion = Motion.from_spin(body, dtheta=row["dtheta"])
        p, q = _row_level(row, motion, rounded=row_body is None)
        multiple = f"{p}" if q == 1 else f"{p}/{q}"
        name = literal_text(_row_name(row) or "body")
        label = (
            rf"{name}: closed orbit $\Delta\alpha = 2\pi\cdot{multiple}$, "
            rf"{motion.branch}, $\theta-\theta_c$ = {float(row['dtheta']):.3e}"
            + "\n"
            + _closure_text(row, p, q)
        )
        return motion, float(q), label
    body = as_body(source)
    if row_body is not None and row_body is not source:
        # the source is the body drawn: another one would be ignored
        raise InputError(
            "body given with a body as the source, which is the one drawn; give one of the two"
        )
    if theta is None and dtheta is None:
        raise InputError("give the spin: theta or dtheta (or pass a Motion or a catalog row)")
    return Motion.from_spin(body, theta, dtheta=dtheta, phi=phi, speed=speed), 1.0, None


def _same_moments(body, moments):
    """Whether ``body``'s normalised moments are ``moments`` (``I/|I|``, as a
    catalog's I1, I2, I3 hold them) to 1e-12; rows of shape (k, 3) give k answers."""
    moments = np.asarray(moments, dtype=float)
    close = np.isclose(moments, as_body(body).normalized_moments, rtol=1e-12, atol=0.0)
    return close.all(axis=-1)


def _row_name(row):
    """A row's body name as text, or None: pandas reads the names 7, 1e5 and
    NA of a catalog (``read_csv(comment="#")``) as an int, a float and NaN."""
    name = row.get("body")
    return None if _missing(name) else str(name)


def _row_level(row, motion, rounded=False):
    """``(p, q)`` of a catalog row, in lowest terms, checked against its motion.

    A row is drawn under the title "closed orbit": its ``n`` and ``q`` must
    be whole, its ``branch`` (when given) the motion's, and the motion's own
    total phase must be ``2 pi n/q`` to the search's
    :data:`~orbits.search.RESIDUAL_TOLERANCE` (ten times it, for the
    re-evaluation): an edited or hand-made row that does not close is
    refused, not titled closed.  ``rounded``: the motion's moments are the
    row's ``I/|I|`` rounded to doubles (no ``body`` given), on which a nearly
    symmetric body's or a thin rod's phase moves beyond that tolerance; the
    phase's change under that rounding (4 ulps of each moment) is allowed too.
    """
    from .search import RESIDUAL_TOLERANCE, TWO_PI

    n, q = integer("the row's n", row["n"]), integer("the row's q", row["q"])
    branch = row.get("branch")
    if branch is not None and not _missing(branch) and branch != motion.branch:
        raise InputError(
            f"the row's branch {branch!r} is not its spin's: dtheta = "
            f"{float(row['dtheta'])!r} is on {motion.branch}"
        )
    level = TWO_PI * n / q
    phase = motion.total_phase()
    allowed = 10.0 * RESIDUAL_TOLERANCE * level
    if rounded and not abs(phase - level) <= allowed:
        allowed += _rounding_slack(motion, float(row["dtheta"]), phase)
    if not abs(phase - level) <= allowed:
        raise InputError(
            f"the row does not close: its spin's total phase is {phase!r} rad, "
            f"not 2 pi n/q = {level!r} (n = {n}, q = {q}); an edited row? "
            "Take rows from orbits.catalog, orbit_row or a catalog file"
        )
    common = math.gcd(n, q)
    return n // common, q // common


def _rounding_slack(motion, dtheta, phase):
    """How far the total phase at ``dtheta`` moves when the motion's moments
    move by 4 ulps each (the rounding of a catalog's ``I/|I|`` columns)."""
    from .phases import total_phase

    moments = np.asarray(motion.body.normalized_moments, dtype=float)
    slack = 0.0
    for k in range(3):
        for sign in (-1.0, 1.0):
            moved = moments.copy()
            moved[k] += sign * 4.0 * np.spacing(moved[k])
            try:
                slack = max(slack, abs(float(total_phase(moved, dtheta=dtheta)) - phase))
            except OrbitsError:  # moved off the body's region or the spin's range
                return math.inf
    return 3.0 * slack


def _missing(value):
    """Whether a row's cell is empty (None, or NaN as pandas reads one)."""
    return value is None or (isinstance(value, float) and math.isnan(value))


def _closure_text(row, p, q):
    """When the herpolhode and the body come back (search.closes_after of p/q).

    A row's own ``closes_after`` must agree (it is derived from p and q).
    """
    from .search import closes_after

    closes = closes_after(p, q)
    given = row.get("closes_after")
    if not _missing(given) and str(given) != closes:
        raise InputError(f"the row's closes_after {given!r} is not that of 2 pi {p}/{q}: {closes}")
    body_back = f"the body back at its start after {q} T"
    if closes == str(q):
        return f"herpolhode closed and {body_back}"
    return f"herpolhode closed after {closes} T, {body_back}"


def _as_row(source):
    keys = ("I1", "I2", "I3", "dtheta", "n", "q")
    if hasattr(source, "_asdict"):  # DataFrame.itertuples()
        source = source._asdict()
    if hasattr(source, "keys") and all(k in source.keys() for k in keys):
        return {k: source[k] for k in source.keys()}
    return None


__all__ = [
    "GIF_FPS",
    "FrameData",
    "PoinsotAnimation",
    "animation_motion",
    "check_dpi",
    "check_fps",
    "check_output",
    "check_real_time",
    "check_span",
    "flip_motion",
    "inertia_ellipsoid_lines",
    "min_dpi",
    "mp4_available",
    "orbit_row",
    "poinsot_animation",
    "solid_faces",
    "t_handle_boxes",
]
