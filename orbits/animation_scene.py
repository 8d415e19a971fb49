"""The geometry of a Poinsot animation, frame by frame: no drawing, no matplotlib.

What :class:`orbits.animate.PoinsotAnimation` draws, computed here (the
units and the construction are those of :mod:`orbits.animate`'s
docstring): the solid's faces in the principal frame (:func:`solid_faces`:
T-handle, box, cylinder, mesh or the equivalent ellipsoid), the inertia
ellipsoid's wire frame (:func:`inertia_ellipsoid_lines`), and per frame
(:class:`PoinsotScene`) the orientation, the contact point of ellipsoid and
invariable plane, and the herpolhode and polhode traced so far
(:class:`FrameData`).  :mod:`orbits.animate` turns these into matplotlib
artists and files.
"""

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ._args import finite_array, integer, real_array
from .bodies import Body, cylinder_moments
from .errors import ArgumentTypeError, InputError
from .limits import format_bytes, memory_budget
from .motion import Motion, as_body
from .plotting import box_faces


# ----------------------------------------------------------------- solids
def solid_faces(body, solid="auto"):
    """The faces of the solid to draw, in the principal frame, about the centre of mass.

    Parameters
    ----------
    body : Body
    solid : "auto", "ellipsoid", or a tuple
        ``("t-handle", l1, l2, w)``, ``("box", a, b, c)`` (full side
        lengths along the caller's x, y, z), ``("cylinder", a, length, b)``
        (along z, section semi-axes a along x and b along y) or ``("mesh",
        vertices, faces)`` (caller's axes, centred at the centre of mass),
        or the same as a mapping with every part named (``{"kind": "box",
        "a": 0.15, "b": 0.07, "c": 0.008}``; keys in :data:`SOLID_PARTS`).  ``"auto"``
        uses ``body.shape`` when the body carries one (same tuples: set by
        :meth:`Body.t_handle`, :meth:`Body.box`, :meth:`Body.cylinder` and
        :meth:`Body.from_mesh`), the
        T-handle when the moments are those of :meth:`Body.t_handle` (8, 4,
        1) (the ``t-handle`` preset), and else the equivalent ellipsoid
        (:meth:`Body.equivalent_ellipsoid`).

    Returns
    -------
    kind : str
    faces : list of ndarray, each (k, 3)
        Polygons in the sorted principal frame (length units of the body).

    Raises
    ------
    InputError
        An unknown solid; lengths that are not three positive finite
        numbers; a mesh whose vertices are not finite (k, 3) or whose faces
        are not lists of at least 3 vertex indices.
    """
    body = as_body(body)
    spec = solid
    if isinstance(spec, str) and spec == "auto":
        spec = getattr(body, "shape", None)
        if spec is None and np.array_equal(body.moments, Body.t_handle(8.0, 4.0, 1.0).moments):
            spec = ("t-handle", 8.0, 4.0, 1.0)
        if spec is None:
            spec = "ellipsoid"
    if isinstance(spec, Mapping):
        spec = _from_mapping(spec)
    if isinstance(spec, str):
        spec = (spec,)
    kind = spec[0] if isinstance(spec, (tuple, list)) and spec else None
    if kind == "ellipsoid":
        semi = np.array(body.equivalent_ellipsoid())
        # semi-axes (a, b, c) lie along the principal axes I1, I2, I3
        return "ellipsoid", _ellipsoid_faces(np.maximum(semi, 1e-3 * semi.max()))
    if kind == "t-handle":
        l1, l2, w = _lengths(spec, ("l1", "l2", "w"))
        faces = _t_handle_faces(l1, l2, w)
        frame = Body.t_handle(l1, l2, w).frame
    elif kind == "box":
        a, b, c = _lengths(spec, ("a", "b", "c"))
        faces = box_faces((-a / 2, -b / 2, -c / 2), (a / 2, b / 2, c / 2))
        frame = Body((b * b + c * c, a * a + c * c, a * a + b * b)).frame
    elif kind == "cylinder":
        a, length, b = _lengths(spec, ("a", "length", "b"))
        faces = _cylinder_faces(a, b, length)
        frame = Body(cylinder_moments(a, length, radius_y=b)).frame
    elif kind == "mesh":
        faces = _mesh_faces(spec)
        frame = body.frame
    else:
        raise InputError(
            f"unknown solid {solid!r}; use 'auto', 'ellipsoid', "
            "('t-handle', l1, l2, w), ('box', a, b, c), "
            "('cylinder', a, length, b) or ('mesh', vertices, faces)"
        )
    # caller's axes -> sorted principal axes: v_principal = frame @ v
    return kind, [face @ frame.T for face in faces]


# the named parts of each solid, in the order of its tuple
SOLID_PARTS = {
    "ellipsoid": (),
    "t-handle": ("l1", "l2", "w"),
    "box": ("a", "b", "c"),
    "cylinder": ("a", "length", "b"),
    "mesh": ("vertices", "faces"),
}


def _from_mapping(spec):
    """The tuple of a solid given as a mapping, ``{"kind": "box", "a": .., "b": .., "c": ..}``.

    Every part is named: a missing or unknown key is refused (values taken
    in the mapping's order would put a box's ``c`` where its ``a`` goes).
    """
    kind = spec.get("kind")
    parts = SOLID_PARTS.get(kind) if isinstance(kind, str) else None
    if parts is None:
        raise InputError(
            f"unknown solid {spec!r}: a mapping needs 'kind', one of {', '.join(SOLID_PARTS)}"
        )
    given, wanted = set(spec) - {"kind"}, set(parts)
    if given != wanted:
        missing = ", ".join(sorted(map(str, wanted - given))) or "none"
        unknown = ", ".join(sorted(map(str, given - wanted))) or "none"
        raise InputError(
            f"solid {kind!r} given as a mapping takes the keys "
            f"{', '.join(('kind', *parts))} (missing: {missing}; unknown: {unknown})"
        )
    return (kind, *(spec[name] for name in parts))


def _lengths(spec, names):
    """The three positive finite lengths of a ``(kind, x, y, z)`` solid."""
    kind = spec[0]
    usage = f"({kind!r}, {', '.join(names)})"
    if len(spec) != 4:
        raise InputError(f"solid {usage} takes three lengths, got {len(spec) - 1}: {spec!r}")
    lengths = finite_array(f"solid {usage}", list(spec[1:]))
    if not np.all(lengths > 0.0):
        raise InputError(f"solid {usage} needs positive lengths, got {spec!r}")
    return (float(v) for v in lengths)


def _mesh_faces(spec):
    """The polygons of a ``("mesh", vertices, faces)`` solid, checked."""
    usage = "solid ('mesh', vertices, faces)"
    if len(spec) != 3:
        raise InputError(f"{usage} takes vertices and faces, got {len(spec) - 1} of them")
    vertices = finite_array(f"{usage}: vertices", spec[1])
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) < 3:
        raise InputError(
            f"{usage}: vertices must be an array (k, 3) of k >= 3 points, "
            f"got shape {vertices.shape}"
        )
    try:
        face_list = list(spec[2])
    except TypeError:
        raise ArgumentTypeError(f"{usage}: faces must be a list of index lists") from None
    faces = []
    for number, face in enumerate(face_list):
        index = real_array(f"{usage}: face {number}", face)
        if (
            index.ndim != 1
            or len(index) < 3
            or not np.all(index == np.floor(index))
            or not np.all((index >= 0) & (index < len(vertices)))
        ):
            raise InputError(
                f"{usage}: face {number} must list at least 3 vertex indices "
                f"0..{len(vertices) - 1}, got {face!r}"
            )
        faces.append(vertices[index.astype(int)])
    if not faces:
        raise InputError(f"{usage}: no faces")
    return faces


def frame_times(times):
    """The frame times as a float array: finite, at least 2, increasing.

    Raises
    ------
    InputError
        Anything else (the message names ``times``).
    """
    times = finite_array("times", times)
    if times.ndim != 1 or len(times) < 2:
        raise InputError(
            f"times must be a 1-D array of at least 2 frame times, got shape {times.shape}"
        )
    if not np.all(np.diff(times) > 0.0):
        k = int(np.argmin(np.diff(times) > 0.0))
        raise InputError(
            f"times must increase from frame to frame, got times[{k}] = {times[k]:g} "
            f"then times[{k + 1}] = {times[k + 1]:g}"
        )
    return times.copy()  # not the caller's array


def t_handle_boxes(l1, l2, w):
    """The T-handle's two bars as (lo, hi) corners about its centre of mass.

    Cross piece along x, shaft along y from the cross piece's edge, square
    section w (the geometry of eqn:IsforT).
    """
    com_y = (l2 / (l1 + l2)) * 0.5 * (w + l2)
    return [
        ((-l1 / 2, -w / 2 - com_y, -w / 2), (l1 / 2, w / 2 - com_y, w / 2)),
        ((-w / 2, w / 2 - com_y, -w / 2), (w / 2, w / 2 + l2 - com_y, w / 2)),
    ]


def _same_vertex_count(faces):
    """Faces padded to one vertex count by repeating each face's last vertex.

    matplotlib 3.11 stores polygons of different lengths in an ``np.empty``
    array and projects and autoscales its unused padding too
    (matplotlib/matplotlib#32272): a cylinder (24-gon caps, quadrilateral
    walls) got axis limits of 1.8e308 in one CI run.  A repeated vertex adds
    a zero-length edge: the drawing is the same.
    """
    count = max(len(face) for face in faces)
    return [
        face
        if len(face) == count
        else np.concatenate([face, np.repeat(face[-1:], count - len(face), axis=0)])
        for face in faces
    ]


def _cylinder_faces(a, b, length, sides=24):
    """An elliptic cylinder along z (semi-axes a along x, b along y) as a prism."""
    u = np.linspace(0.0, 2.0 * np.pi, sides + 1)[:-1]
    rim = np.stack([a * np.cos(u), b * np.sin(u)], axis=-1)
    bottom = np.column_stack([rim, np.full(sides, -0.5 * length)])
    top = np.column_stack([rim, np.full(sides, 0.5 * length)])
    walls = [np.array([bottom[i], bottom[i - 1], top[i - 1], top[i]]) for i in range(sides)]
    return [bottom, top] + walls


def _t_handle_faces(l1, l2, w):
    faces = []
    for lo, hi in t_handle_boxes(l1, l2, w):
        faces += box_faces(lo, hi)
    return faces


def _ellipsoid_faces(semi, longitudes=16, latitudes=8):
    u = np.linspace(0.0, 2.0 * np.pi, longitudes + 1)
    v = np.linspace(0.0, np.pi, latitudes + 1)
    points = np.stack(
        [
            np.outer(np.cos(u), np.sin(v)) * semi[0],
            np.outer(np.sin(u), np.sin(v)) * semi[1],
            np.outer(np.ones_like(u), np.cos(v)) * semi[2],
        ],
        axis=-1,
    )
    return [
        np.array([points[i, j], points[i + 1, j], points[i + 1, j + 1], points[i, j + 1]])
        for i in range(longitudes)
        for j in range(latitudes)
    ]


def inertia_ellipsoid_lines(moments, meridians=8, parallels=5, samples=49):
    """Wire-frame curves of the inertia ellipsoid ``x.I.x = 1`` (body frame).

    Returns a list of (samples, 3) arrays: meridians through the I3 poles
    and parallels of constant x3 (every point satisfies ``x.I.x = 1``).
    """
    semi = 1.0 / np.sqrt(np.asarray(moments, dtype=float))
    s = np.linspace(0.0, 2.0 * np.pi, samples)
    curves = []
    for k in range(meridians):
        azimuth = np.pi * k / meridians
        curves.append(
            np.stack(
                [
                    semi[0] * np.cos(azimuth) * np.sin(s),
                    semi[1] * np.sin(azimuth) * np.sin(s),
                    semi[2] * np.cos(s),
                ],
                axis=-1,
            )
        )
    for k in range(1, parallels + 1):
        polar = np.pi * k / (parallels + 1)
        curves.append(
            np.stack(
                [
                    semi[0] * np.sin(polar) * np.cos(s),
                    semi[1] * np.sin(polar) * np.sin(s),
                    np.full(samples, semi[2] * np.cos(polar)),
                ],
                axis=-1,
            )
        )
    return curves


# ----------------------------------------------------------------- per frame
@dataclass
class FrameData:
    """What frame ``k`` draws, in the units of the module docstring.

    Attributes
    ----------
    t : float
        Time of the frame.
    rotation : ndarray (3, 3)
        The orientation drawn (body -> space): its columns are the drawn
        body axes.
    contact : ndarray (3,)
        The contact point of ellipsoid and plane, space frame.
    contact_body : ndarray (3,)
        The same point in the body frame (end of the polhode drawn).
    herpolhode : ndarray (k, 3)
        The herpolhode traced up to ``t`` (space frame; ends at ``contact``).
    polhode : ndarray (k, 3)
        The polhode traced up to ``t`` (body frame).
    plane_height : float
        ``sqrt(2E)/M``: the plane is ``z = plane_height``.
    """

    t: float
    rotation: np.ndarray
    contact: np.ndarray
    contact_body: np.ndarray
    herpolhode: np.ndarray
    polhode: np.ndarray
    plane_height: float


# the traced polhode and herpolhode: at least this many steps per period T
# (a smooth curve at any frame count) and per turn of the herpolhode about
# the L axis (|Delta alpha| / 2 pi turns a period: near the separatrix the
# point creeps by the I2 axis for most of T and turns over in a small
# fraction of it, ~1/turns; 128 steps a turn keep a chord within
# 1 - cos(pi/128) = 3e-4 of the curve's size), and at most this many
# points in all
TRACE_SAMPLES_PER_PERIOD = 256
TRACE_SAMPLES_PER_TURN = 128
TRACE_MAX_SAMPLES = 1_000_000
# memory of one traced point: its time, the motion's state (omega, Euler
# angles, rotation, omega in space) and the two rho curves, with the
# temporaries of Motion.state, about twice the 200 bytes kept
TRACE_BYTES_PER_POINT = 400


def _trace_steps(asked, times, period, turns=0.0):
    """Steps per frame interval: ``asked``, or more for TRACE_SAMPLES_PER_PERIOD
    steps per period and TRACE_SAMPLES_PER_TURN per turn (``turns`` a
    period) over the longest interval, within TRACE_MAX_SAMPLES points in all."""
    intervals = len(times) - 1
    longest = float(np.max(np.diff(times))) if intervals > 0 else 0.0
    if not (intervals > 0 and longest > 0.0 and math.isfinite(period) and period > 0.0):
        return asked
    per_period = max(TRACE_SAMPLES_PER_PERIOD, TRACE_SAMPLES_PER_TURN * turns)
    needed = math.ceil(per_period * longest / period)
    cap = max(1, TRACE_MAX_SAMPLES // intervals)
    return max(asked, min(needed, cap))


class PoinsotScene:
    """The geometry of every frame of a Poinsot animation (nothing drawn).

    Parameters
    ----------
    motion : Motion
    times : array_like (frames,)
        Frame times (at least 2), finite and increasing from frame to frame.
    solid : "auto", "ellipsoid" or tuple
        The solid; see :func:`solid_faces`.
    subsamples : int
        Steps of the traced curves per frame interval (>= 1); more where
        that is needed for :data:`TRACE_SAMPLES_PER_PERIOD` steps per period
        T of the motion and :data:`TRACE_SAMPLES_PER_TURN` per turn of the
        herpolhode, in the longest interval (a few frames, or an orbit
        near the separatrix, would otherwise trace the polhode as chords
        through the ellipsoid and the herpolhode as a polygon), up to
        :data:`TRACE_MAX_SAMPLES` in all.

    Raises
    ------
    InputError
        Bad ``times`` (:func:`frame_times`), ``subsamples`` or ``solid``;
        a ``motion`` that is not a :class:`~orbits.Motion`.

    Attributes
    ----------
    motion : Motion
    times : ndarray (frames,)
    plane_height : float
        ``sqrt(2E)/M``: the invariable plane is ``z = plane_height``.
    semi_axes : ndarray (3,)
        ``1/sqrt(I_k)``: the inertia ellipsoid's semi-axes (body frame).
    dense_times : ndarray
        The traced curves' times: :attr:`subsamples` steps per frame interval,
        holding the frame times exactly at multiples of it.
    subsamples : int
        The steps per frame interval used (at least the one asked for).
    rho_space, rho_body : ndarray (len(dense_times), 3)
        ``omega / sqrt(2E)`` at ``dense_times``: the herpolhode (space
        frame) and the polhode (body frame).
    rotations : ndarray (frames, 3, 3)
        Body -> space at each frame.
    frame_turns : ndarray (frames - 1,)
        The angle (radians) the body turns through between consecutive
        frames, the integral of ``|omega|`` over each interval (trapezoid
        rule on :attr:`dense_times`).
    frame_rho_space, frame_rho_body : ndarray (frames, 3)
        The contact point at each frame, space and body frame.
    wire : list of ndarray (samples, 3)
        The inertia ellipsoid's wire frame, body frame.
    solid_kind : str
    solid_scale : float
        Length units of the solid -> ellipsoid units (display only): the
        whole solid fits inside the inertia ellipsoid.
    faces : list of ndarray (k, 3)
        The solid's faces, scaled, body frame, padded to one vertex count.
    """

    def __init__(self, motion, times, *, solid="auto", subsamples=8):
        if not isinstance(motion, Motion):
            raise ArgumentTypeError(
                f"motion must be an orbits.Motion, got {type(motion).__name__}"
            )
        self.motion = motion
        self.times = frame_times(times)
        asked = integer("subsamples", subsamples)
        points = asked * (len(self.times) - 1)
        if points * TRACE_BYTES_PER_POINT > memory_budget():  # 10**9 asked for 67 GiB
            raise InputError(
                f"subsamples = {asked} steps for each of {len(self.times) - 1} frame "
                f"intervals: {points:.3g} traced points need about "
                f"{format_bytes(points * TRACE_BYTES_PER_POINT)}, beyond half of this "
                "machine's memory; give fewer subsamples or frames"
            )
        turns = abs(motion.total_phase()) / (2.0 * math.pi)  # of the herpolhode, a period
        subsamples = _trace_steps(asked, self.times, motion.period, turns)
        body = motion.body
        moments = body.moments
        two_e = 2.0 * motion.energy
        self.plane_height = math.sqrt(two_e) / motion.momentum
        self.semi_axes = 1.0 / np.sqrt(moments)
        # a dense grid for the traced curves: `subsamples` even steps in each
        # frame interval, so that frame k is point k * subsamples for any
        # frame times (one linspace over all put uneven ones between points)
        steps = np.arange(subsamples) / subsamples
        start, width = self.times[:-1, None], np.diff(self.times)[:, None]
        self.dense_times = np.append((start + width * steps).ravel(), self.times[-1])
        self.subsamples = subsamples
        state = motion.state(self.dense_times)
        self.rho_space = state.omega_space / math.sqrt(two_e)
        self.rho_body = state.omega / math.sqrt(two_e)
        speed = np.linalg.norm(state.omega, axis=1)
        steps = 0.5 * (speed[:-1] + speed[1:]) * np.diff(self.dense_times)
        self.frame_turns = steps.reshape(len(self.times) - 1, subsamples).sum(axis=1)
        frame_state = motion.state(self.times)
        self.rotations = frame_state.rotation
        self.frame_rho_space = frame_state.omega_space / math.sqrt(two_e)
        self.frame_rho_body = frame_state.omega / math.sqrt(two_e)
        self.wire = inertia_ellipsoid_lines(moments)
        self.solid_kind, faces = solid_faces(body, solid)
        # the whole solid (every vertex) fits inside the inertia ellipsoid
        vertices = np.concatenate(faces)
        reach = float(np.max(np.sqrt(np.sum((vertices / self.semi_axes) ** 2, axis=1))))
        self.solid_scale = 0.95 / reach
        self.faces = _same_vertex_count([face * self.solid_scale for face in faces])

    def extents(self):
        """``(half, reach)``: half-widths of the space and body panels' boxes.

        ``reach`` is 1.05 times the ellipsoid's longest semi-axis; ``half``
        also holds the herpolhode with a 15 % margin.
        """
        reach = 1.05 * float(self.semi_axes.max())
        radius = float(np.max(np.hypot(self.rho_space[:, 0], self.rho_space[:, 1])))
        return max(reach, 1.15 * radius), reach

    def frame(self, k):
        """The :class:`FrameData` of frame ``k``.

        Raises
        ------
        InputError
            ``k`` outside ``0 .. frames - 1``.
        """
        k = int(k)
        if not 0 <= k < len(self.times):
            raise InputError(f"frame {k} out of range 0..{len(self.times) - 1}")
        contact = self.frame_rho_space[k]
        contact_body = self.frame_rho_body[k]
        end = k * self.subsamples + 1
        # the dense grid holds the frame times exactly at multiples of subsamples;
        # the traced curves end at the frame's own contact point
        herpolhode = np.concatenate([self.rho_space[: end - 1], contact[None]])
        polhode = np.concatenate([self.rho_body[: end - 1], contact_body[None]])
        return FrameData(
            float(self.times[k]),
            self.rotations[k],
            contact,
            contact_body,
            herpolhode,
            polhode,
            self.plane_height,
        )

    def ellipsoid_lines(self, rotation):
        """The wire frame turned by ``rotation`` (body -> space)."""
        return [curve @ rotation.T for curve in self.wire]

    def solid_polygons(self, rotation):
        """The solid's faces turned by ``rotation`` (body -> space)."""
        return [face @ rotation.T for face in self.faces]

    def axis_tips(self, rotation):
        """The ends of the three drawn body axes (1.15 semi-axes), space frame."""
        return [1.15 * self.semi_axes[j] * rotation[:, j] for j in range(3)]


__all__ = [
    "FrameData",
    "PoinsotScene",
    "frame_times",
    "inertia_ellipsoid_lines",
    "solid_faces",
    "t_handle_boxes",
]
