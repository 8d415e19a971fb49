"""Rigid bodies: principal moments of inertia and their constructors.

A :class:`Body` holds its three principal moments sorted ascending,
``I1 < I2 < I3``, exactly as given (not normalised: the phases do not
depend on the scale, and normalising would round away the small
differences of nearly symmetric bodies).  The paper's normalisation
``|I| = 1`` is available as :attr:`Body.normalized_moments`.

Units: moments in any consistent unit (the paper writes J s^2 so that
energies come out in J for ``|omega| = 1 rad/s``); constructors from
lengths assume unit mass.
"""

import math
import re

import numpy as np

from ._args import (
    broadcast,
    finite_array,
    flat_broadcast,
    integer,
    real_array,
    real_scalar,
    utf8_text,
    warn,
)
from .cells import numbers_label
from .errors import (
    AngleError,
    ArgumentTypeError,
    InputError,
    NonPhysicalBodyError,
    SymmetricTopError,
)
from .limits import check_resolution, format_bytes, memory_budget
from .threads import size_aware

# Relative slack for I3 <= I1 + I2: a flat body built in floating point
# (e.g. I3 = fl(I1 + I2)) may exceed the bound by a few rounding errors.
# Within it the body is moved exactly onto the flat edge (see
# :func:`canonical_moments`); beyond it, it is rejected.
FLAT_SLACK = 8.0 * np.finfo(float).eps


def _two_sum(a, b):
    """``s = fl(a + b)`` and the exact error ``a + b - s`` (Knuth's TwoSum)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _sum_of_three(a, b, c):
    """``a + b + c`` from the exact ``a + b`` (TwoSum): accurate where ``c`` cancels it."""
    s, e = _two_sum(a, b)
    return (s + c) + e


def flat_excess(unit):
    """``I3 - I1 - I2`` of sorted moments, with its sign decided exactly.

    ``unit`` has shape (n, 3), sorted, largest entry below 1 (no overflow).
    ``s + e = I1 + I2`` exactly (TwoSum); ``I3 - s`` is exact by Sterbenz's
    lemma whenever ``s/2 <= I3 <= 2 s`` (always for a candidate body), so
    the one rounding left, in ``(I3 - s) - e``, keeps the sign: the result
    is 0 exactly on the flat edge, negative strictly inside.
    """
    s, e = _two_sum(unit[:, 0], unit[:, 1])
    return (unit[:, 2] - s) - e


def _exact_difference(a, b):
    """``a - b`` and whether it is exact."""
    d, e = _two_sum(a, -b)
    return d, e == 0.0


# the moment unit of bodies built from lengths and masses (Body.moment_unit)
SI_FROM_INPUTS = "kg m^2 (lengths in m, mass in kg)"


def canonical_moments(moments):
    """Validate sorted moments and bring them to the scale-free canonical form.

    Parameters
    ----------
    moments : ndarray, shape (..., 3)
        Sorted ascending along the last axis, any positive scale.

    Returns
    -------
    unit : ndarray, shape (..., 3)
        The moments times ``2**-exponent`` (an exact scaling), so that the
        largest lies in [1/2, 1); a body within the flat-edge slack is moved
        exactly onto the edge ``I3 = I1 + I2`` (one moment changed by at
        most ``8 eps I3``).
    exponent : ndarray of int, shape (...)
        ``moments ~= unit * 2**exponent``.

    Raises
    ------
    NonPhysicalBodyError
        A moment not finite or not positive; ``I3 > I1 + I2`` by more than
        ``8 eps I3``; or within that slack with no double-precision body on
        the flat edge that differs from it in one moment by the excess.
    SymmetricTopError
        Two equal moments (after any move onto the flat edge), or two that
        round to one value when scaled to ``|I| = 1``.

    Notes
    -----
    Every kernel receives ``unit``, so Delta alpha, theta_crit, the roots of
    the search and whole catalogs are bit-identical for moments scaled by a
    power of two, and free of overflow and underflow for any scale of
    doubles.  A subnormal moment (below 2.2e-308) is taken as the exact
    double it is, with its fewer significant bits (``1e-320`` typed in
    Python is already rounded to about 11 bits, and the body is that of the
    rounded double); the command line refuses such decimals as typed.

    The flat edge is decided exactly (:func:`flat_excess`): on it
    ``min Delta alpha = 2 pi``, reached only in the limit theta -> 0, so no
    body beyond rounding of the edge can report an n = 1 orbit.
    """
    shape = moments.shape[:-1]
    flat = np.array(moments, dtype=float).reshape(-1, 3)
    bad = ~np.all(np.isfinite(flat), axis=1)
    if bad.any():
        raise NonPhysicalBodyError(f"moments {_row(flat, bad)} are not all finite")
    bad = flat[:, 0] <= 0.0
    if bad.any():
        raise NonPhysicalBodyError(f"moments {_row(flat, bad)} must all be positive")
    _, exponent = np.frexp(flat[:, 2])
    exponent = exponent.astype(np.int64)
    with np.errstate(under="ignore"):
        unit = np.ldexp(flat, -exponent[:, None])
    excess = flat_excess(unit)
    bad = excess > FLAT_SLACK * unit[:, 2]
    if bad.any():
        raise NonPhysicalBodyError(
            f"moments {_row(flat, bad)} violate the triangle inequality "
            "I3 <= I1 + I2 that every rigid body satisfies (by more than the "
            "rounding slack 8 eps I3)"
        )
    near = np.flatnonzero(excess > 0.0)
    if near.size:
        unit[near] = _snap_flat(unit[near], flat[near], near, flat.shape[0])
    bad = (unit[:, 0] == unit[:, 1]) | (unit[:, 1] == unit[:, 2])
    if bad.any():
        raise SymmetricTopError(
            f"moments {_row(flat, bad)} describe a symmetric top (two equal "
            "moments): it has no separatrix and its elliptic modulus "
            "degenerates, so the total-phase formula needs I1 < I2 < I3"
        )
    # moments an ulp apart can round to one value in I / |I| (the catalog's columns)
    scaled = unit_norm(unit)
    bad = (scaled[:, 0] == scaled[:, 1]) | (scaled[:, 1] == scaled[:, 2])
    if bad.any():
        raise SymmetricTopError(
            f"moments {_row(flat, bad)} are a symmetric top within rounding: two "
            "of them become equal when scaled to |I| = 1 (the catalog's I1, I2, "
            "I3), so no catalog can tell them apart; give moments that differ by "
            "more than a few parts in 1e16"
        )
    return unit.reshape(shape + (3,)), exponent.reshape(shape)


def unit_norm(unit):
    """``unit / |unit|`` along the last axis, rounded as the catalog's ``I1,
    I2, I3`` columns are (:mod:`orbits.core.rows`: ``sqrt((I1^2 + I2^2) +
    I3^2)``); ``unit`` canonical (:func:`canonical_moments`), so nothing
    overflows or underflows."""
    unit = np.asarray(unit, dtype=float)
    i1, i2, i3 = unit[..., 0], unit[..., 1], unit[..., 2]
    return unit / np.sqrt((i1 * i1 + i2 * i2) + i3 * i3)[..., None]


def _snap_flat(unit, given, rows, total):
    """Move bodies just beyond the flat edge exactly onto it (rows of ``unit``).

    Tried in turn, each exact in doubles and keeping ``I1 < I2 < I3``:
    ``I3 <- I1 + I2``, ``I1 <- I3 - I2``, ``I2 <- I3 - I1``.  The moment
    changed moves by the excess ``I3 - I1 - I2 <= 8 eps I3``.  ``rows`` and
    ``total`` place these rows among all the bodies given, for messages.
    """
    out = unit.copy()
    i1, i2, i3 = unit[:, 0], unit[:, 1], unit[:, 2]
    new3, exact3 = _two_sum(i1, i2)
    ok3 = (exact3 == 0.0) & (new3 > i2)
    new1, ok1 = _exact_difference(i3, i2)
    ok1 &= (new1 > 0.0) & (new1 < i2)
    new2, ok2 = _exact_difference(i3, i1)
    ok2 &= (new2 > i1) & (new2 < i3)
    done = np.zeros(len(unit), dtype=bool)
    for column, new, ok in ((2, new3, ok3), (0, new1, ok1), (1, new2, ok2)):
        use = ok & ~done
        out[use, column] = new[use]
        done |= use
    if not done.all():
        raise NonPhysicalBodyError(
            f"moments {_row(given, ~done, rows, total)} exceed the flat edge I3 = I1 + I2 by "
            "less than the rounding slack 8 eps I3, but no body on the edge "
            "differs from them in one moment by that excess; give moments with "
            "I3 <= I1 + I2"
        )
    # a rod thinner than the rounding of I3 gets an I1 of ~eps I3: its phases
    # are those of the thin rod still, but not its energy along I1
    grown = np.abs(out[:, 0] - unit[:, 0]) > FLAT_MOVE_WARNING * unit[:, 0]
    if grown.any():
        k = int(np.flatnonzero(grown)[0])
        # in the given units (unit I1 may have underflowed to 0)
        scale = float(given[k, 2]) / float(unit[k, 2])  # a power of two
        new, old = float(out[k, 0]) * scale, float(given[k, 0])
        change = abs(new / old - 1.0)  # Python floats: inf, not a RuntimeWarning
        changed = f"{change:.2g} of itself" if math.isfinite(change) else "by far more"
        warn(
            f"moments {_row(given, grown, rows, total)} lie beyond the flat edge by rounding and "
            f"were moved onto it: I1 {old:.17g} became {new:.17g}, "
            f"{changed} (a thin rod next to the rounding of I3: its "
            "phases are the thin rod's, but energies and momenta are those of the "
            "moved body)",
            InertialDefectWarning,
        )
    return out


# _snap_flat warns when it changes I1 by more than this fraction of itself
FLAT_MOVE_WARNING = 1e-6


def validate_moments(moments):
    """Check an array of sorted moments, shape (..., 3); raise on bad rows.

    See :func:`canonical_moments`, which this calls (bodies within the
    flat-edge slack pass).

    Raises
    ------
    NonPhysicalBodyError
        A moment is NaN, infinite or not positive, or ``I3 > I1 + I2``
        beyond the slack.
    SymmetricTopError
        Two moments are equal.
    """
    canonical_moments(moments)


def _row(flat, bad, rows=None, total=None):
    """The first bad row of ``flat`` as text; ``rows``/``total``: where the
    rows of ``flat`` sit among all the bodies given (a subset's own index
    named the wrong body)."""
    index = int(np.flatnonzero(bad)[0])
    number = index if rows is None else int(rows[index])
    total = flat.shape[0] if total is None else total
    # counted from 1, as catalog's "body k of N" (was "#0" for the first)
    where = f" (body {number + 1} of {total})" if total > 1 else ""
    return numbers_label("", flat[index]) + where


def _moment_array(body_or_moments):
    """Sorted moments, shape (..., 3), from an array-like (type-checked)."""
    moments = real_array("moments", body_or_moments, NonPhysicalBodyError)
    if moments.ndim == 0 or moments.shape[-1] != 3:
        raise NonPhysicalBodyError(f"moments must have shape (..., 3), got {moments.shape}")
    return np.sort(moments, axis=-1)


def _rescaled(unit, exponent, given):
    """``unit * 2**exponent``; refuses a flat-edge move lost to underflow."""
    with np.errstate(under="ignore", over="ignore"):
        out = np.ldexp(unit, np.asarray(exponent)[..., None])
        back = np.ldexp(out, -np.asarray(exponent)[..., None])
    if not np.array_equal(back, unit):
        flat = np.asarray(given).reshape(-1, 3)
        wrong = ~np.all(back.reshape(-1, 3) == unit.reshape(-1, 3), axis=1)
        raise NonPhysicalBodyError(
            f"moments {_row(flat, wrong)} lie within rounding of the flat edge; "
            "the body on the edge is not representable at this scale "
            "(subnormal moments): give the moments in larger units"
        )
    return out


def as_moments(body_or_moments):
    """Sorted, validated moments of shape (..., 3) at the caller's scale.

    A body within the flat-edge slack comes back exactly on the edge
    (see :func:`canonical_moments`).
    """
    if isinstance(body_or_moments, Body):
        return body_or_moments.moments
    moments = _moment_array(body_or_moments)
    unit, exponent = canonical_moments(moments)
    return _rescaled(unit, exponent, moments)


def unit_moments(body_or_moments):
    """Canonical moments ``unit`` and ``exponent`` (see :func:`canonical_moments`).

    What every kernel receives: exact power-of-two normalisation, largest
    moment in [1/2, 1), bodies within the slack on the flat edge.
    """
    if isinstance(body_or_moments, Body):
        return body_or_moments.unit_moments, body_or_moments.exponent
    return canonical_moments(_moment_array(body_or_moments))


# largest |F F^T - 1| of a frame given to Body (eigenvectors from an eigen-
# solver are orthonormal to a few 1e-16; a frame off by more would turn
# every vector passed through it by that much)
FRAME_TOLERANCE = 1e-9


def _orthonormal_frame(frame):
    """``frame`` as a float (3, 3) array with orthonormal rows, or an error."""
    frame = real_array("frame", frame, NonPhysicalBodyError)
    if frame.shape != (3, 3) or not np.all(np.isfinite(frame)):
        got = "non-finite entries" if frame.shape == (3, 3) else f"shape {frame.shape}"
        raise NonPhysicalBodyError(
            f"frame must be a finite 3x3 matrix (the principal axes as rows), got {got}"
        )
    off = float(np.max(np.abs(frame @ frame.T - np.eye(3))))
    if not off <= FRAME_TOLERANCE:
        raise NonPhysicalBodyError(
            f"frame rows are not orthonormal unit vectors: |F F^T - 1| = {off:.3g} "
            f"> {FRAME_TOLERANCE:g} (a rotation, or a rotation times a reflection, is needed)"
        )
    return frame.copy()


class Body:
    """An asymmetric rigid body given by its principal moments of inertia.

    Parameters
    ----------
    moments : array_like, shape (3,)
        Principal moments in any order and any positive scale.
    name : str, optional
        Label carried into catalogs and figure titles.
    frame : array_like, shape (3, 3), optional
        Rows: the principal axes of ``moments`` (in the order given) as
        unit vectors of the caller's frame, orthonormal to within
        :data:`FRAME_TOLERANCE` (e.g. eigenvectors as rows).  Default: the
        caller's axes are the principal axes.

    Raises
    ------
    NonPhysicalBodyError
        Moments not finite or not positive, or ``I3 > I1 + I2``; a frame
        that is not a finite 3x3 matrix with orthonormal rows.
    SymmetricTopError
        Two equal moments.

    Notes
    -----
    The moments are kept sorted, ``I1 < I2 < I3`` (the paper's labelling).
    :attr:`frame` maps the caller's axes to the sorted principal axes with
    a proper rotation: a vector ``v`` in the caller's frame has principal
    components ``frame @ v``.  When sorting needs an odd permutation of
    the caller's axes, the third principal axis is reversed so that the
    principal frame stays right-handed.
    """

    def __init__(self, moments, *, name=None, frame=None):
        given = real_array("moments", moments, NonPhysicalBodyError)
        if given.shape != (3,):
            raise NonPhysicalBodyError(
                f"a body needs exactly 3 principal moments, got shape {given.shape}"
            )
        order = np.argsort(given, kind="stable")
        unit, exponent = canonical_moments(given[order])
        sorted_moments = _rescaled(unit, exponent, given[order])
        if frame is None:
            frame = np.zeros((3, 3))
            frame[np.arange(3), order] = 1.0
            if np.linalg.det(frame) < 0.0:
                frame[2] *= -1.0
        else:
            frame = _orthonormal_frame(frame)[order]
            if np.linalg.det(frame) < 0.0:
                frame[2] *= -1.0
        self._moments = sorted_moments
        self._moments.setflags(write=False)
        self._unit = unit
        self._unit.setflags(write=False)
        self._exponent = int(exponent)
        self._permutation = tuple(int(i) for i in order)
        self._frame = frame
        self._frame.setflags(write=False)
        self.name = name
        # the solid the moments came from, for drawing (orbits.animate.solid_faces):
        # ("t-handle", l1, l2, w), ("box", a, b, c), ("cylinder", a, length, b) or
        # ("mesh", vertices about the centre of mass, faces); None when unknown
        self.shape = None
        # the unit of the moments where a constructor knows it (moment_unit)
        self._moment_unit = None

    # -- constructors --------------------------------------------------
    @classmethod
    def t_handle(cls, l1, l2, w, *, name=None):
        """The paper's T-shaped handle of unit mass (eqn:IsforT).

        Parameters
        ----------
        l1 : float
            Length of the cross piece (along the body x axis).
        l2 : float
            Length of the shaft (along y), attached at the middle of the
            cross piece.
        w : float
            Side of the square cross-section of both bars.
        name : str, optional
            Label carried into catalogs and figure titles (as :class:`Body`).

        Notes
        -----
        eqn:IsforT gives the moments about the cross-piece axis (x), the
        shaft axis (y) and the normal to the plane of the T (z); a short
        cross piece reorders them, which :class:`Body` handles by sorting
        (the footnote to eqn:ellipsoid).

        The lengths are scaled by the exact power of two that brings the
        largest into [1/2, 1) before the polynomials are formed, so the body
        does not depend on the scale (lengths ``2**k`` times give moments
        ``4**k`` times, bit for bit).

        Raises
        ------
        NonPhysicalBodyError
            A length not finite and positive; a moment that overflows a
            double or underflows below the smallest normal double (2.2e-308);
            or lengths so disparate that the smallest moment underflows when
            computed at the scale of the largest.
        """
        l1, l2, w = _positive_lengths("T-handle", l1=l1, l2=l2, w=w)
        shape = ("t-handle", float(l1), float(l2), float(w))
        k = _binary_exponent(max(l1, l2, w))
        l1, l2, w = (math.ldexp(float(v), -k) for v in (l1, l2, w))
        # eqn:IsforT term by term: the bars' mass fractions a and b, each
        # bar about its own centre, and the parallel-axis term a b d**2 of
        # centres d = (w + l2)/2 apart.  Every term is positive and no
        # product of lengths is formed before the division by l1 + l2
        # (the expanded polynomials over (l1 + l2)**2 lost their digits,
        # then divided by zero, for l1, l2 below 1e-160 of w)
        total = l1 + l2
        a, b = l1 / total, l2 / total
        apart = a * b * (0.5 * (w + l2)) ** 2
        cross_piece = a * (l1 * l1 + w * w) / 12
        shaft = b * (l2 * l2 + w * w) / 12
        ix = a * (w * w) / 6 + shaft + apart
        iy = cross_piece + b * (w * w) / 6
        iz = cross_piece + shaft + apart
        what = "T-handle ({:.6g}, {:.6g}, {:.6g})".format(*shape[1:])
        labels = ("I_x", "I_y", "I_z")
        small = "give the lengths in smaller units (larger numbers)"
        moments = _at_scale(
            (ix, iy, iz),
            2 * k,
            what,
            labels,
            small=small,
            large="give the lengths in larger units (smaller numbers)",
        )
        for label, value in zip(labels, (ix, iy, iz)):
            if value < _SAFE_UNIT:
                raise NonPhysicalBodyError(
                    f"the {what} has {label} = {_decimal(value, 2 * k)}, less than "
                    f"{_decimal(_SAFE_UNIT)} of the square of its longest length: it "
                    "underflows in the intermediate products and would lose precision "
                    "(lengths this disparate are beyond double precision)"
                )
        body = cls(moments, name=name)
        body.shape = shape
        return body

    @classmethod
    def ellipsoid(cls, b, c, *, name=None):
        """The paper's unit-norm body from two ellipsoid semi-axes (eqn:isforellipsoid).

        ``I1 = b^2 + c^2``, ``I2 = (c^2 - b^2 + S)/2``,
        ``I3 = (b^2 - c^2 + S)/2`` with ``S = sqrt(2 - 3b^4 - 2b^2c^2 - 3c^4)``,
        so that ``|I| = 1``; the third semi-axis is
        ``a = sqrt((S - b^2 - c^2)/2)``.  Needs ``0 <= c < b < a``
        (``c = 0``: a flat body, a lamina); the semi-axes are dimensionless
        (the body has unit norm, not unit mass).

        Parameters
        ----------
        b, c : float
            The middle and the shortest semi-axis, dimensionless.
        name : str, optional
            Label carried into catalogs and figure titles (as :class:`Body`).

        Raises
        ------
        NonPhysicalBodyError
            ``b`` or ``c`` not finite, negative, ``c > b``, ``a < b``, too
            large for a unit norm (``2 - 3b^4 - 2b^2c^2 - 3c^4 < 0``), or
            ``b`` so small that ``I1 = b^2 + c^2`` underflows below the
            smallest normal double (2.2e-308).
        SymmetricTopError
            ``c = b`` or ``a = b`` (two equal moments).
        """
        b, c = _non_negative_lengths("ellipsoid semi-axis", b=b, c=c)
        if c > b:
            raise NonPhysicalBodyError(
                f"ellipsoid semi-axes b={b}, c={c}: the paper's parametrisation needs "
                "0 <= c < b < a (c the shortest semi-axis); swap b and c"
            )
        if c == b:
            raise SymmetricTopError(
                f"ellipsoid semi-axes b = c = {b} give I2 = I3: a symmetric top, which "
                "has no separatrix and no total-phase formula; need 0 <= c < b < a"
            )
        # 3 b^4 <= 2 needs b < 1; checked first so that b^4 cannot overflow
        root_sq = 2.0 - 3.0 * b**4 - 2.0 * b**2 * c**2 - 3.0 * c**4 if b < 1.0 else -1.0
        if root_sq < 0.0:
            raise NonPhysicalBodyError(
                f"ellipsoid semi-axes b={b}, c={c} are too large for a "
                "unit-norm moment of inertia (2 - 3b^4 - 2b^2c^2 - 3c^4 < 0)"
            )
        root = math.sqrt(root_sq)
        if root - b * b - c * c <= 0.0:
            raise NonPhysicalBodyError(
                f"ellipsoid semi-axes b={b}, c={c} leave no real third "
                "semi-axis a (need sqrt(2-3b^4-2b^2c^2-3c^4) > b^2 + c^2)"
            )
        # a^2 - b^2 = (S - 3 b^2 - c^2)/2 = I2 - I1
        if root - 3.0 * b * b - c * c < 0.0:
            a = math.sqrt(0.5 * (root - b * b - c * c))
            raise NonPhysicalBodyError(
                f"ellipsoid semi-axes b={b}, c={c} give a third semi-axis a = {a:.6g} "
                "shorter than b: the paper's parametrisation needs 0 <= c < b < a "
                "(b the middle semi-axis)"
            )
        square_sum, k = _scaled_square_sum(b, c)
        (i1,) = _at_scale(
            (square_sum,),
            k,
            f"ellipsoid of semi-axes b={b:.6g}, c={c:.6g}",
            ("I1 = b^2 + c^2",),
            small="b must be at least about 1.5e-154",
        )
        moments = (i1, 0.5 * (c * c - b * b + root), 0.5 * (b * b - c * c + root))
        return cls(moments, name=name)

    @classmethod
    def from_inertia_tensor(cls, tensor, *, name=None, defect="error"):
        """Body from a symmetric 3x3 inertia tensor in the caller's frame.

        The principal axes (eigenvectors) are kept in :attr:`frame`.

        Parameters
        ----------
        tensor : array_like, shape (3, 3)
        name : str, optional
            Label carried into catalogs and figure titles (as :class:`Body`).
        defect : {"error", "flatten"}
            What to do with a measured or computed body a hair beyond the
            flat limit, ``I3 > I1 + I2`` (see :func:`remove_flat_excess`).

        Raises
        ------
        NonPhysicalBodyError
            Not a finite symmetric 3x3 matrix, or its eigenvalues are not
            the moments of a rigid body (``I3 > I1 + I2`` with
            ``defect="error"``).
        InputError
            ``defect`` not one of the two names.
        SymmetricTopError
            Two eigenvalues closer than the eigen-solver's rounding
            (:func:`symmetric_within_rounding`): a symmetric top whose
            rounding noise would otherwise decide its phases.

        Warns
        -----
        InertialDefectWarning
            With ``defect="flatten"`` when the excess was removed.
        """
        return _from_tensor(cls, tensor, name, defect, 0.0, "body given by its tensor")

    @classmethod
    def from_semi_axes(cls, a, b, c, *, name=None):
        """Uniform solid ellipsoid of unit mass with semi-axes a, b, c.

        Moments about the a, b, c axes are ``(b^2+c^2)/5``, ``(a^2+c^2)/5``
        and ``(a^2+b^2)/5`` (caller's axes along a, b, c); a zero semi-axis
        gives a flat body.  Each moment is computed with its semi-axes scaled
        by an exact power of two (scale-free, as :meth:`box`).

        Parameters
        ----------
        a, b, c : float
            Semi-axes along x, y and z (m for kg m^2; the mass is 1).
        name : str, optional
            Label carried into catalogs and figure titles (as :class:`Body`).

        Raises
        ------
        NonPhysicalBodyError
            A semi-axis not finite or negative, two zero semi-axes, or a
            moment that overflows a double or underflows below the smallest
            normal double (2.2e-308).
        SymmetricTopError
            Two equal semi-axes.
        """
        a, b, c = _non_negative_lengths("semi-axis", a=a, b=b, c=c)
        values, exponents = [], []
        for p, q in ((b, c), (a, c), (a, b)):
            if max(p, q) == 0.0:
                values.append(0.0)  # refused by Body: not positive
                exponents.append(0)
                continue
            square_sum, k = _scaled_square_sum(p, q)
            values.append(square_sum / 5.0)
            exponents.append(k)
        moments = _at_scale(
            values,
            exponents,
            f"ellipsoid of semi-axes ({a:.6g}, {b:.6g}, {c:.6g})",
            ("I_a", "I_b", "I_c"),
            small="give the semi-axes in smaller units (larger numbers)",
            large="give the semi-axes in larger units (smaller numbers)",
        )
        return cls(moments, name=name)

    @classmethod
    def preset(cls, name):
        """A named body: ``"t-handle"`` (8, 4, 1) or ``"fig6"``.

        ``fig6`` is the paper's Fig. 6 body, I = (0.26, 0.55, 0.793662).

        Parameters
        ----------
        name : str
            A key of :data:`orbits.PRESETS`.

        Raises
        ------
        InputError
            A name that is not a key (the message lists the known ones).
        """
        try:
            if not isinstance(name, str):
                raise KeyError(name)
            factory = PRESETS[name]
        except KeyError:
            known = ", ".join(sorted(PRESETS))
            raise InputError(f"unknown preset {name!r}; known presets: {known}") from None
        return factory()

    # -- properties ----------------------------------------------------
    @property
    def moments(self):
        """Principal moments ``(I1, I2, I3)``, ascending, as given.

        Moments given beyond the flat edge by rounding are those moved onto
        it (:func:`canonical_moments`; docs: conventions).
        """
        return self._moments

    @property
    def unit_moments(self):
        """Moments times ``2**-exponent`` (exact), the largest in [1/2, 1).

        The scale-free form every kernel receives (:func:`canonical_moments`).
        """
        return self._unit

    @property
    def name(self):
        """Label carried into catalogs and figure titles (str), or None."""
        return self._name

    @name.setter
    def name(self, value):
        # an array or a number here broke repr() and every catalog of the body
        if value is not None and not isinstance(value, str):
            raise ArgumentTypeError(f"name must be a str or None, got {type(value).__name__}")
        # np.str_ as plain text; a lone surrogate refused here, not when written
        self._name = None if value is None else utf8_text("name", str(value))

    @property
    def moment_unit(self):
        """The unit of :attr:`moments` where the constructor knows it, else None.

        ``"kg m^2"`` for :meth:`from_rotational_constants` (Planck's
        constant in SI); ``"kg m^2 (lengths in m, mass in kg)"`` for
        :meth:`box`, :meth:`cylinder`, :meth:`from_point_masses` and
        :meth:`from_mesh`, whose moments are in the units of their inputs
        (mass times length squared); None for moments given as numbers (any
        unit, any scale).  Notebook views label energies and momenta by it.
        """
        return self._moment_unit

    @property
    def exponent(self):
        """``moments = unit_moments * 2**exponent``."""
        return self._exponent

    @property
    def normalized_moments(self):
        """Moments scaled to ``|I| = 1`` (the paper's convention)."""
        return unit_norm(self._unit)  # no overflow at any scale

    @property
    def permutation(self):
        """Caller's axis index of each sorted moment: ``I_k = given[permutation[k]]``."""
        return self._permutation

    @property
    def frame(self):
        """Proper rotation from the caller's axes to the principal axes."""
        return self._frame

    @property
    def is_flat(self):
        """True when ``I3 = I1 + I2`` exactly (a lamina).

        Moments given within the rounding slack of the edge were moved onto
        it (:func:`canonical_moments`), so this is an exact test.
        """
        return bool(flat_excess(self._unit.reshape(1, 3))[0] == 0.0)

    def equivalent_ellipsoid(self):
        """Semi-axes (a, b, c) of the unit-mass solid ellipsoid with these moments.

        ``a^2 = 5 (I2 + I3 - I1)/2`` (along the I1 axis), and cyclically;
        ``a >= b >= c``.  A flat body gives ``c = 0``.  The moments are
        used as given (not normalised), e.g. the unit-mass T-handle
        (8, 4, 1) gives (4.23281, 3.07318, 0.645497) (Fig. 1 caption).

        Computed on the scale-free moments (``unit_moments * 2**exponent``,
        as every other routine), so moments near the top or the bottom of
        the double range give finite semi-axes; each sum of three moments
        keeps its relative accuracy where it cancels (TwoSum), and ``c`` is
        0 exactly when :attr:`is_flat`.
        """
        i1, i2, i3 = (float(v) for v in self._unit)
        squares = [
            _sum_of_three(i2, i3, -i1),
            _sum_of_three(i1, i3, -i2),
            max(0.0, 0.0 - float(flat_excess(self._unit.reshape(1, 3))[0])),  # +0.0 when flat
        ]
        # sqrt(x 2**e) = sqrt(x 2**(e mod 2)) 2**(e // 2), exactly scaled
        half, odd = divmod(self._exponent, 2)
        return tuple(
            math.ldexp(math.sqrt(2.5 * square * (2.0 if odd else 1.0)), half) for square in squares
        )

    def critical_angle(self, phi=0.0):
        """Polar angle of the separatrix spin, radians; see :func:`orbits.critical_angle`."""
        return critical_angle(self, phi)

    def __repr__(self):
        label = f", name={self.name!r}" if self.name else ""
        # the axes too where they are not the caller's: Body([3, 1, 2]) showed
        # as Body((1, 2, 3)), which it does not equal
        axes = (
            ""
            if np.array_equal(self._frame, np.eye(3))
            else f", frame={tuple(tuple(row) for row in (self._frame + 0.0).tolist())}"
        )
        return f"Body({numbers_label('', self._moments)}{axes}{label})"

    def _repr_html_(self):
        """The body in a notebook: moments (with their unit where known) and axes."""
        from .units import html_table

        kind = self.shape[0] if self.shape is not None else None
        unit = self._moment_unit or ""
        rows = [(f"I{k + 1}", float(v), unit) for k, v in enumerate(self._moments)]
        rows += [(f"I{k + 1} / |I|", float(v), "") for k, v in enumerate(self.normalized_moments)]
        rows += [
            ("flat (I3 = I1 + I2)", "yes" if self.is_flat else "no", ""),
            ("separatrix angle theta_crit (phi = 0)", float(self.critical_angle()), "rad"),
            ("principal axes (rows: I1, I2, I3 in your axes)", self._frame.round(6).tolist(), ""),
        ]
        if self.shape is not None:
            rows.append(("solid", kind, ""))
        return html_table(f"Body {self.name!r}" if self.name else "Body", rows)

    def __eq__(self, other):
        if not isinstance(other, Body):
            return NotImplemented
        return np.array_equal(self._moments, other._moments) and np.array_equal(
            self._frame, other._frame
        )

    def __hash__(self):
        return hash(self._moments.tobytes())

    def __setstate__(self, state):
        # pickle and deepcopy rebuild the arrays writeable: an edit to a
        # copy's moments changed its repr and hash but not its phases
        self.__dict__.update(state)
        for array in (self._moments, self._unit, self._frame):
            array.setflags(write=False)

    # -- real bodies (kg m^2 in, kg m^2 out) ---------------------------
    @classmethod
    def box(cls, a, b, c, mass=1.0, *, name=None):
        """Uniform solid rectangular box with edges a, b, c along x, y, z.

        ``I_x = m (b^2 + c^2)/12``, ``I_y = m (a^2 + c^2)/12``,
        ``I_z = m (a^2 + b^2)/12`` (any mechanics text, e.g. Goldstein,
        Table of moments).  In SI units (m, kg) the moments are in kg m^2 and
        every output of :class:`orbits.Motion` is physical.

        Each moment is computed with its two edges and the mass scaled by
        exact powers of two, so the body does not depend on the scale: edges
        ``2**k (a, b, c)`` give moments ``4**k`` times those of ``(a, b, c)``,
        bit for bit, and the same unit moments and phases.

        Parameters
        ----------
        a, b, c : float
            Edges along x, y and z (m for kg m^2).
        mass : float
            Total mass (kg for kg m^2); default 1.
        name : str, optional
            Label carried into catalogs and figure titles (as :class:`Body`).

        Raises
        ------
        NonPhysicalBodyError
            An edge or the mass not finite and positive, a subnormal mass, or
            a moment that overflows a double or underflows below the smallest
            normal double (2.2e-308): give the lengths or the mass in other
            units.
        SymmetricTopError
            Two equal edges (a square cross-section is a symmetric top).
        """
        a, b, c = _positive_lengths("box edge", a=a, b=b, c=c)
        mass = _positive_mass(mass)
        m_exp = _binary_exponent(mass)
        m = math.ldexp(mass, -m_exp)
        values, exponents = [], []
        for p, q in ((b, c), (a, c), (a, b)):
            square_sum, k = _scaled_square_sum(p, q)
            values.append(m * square_sum / 12.0)
            exponents.append(m_exp + k)
        moments = _at_scale(
            values,
            exponents,
            f"box ({a:.6g}, {b:.6g}, {c:.6g}) of mass {mass:.6g}",
            ("I_x", "I_y", "I_z"),
            small=_SMALL_LENGTHS,
            large=_LARGE_LENGTHS,
        )
        body = cls(moments, name=name)
        body.shape = ("box", a, b, c)
        body._moment_unit = SI_FROM_INPUTS
        return body

    @classmethod
    def cylinder(cls, radius, length, mass=1.0, *, radius_y=None, name=None):
        """Uniform solid cylinder along z, of circular or elliptic section.

        With semi-axes ``a = radius`` (along x) and ``b = radius_y`` (along
        y, default ``radius``) of the cross-section and length ``L``:
        ``I_x = m (b^2/4 + L^2/12)``, ``I_y = m (a^2/4 + L^2/12)``,
        ``I_z = m (a^2 + b^2)/4``; for ``a = b = R`` these are the textbook
        ``m (3R^2 + L^2)/12`` (twice) and ``m R^2/2``.

        Parameters
        ----------
        radius : float
            Semi-axis ``a`` of the cross-section, along x (m for kg m^2).
        length : float
            Length ``L`` along z.
        mass : float
            Total mass (kg for kg m^2); default 1.
        radius_y : float, optional
            Semi-axis ``b`` along y; needed for an asymmetric body.
        name : str, optional
            Label carried into catalogs and figure titles (as :class:`Body`).

        Raises
        ------
        SymmetricTopError
            Always for a circular section (two equal moments: a symmetric
            top, which has no separatrix); pass ``radius_y`` for an
            asymmetric, elliptic cylinder.
        NonPhysicalBodyError
            A length or the mass not finite and positive.
        """
        moments = cylinder_moments(radius, length, mass, radius_y=radius_y)
        if radius_y is None or moments[0] == moments[1]:
            raise SymmetricTopError(
                f"a cylinder of circular section has moments "
                f"{numbers_label('', moments)}: "
                "a symmetric top, which has no separatrix and no total-phase "
                "formula; give radius_y (an elliptic section) for an asymmetric "
                "body"
            )
        body = cls(moments, name=name)
        # the checked floats (a 1-element array or list is one number, as in box)
        radius, length = _positive_lengths("cylinder", radius=radius, length=length)
        (radius_y,) = _positive_lengths("cylinder", radius_y=radius_y)
        body.shape = ("cylinder", radius, length, radius_y)
        body._moment_unit = SI_FROM_INPUTS
        return body

    @classmethod
    def from_point_masses(cls, masses, positions, *, name=None, defect="error"):
        """Rigid set of point masses, about its centre of mass.

        ``I = sum_k m_k (|r_k|^2 1 - r_k r_k^T)`` with ``r_k`` measured from
        the centre of mass ``sum m_k x_k / sum m_k``; the principal axes
        are kept in :attr:`frame`.  Masses in kg and positions in m give
        kg m^2.

        Parameters
        ----------
        masses : array_like, shape (n,)
        positions : array_like, shape (n, 3)
        name : str, optional
            Label carried into catalogs and figure titles (as :class:`Body`).
        defect : {"error", "flatten"}
            As :meth:`from_inertia_tensor` (a planar set computed in
            floating point can land a hair past ``I3 = I1 + I2``).

        Raises
        ------
        NonPhysicalBodyError
            Shapes that do not match, masses not positive, non-finite
            values, a subnormal mass, collinear masses (a zero moment), or
            moments that overflow a double or underflow below the smallest
            normal double (2.2e-308).
        InputError
            ``defect`` not one of the two names.
        SymmetricTopError
            Two moments closer than the rounding of the sums that built
            them (e.g. three equal masses on an equilateral triangle).

        Notes
        -----
        The masses and positions are scaled by exact powers of two (largest
        mass and largest coordinate in [1/2, 1)) before the tensor is formed,
        so the body does not depend on the units: positions ``2**k`` times
        give moments ``4**k`` times, bit for bit, with no overflow of the
        intermediate products.
        """
        masses = real_array("point masses", masses, NonPhysicalBodyError)
        positions = real_array("point-mass positions", positions, NonPhysicalBodyError)
        if masses.ndim != 1 or masses.size == 0 or positions.shape != (masses.size, 3):
            raise NonPhysicalBodyError(
                f"point masses need masses of shape (n,) and positions of shape "
                f"(n, 3), got {masses.shape} and {positions.shape}"
            )
        if not (np.all(np.isfinite(masses)) and np.all(np.isfinite(positions))):
            raise NonPhysicalBodyError("point masses and positions must be finite")
        if np.any(masses <= 0.0):
            raise NonPhysicalBodyError("point masses must all be positive")
        for k in np.flatnonzero(masses < _SMALLEST_NORMAL)[:1]:
            _refuse_below_normal(f"point mass #{k}", float(masses[k]))
        if masses.size < 3:
            what = (
                "a single point mass: every moment about its centre of mass is zero"
                if masses.size == 1
                else "2 point masses lie on a line: the moment about it is zero"
            )
            raise NonPhysicalBodyError(
                f"{what}, which is no rigid body of this library; an asymmetric body "
                "needs at least 3 masses, not on one line"
            )
        reach_given = float(np.max(np.abs(positions)))
        if reach_given == 0.0:
            raise NonPhysicalBodyError(
                "the point masses all lie at one point: every moment is zero, "
                "which is no rigid body of this library"
            )
        _refuse_below_normal("the largest point-mass coordinate", reach_given)
        # exact power-of-two scalings: the largest mass and the largest
        # coordinate in [1/2, 1); the tensor is then 2**exponent times the one
        # computed here, free of overflow, and the same bits at any scale
        m_exp = _binary_exponent(float(np.max(masses)))
        x_exp = _binary_exponent(reach_given)
        with np.errstate(under="ignore"):
            masses = np.ldexp(masses, -m_exp)
            positions = np.ldexp(positions, -x_exp)
        exponent = m_exp + 2 * x_exp
        relative = positions - masses @ positions / masses.sum()
        with np.errstate(under="ignore"):
            squared = np.einsum("k,ki,ki->", masses, relative, relative)
            tensor = squared * np.eye(3) - np.einsum("k,ki,kj->ij", masses, relative, relative)
        if not squared > masses.size * _SAFE_UNIT:
            # at this scale an underflowed product is off by ~2^-1074 at most:
            # negligible beside moments above n 2^-960, not beside smaller ones
            raise NonPhysicalBodyError(
                "the point masses have a moment of inertia sum m r^2 = "
                f"{_decimal(float(squared), exponent)} about their centre of mass, less "
                f"than {_decimal(masses.size * _SAFE_UNIT)} of (largest mass) x (largest "
                "coordinate)^2: it underflows in the intermediate products and would "
                "lose precision (masses or distances this disparate are beyond double "
                "precision)"
            )
        values = np.linalg.eigvalsh(tensor)
        if values[0] <= 1e-12 * values[2]:
            raise NonPhysicalBodyError(
                "the point masses lie on a line: the moment about that line is "
                "zero, which is no rigid body of this library"
            )
        # rounding of the construction: each entry is a sum of n products
        # (n + 4 roundings each, relative to the sum of magnitudes); the
        # centre of mass is off by at most shift = 2 (n + 2) eps max|x|, which
        # moves every relative position by that one vector (a term linear in
        # the offset of the positions from their origin, not quadratic)
        reach = np.sqrt(np.einsum("ki,ki->k", relative, relative))
        shift = 2.0 * (masses.size + 2) * _EPS * float(np.max(np.abs(positions))) * math.sqrt(3)
        rounding = 4.0 * (masses.size + 4) * _EPS * float(masses @ reach**2) + 4.0 * shift * float(
            masses @ (reach + shift)
        )
        body = _from_tensor(cls, tensor, name, defect, rounding, "point masses", exponent)
        body._moment_unit = SI_FROM_INPUTS
        return body

    @classmethod
    def from_mesh(cls, path, *, density=1.0, name=None, defect="error"):
        """Uniform solid bounded by a closed triangle mesh (STL, OBJ, PLY...).

        Volume integrals over the mesh by trimesh (exact for the polyhedron:
        Mirtich's divergence-theorem formulas), about the centre of mass;
        the principal axes are kept in :attr:`frame`.  Lengths in m and
        ``density`` in kg/m^3 give kg m^2.  Needs the optional extra
        ``orbits[mesh]`` (trimesh).

        Parameters
        ----------
        path : path
            The mesh file, in any format trimesh reads.
        density : float
            Mass per unit volume (kg/m^3 for kg m^2); default 1.
        name : str, optional
            Label carried into catalogs and figure titles (as :class:`Body`).
        defect : {"error", "flatten"}
            As :meth:`from_inertia_tensor` (a thin plate's mesh can land a
            hair past the flat limit).

        Raises
        ------
        InputError
            trimesh missing, the file unreadable, the mesh not closed
            (not watertight) or inside out, or ``defect`` not one of the two
            names.
        NonPhysicalBodyError
            ``density`` not finite and positive or subnormal, or moments that
            overflow a double or underflow below the smallest normal double
            (2.2e-308).  The vertices and the density are scaled by exact
            powers of two before trimesh integrates, so the body does not
            depend on the units.
        SymmetricTopError
            Two moments closer than the rounding of the sums over the
            faces that built them (e.g. a sphere or a cube as a mesh).

        Warns
        -----
        UserWarning
            Closed shells whose bounding boxes overlap: where the solids
            overlap, their common volume counts twice (merge them first).

        Notes
        -----
        The mesh is moved to its bounding box's centre before it is
        integrated, so a mesh far from the origin (a part placed in an
        assembly's coordinates) gives the same moments as at the origin.
        """
        from .errors import InputError

        density = _positive_mass(density, "density")
        _check_defect(defect)
        try:
            import trimesh
        except ImportError:
            raise InputError("Body.from_mesh needs trimesh: pip install 'orbits[mesh]'") from None
        try:
            # read as stored, then processed (vertices merged, trimesh's
            # absolute tolerance) at the working scale below
            raw = trimesh.load(str(path), force="mesh", process=False)
        except Exception as error:  # trimesh raises many kinds
            raise InputError(f"cannot read mesh {path}: {error}") from None
        if not isinstance(raw, trimesh.Trimesh) or len(raw.faces) == 0:
            raise InputError(f"{path} holds no triangle mesh")
        vertices = np.asarray(raw.vertices, dtype=float)
        if not np.all(np.isfinite(vertices)):
            raise InputError(f"mesh {path} has vertices that are not finite numbers")
        # the mesh moved to its bounding box's centre first: trimesh
        # integrates about the origin and then shifts the tensor to the centre
        # of mass, which cancels catastrophically far from it (a box 10^4 m
        # out came 5 % off, an off-centre cube passed as an asymmetric top;
        # an audit).  The subtraction's rounding, below an ulp of the extent,
        # is far inside the file's own (an ulp of the coordinates).
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        local = vertices - (0.5 * low + 0.5 * high)
        # exact power-of-two scalings (largest coordinate and the density in
        # [1/2, 1)): trimesh's volume integrals (degree 5 in the lengths) are
        # then free of overflow and underflow, and its merging tolerance is
        # relative to the size; the tensor is 2**exponent times the one computed
        x_exp = _binary_exponent(float(np.max(np.abs(local))))
        d_exp = _binary_exponent(density)
        mesh = trimesh.Trimesh(vertices=np.ldexp(local, -x_exp), faces=np.asarray(raw.faces))
        if len(mesh.faces) == 0:
            raise InputError(f"{path} holds no triangle mesh")
        if not mesh.is_watertight:
            raise InputError(f"mesh {path} is not closed (watertight): it bounds no volume")
        if not mesh.is_winding_consistent or not mesh.volume > 0.0:
            raise InputError(
                f"mesh {path} is inside out or inconsistently wound (its volume is not positive)"
            )
        _check_shells(mesh, path)
        mesh.density = math.ldexp(density, -d_exp)
        exponent = d_exp + 5 * x_exp
        tensor = np.asarray(mesh.moment_inertia, dtype=float)
        centre = np.asarray(mesh.center_mass, dtype=float)
        # rounding of the construction: the vertices as the file stores them
        # move the surface by at most delta along its normal, which moves
        # each moment by at most rho delta (surface integral of r^2 about the
        # centre of mass; Weyl's inequality on rho (r^2 1 - r r^T) delta_n dA),
        # 2 rho delta that integral is the bound used (a thin plate's moments
        # move far more than M R delta); and one sum over the faces per
        # entry, bounded by 16 (faces + 4) eps |I|
        delta = math.ldexp(vertex_rounding(vertices, _mesh_text(path)), -x_exp)
        file_part = (
            2.0
            * delta
            * float(mesh.density)
            * _surface_r2(mesh.triangles - centre, mesh.area_faces)
        )
        rounding = file_part + 16.0 * (len(mesh.faces) + 4) * _EPS * float(
            np.abs(np.trace(tensor))
        )
        try:
            body = _from_tensor(cls, tensor, name, defect, rounding, f"mesh {path}", exponent)
        except SymmetricTopError as error:
            if file_part <= 0.5 * rounding:  # the sums' rounding, not the file's digits
                raise
            raise SymmetricTopError(
                f"{error}; the bound is set by the digits the file writes (vertices "
                f"good to {math.ldexp(delta, x_exp):.2g} in its units): if they are "
                "exact, write more digits (OBJ with %.8f, or binary STL)"
            ) from None
        body._moment_unit = SI_FROM_INPUTS
        body.shape = (
            "mesh",
            np.ldexp(np.asarray(mesh.vertices - centre, dtype=float), x_exp),
            np.asarray(mesh.faces),
        )
        return body

    @classmethod
    def from_rotational_constants(cls, a, b, c, unit="cm-1", *, defect="error", name=None):
        """A molecule from its rotational constants A >= B >= C.

        ``I_A = h / (8 pi^2 c A)`` for wavenumbers (``unit="cm-1"``, with
        ``c`` in cm/s), ``I_A = h / (8 pi^2 A)`` for frequencies (``"MHz"``,
        ``"GHz"``), and likewise for B and C (e.g. Gordy & Cook,
        *Microwave Molecular Spectra*, eq. 2.8); CODATA constants from
        :mod:`scipy.constants`.  The moments are in kg m^2.  The body's own
        axes (:attr:`frame`, the axes of an ``omega`` given to it) are the
        principal axes a, b, c of ``A >= B >= C`` (``I_A <= I_B <= I_C``),
        whatever the order the constants are given in.

        Parameters
        ----------
        a, b, c : float
            Rotational constants, any order (sorted: the body's axes are
            a, b, c).
        unit : {"cm-1", "MHz", "GHz"}
        defect : {"error", "flatten"}
            Ground-state constants of planar molecules give
            ``I_C > I_A + I_B`` by the inertial defect
            ``Delta = I_C - I_A - I_B`` (vibration-rotation interaction;
            water: 0.05 u A^2, 3 %).  ``"error"`` (default) raises;
            ``"flatten"`` sets ``I_C = I_A + I_B`` (the flat edge of the
            physical region) and warns with the defect.
        name : str, optional
            Label carried into catalogs and figure titles (as :class:`Body`).

        Raises
        ------
        NonPhysicalBodyError
            A constant not finite and positive or subnormal, a moment that
            overflows a double or underflows below the smallest normal double
            (2.2e-308), or a positive inertial defect with ``defect="error"``.
        InputError
            An unknown ``unit`` or ``defect``.

        Warns
        -----
        InertialDefectWarning
            With ``defect="flatten"`` when the defect was removed.
        """
        from scipy import constants as codata

        factors = {"cm-1": 100.0 * codata.c, "MHz": 1e6, "GHz": 1e9}
        if not isinstance(unit, str) or unit not in factors:
            raise InputError(
                f"unknown unit {unit!r} for rotational constants; use one of {', '.join(factors)}"
            )
        _check_defect(defect)
        values = _positive_lengths("rotational constant", normal=True, A=a, B=b, C=c)
        a, b, c = values  # floats for the labels (a Fraction or a 1-element array has no :g)
        # I = h / (8 pi^2 f X) with X = x 2**e (x in [1/2, 1)) computed as
        # (h / (8 pi^2 f x)) 2**-e: exact scaling, free of overflow/underflow
        scaled, exponents = [], []
        for value in sorted(values):  # C <= B <= A
            e = _binary_exponent(value)
            scaled.append(codata.h / (8.0 * math.pi**2 * (math.ldexp(value, -e) * factors[unit])))
            exponents.append(-e)
        i_c, i_b, i_a = _at_scale(
            scaled,
            exponents,
            f"molecule of rotational constants ({a:.10g}, {b:.10g}, {c:.10g}) {unit}",
            ("I_C", "I_B", "I_A"),
            unit="kg m^2",
            small="the rotational constants are too large",
            large="the rotational constants are too small",
        )
        amu_a2 = codata.physical_constants["atomic mass constant"][0] * 1e-20
        i_a, i_b, i_c = remove_flat_excess(
            i_a,
            i_b,
            i_c,
            defect,
            what=f"rotational constants ({a:.10g}, {b:.10g}, {c:.10g}) {unit}",
            labels=("I_A", "I_B", "I_C"),
            describe=lambda excess: (
                f"inertial defect Delta = I_C - I_A - I_B = "
                f"{excess / amu_a2:.6g} u A^2 ({excess / i_c:.3%} of I_C)"
            ),
        )
        body = cls((i_a, i_b, i_c), name=name)
        body._moment_unit = "kg m^2"
        return body


class InertialDefectWarning(UserWarning):
    """A body whose excess over the flat limit was removed (``defect="flatten"``).

    Rotational constants (the inertial defect of a planar molecule), point
    masses, meshes and inertia tensors; also moments given beyond the flat
    edge by rounding when moving them onto it changes I1 by more than
    :data:`FLAT_MOVE_WARNING` of itself (a rod thinner than ``eps I3``).
    """


_EPS = float(np.finfo(float).eps)
# eigen-solver backward error of a symmetric 3x3 tensor, in eps |I|
# (LAPACK's syevd: a small multiple of eps ||T||_2 for n = 3)
_EIGEN_ROUNDING = 32.0


def remove_flat_excess(i1, i2, i3, defect, *, what, labels=("I1", "I2", "I3"), describe=None):
    """The one rule for bodies a hair past the flat limit ``I3 = I1 + I2``.

    Parameters
    ----------
    i1, i2, i3 : float
        Moments with ``i3`` the largest.
    defect : {"error", "flatten"}
        ``"error"`` raises when ``i3 - i1 - i2`` exceeds the rounding slack
        ``8 eps i3``; ``"flatten"`` sets ``i3 = i1 + i2`` (the flat edge of
        the physical region) and warns with the excess.
    what : str
        The body, for the messages.
    labels : tuple of str
        Names of the three moments in the messages.
    describe : callable, optional
        ``describe(excess)``: the excess in words (the molecules give it in
        u A^2 as the inertial defect); by default in the moments' units and
        relative to ``i3``.

    Returns
    -------
    i1, i2, i3 : float
        ``i3`` replaced by ``i1 + i2`` when flattened.

    Raises
    ------
    NonPhysicalBodyError
        An excess with ``"error"``.
    InputError
        ``defect`` not one of the two names.

    Warns
    -----
    InertialDefectWarning
        With ``"flatten"`` when the excess was removed (at the first line
        outside the package).
    """
    _check_defect(defect)
    excess = i3 - (i1 + i2)
    if not excess > FLAT_SLACK * i3:
        return i1, i2, i3
    a, b, c = labels
    if describe is None:
        text = f"excess {c} - {a} - {b} = {excess:.6g} ({excess / i3:.3%} of {c})"
    else:
        text = describe(excess)
    if defect == "error":
        raise NonPhysicalBodyError(
            f"{what} violate {c} <= {a} + {b} by the {text}; pass defect='flatten' "
            f"(CLI: --defect flatten) to put the body on the flat edge {c} = {a} + {b}"
        )
    warn(f"{text} removed: {c} set to {a} + {b} (flat body)", InertialDefectWarning)
    # fl(i1 + i2) may round below the edge; rounded up instead, the body
    # lies within the slack and Body moves it exactly onto the edge
    # (canonical_moments), so that it is flat in exact arithmetic
    edge, error = _two_sum(i1, i2)
    if error > 0.0:
        edge = math.nextafter(edge, math.inf)
    return i1, i2, edge


def vertex_rounding(vertices, text=None):
    """Absolute rounding of vertex coordinates as a mesh file stores them.

    A text file (``text``: its bytes; OBJ, ASCII PLY or STL, OFF) keeps each
    coordinate to the decimals written there, trailing zeros included:
    ``0.15000000`` is good to ``5e-9``, ``1.5e-01`` to ``5e-3``.  Without
    the text: STL keeps float32 (relative ``2^-24``); decimal values are
    taken to keep the fewest decimals ``d`` that reproduce every
    coordinate to a few ulps (``0.5 10^-d`` absolute, an upper bound: the
    file may have written more); otherwise the coordinates are taken as
    full doubles (relative ``eps``).
    """
    v = np.asarray(vertices, dtype=float)
    big = float(np.max(np.abs(v))) if v.size else 0.0
    if text is not None:
        written = _written_rounding(text, v.ravel())
        if written is not None:
            return max(written, 0.5 * big * _EPS)
    with np.errstate(over="ignore", under="ignore"):  # beyond float32's range
        if np.array_equal(v.astype(np.float32).astype(float), v):
            return big * 2.0**-24
    slack = 4.0 * _EPS * np.maximum(np.abs(v), np.finfo(float).tiny)
    for digits in range(16):
        if np.all(np.abs(np.round(v, digits) - v) <= slack):
            # (above 2^53 every double is an integer: then a double's own
            # rounding, not the decimals, bounds it)
            return max(0.5 * 10.0**-digits, 0.5 * big * _EPS)
    return big * _EPS


# a decimal number, as text mesh formats write coordinates (integers too:
# %.17g writes 0 and 1 bare; indices and counts among them only matter
# where they equal a vertex value): sign, integer digits, fraction digits,
# exponent
_WRITTEN_NUMBER = re.compile(rb"[-+]?(?=\.?\d)(\d*)(?:\.(\d*))?(?:[eE]([-+]?\d+))?")


def _check_shells(mesh, path):
    """Refuse a shell wound inside out outside every solid; warn of overlapping solids.

    trimesh integrates every shell, so where two solids overlap their common
    volume counts twice (two overlapping boxes came out with the mass of
    both; an audit).  Bounding boxes that overlap do not prove it (linked
    rings), hence a warning, not a refusal; an inner shell wound inside out
    (a cavity) has negative volume and is left out, and one that is inside
    no solid shell's bounding box (so no cavity) is refused with
    :class:`InputError`.  Inside a bounding box is necessary for a cavity,
    not sufficient: a part wound inside out in the hole of a ring passes.
    Shells are the face components, their volumes and boxes summed per
    label, and the solid boxes are swept in order of their lowest x: no
    mesh is built per shell, and many disjoint solid shells (a rubble pile)
    cost about their sorting (each inside-out shell is compared with every
    solid one).
    """
    from trimesh.graph import connected_component_labels

    labels = connected_component_labels(mesh.face_adjacency, node_count=len(mesh.faces))
    count = int(labels.max()) + 1 if labels.size else 0
    if count < 2:
        return
    triangles = mesh.triangles  # cached by trimesh; from_mesh's rounding bound uses it too
    signed = np.einsum("ij,ij->i", triangles[:, 0], np.cross(triangles[:, 1], triangles[:, 2]))
    volume = np.bincount(labels, weights=signed, minlength=count)
    low = np.full((count, 3), np.inf)
    high = np.full((count, 3), -np.inf)
    np.minimum.at(low, labels, triangles.min(axis=1))
    np.maximum.at(high, labels, triangles.max(axis=1))
    solid = np.flatnonzero(volume > 0.0)
    for shell in np.flatnonzero(volume < 0.0):
        # a cavity lies inside a solid shell, so inside its bounding box; a
        # shell wound inside out anywhere else (a part of an assembly with its
        # normals flipped) would count as negative mass: 9 % off I2 for a small
        # part beside a box, with no message (an audit)
        inside = np.all(low[solid] <= low[shell], axis=1) & np.all(
            high[solid] >= high[shell], axis=1
        )
        if not inside.any():
            raise InputError(
                f"mesh {path}: one of its {count} closed shells is wound inside out "
                "(negative volume) and lies outside every solid shell, so it is no "
                "cavity and would count as negative mass; fix its face winding "
                "(normals pointing out)"
            )
    low, high = low[solid], high[solid]
    order = np.argsort(low[:, 0], kind="stable")
    low, high = low[order], high[order]
    for k in range(len(order)):
        for j in range(k + 1, len(order)):
            if low[j, 0] >= high[k, 0]:
                break  # this and every later box start beyond box k in x
            if np.all(np.minimum(high[k], high[j]) > np.maximum(low[k], low[j])):
                warn(
                    f"mesh {path} has {len(solid)} closed shells of positive volume, and "
                    "two of them have overlapping bounding boxes: where the solids "
                    "overlap, their common volume counts twice; merge overlapping "
                    "shells into one surface (a boolean union) first",
                    UserWarning,
                )
                return


def _surface_r2(triangles, areas):
    """The integral of ``|r|^2`` over a triangulated surface (``triangles``
    (F, 3, 3) relative to the point ``r`` is measured from; exact for the
    polyhedron: ``area (a.a + b.b + c.c + a.b + b.c + c.a) / 6`` per face)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    per_face = np.einsum("fi,fi->f", a, a + b) + np.einsum("fi,fi->f", b, b + c)
    per_face += np.einsum("fi,fi->f", c, c + a)
    return float(np.dot(areas, per_face) / 6.0)


def _mesh_text(path):
    """The bytes of a mesh file up to 256 MiB (for :func:`vertex_rounding`), else None."""
    import os

    try:
        if os.path.getsize(path) > 256 * 2**20:
            return None
        with open(path, "rb") as handle:
            return handle.read()
    except (OSError, TypeError, ValueError):
        return None


def _written_rounding(text, values):
    """Largest absolute rounding of ``values`` as written in ``text`` (bytes), or None.

    A writer that pads (a fraction of two or more digits ending in 0, as
    ``%.8f`` writes ``0.15000000``) keeps fixed decimals: each value is good
    to ``0.5 10^(e - decimals)`` of its finest writing.  A writer that
    strips trailing zeros (``%g``, ``repr``, ``%.17g``) keeps some number of
    significant digits, at least the most seen in any coordinate, ``S``:
    the values are good to ``0.5 10^(1 - S) max|v|``.  Short values are
    ambiguous: ``1.5`` may be exact (a shortest-repr writer, as trimesh's
    ASCII STL export) or rounded (``%.2g``, ``round(x, 2)``: a cube written
    so is a symmetric top whose moments differ by rounding alone), so they
    are taken as rounded, and a body whose moments are within that is
    refused, with a note on the digits (:meth:`Body.from_mesh`).  Bare
    integers count as written values (``%.17g`` writes 0 and 1 as ``0``
    and ``1``; they were skipped and the rounding guessed at 0.05).  None
    when the text is not plain ASCII (a binary file) or some value is not
    written in it.
    """
    if not text or not text.isascii() or b"\0" in text:
        return None
    numbers, roundings, digits = [], [], []
    padded = False
    for match in _WRITTEN_NUMBER.finditer(text):
        whole, fraction, exponent = match.group(1), match.group(2), match.group(3)
        fraction = fraction or b""
        if not (whole or fraction):
            continue  # a lone point or sign
        try:
            value = float(match.group(0))
            rounding = 0.5 * 10.0 ** (int(exponent or 0) - len(fraction))
        except (ValueError, OverflowError):
            continue
        padded = padded or (len(fraction) >= 2 and fraction.endswith(b"0"))
        numbers.append(value)
        roundings.append(rounding)
        digits.append(max(len((whole + fraction).lstrip(b"0")), 1))
    if not numbers:
        return None
    numbers, index = np.unique(np.asarray(numbers), return_inverse=True)
    finest = np.full(numbers.size, np.inf)
    np.minimum.at(finest, index, np.asarray(roundings))
    most = np.zeros(numbers.size, dtype=np.int64)
    np.maximum.at(most, index, np.asarray(digits))
    where = np.minimum(np.searchsorted(numbers, values), numbers.size - 1)
    if not np.array_equal(numbers[where], values):
        return None
    if padded:
        return float(np.max(finest[where]))
    significant = int(np.max(most[where]))
    return 0.5 * 10.0 ** (1 - significant) * float(np.max(np.abs(values)))


def symmetric_within_rounding(values, rounding, what):
    """Refuse sorted moments closer than the rounding of their construction.

    Parameters
    ----------
    values : ndarray, shape (3,)
        Moments computed from geometry, ascending.
    rounding : float
        A bound on the rounding error of each moment from its construction
        (the eigen-solver's backward error ``32 eps |I|`` plus that of the
        sums that built the tensor), in the moments' units.
    what : str
        The body, for the message.

    Raises
    ------
    SymmetricTopError
        ``I2 - I1`` or ``I3 - I2`` at most ``2 rounding``: the body is a
        symmetric top within rounding, and its phases would be decided by
        the noise.  The message gives the relative difference and the bound.
    """
    gaps = (values[1] - values[0], values[2] - values[1])
    k = 0 if gaps[0] <= gaps[1] else 1
    if gaps[k] <= 2.0 * rounding:
        pair = ("I1", "I2") if k == 0 else ("I2", "I3")
        raise SymmetricTopError(
            f"the moments {numbers_label('', values)} "
            f"computed from the {what} have {pair[1]} - {pair[0]} = "
            f"{gaps[k] / values[2]:.2g} I3, within the rounding of their "
            f"construction (bound {2.0 * rounding / values[2]:.2g} I3): a symmetric "
            "top, which has no separatrix and no total-phase formula"
        )


def _from_tensor(cls, tensor, name, defect, rounding, what, exponent=0):
    """A Body from a tensor computed with ``rounding`` (see ``from_inertia_tensor``).

    The inertia tensor is ``tensor * 2**exponent`` and ``rounding`` is in the
    units of ``tensor``.  The eigenvalues are found at the working scale
    (largest entry in [1/2, 1), an exact power-of-two scaling) and brought
    back exactly; moments that no normal double holds are refused.
    """
    _check_defect(defect)
    tensor = real_array("the inertia tensor", tensor, NonPhysicalBodyError)
    if tensor.shape != (3, 3) or not np.all(np.isfinite(tensor)):
        raise NonPhysicalBodyError("an inertia tensor must be a finite 3x3 matrix")
    scale = float(np.max(np.abs(tensor)))
    if scale == 0.0:
        raise NonPhysicalBodyError(
            f"the inertia tensor of the {what} is zero: no rigid body of this library"
        )
    k = _binary_exponent(scale)
    with np.errstate(under="ignore"):
        tensor = np.ldexp(tensor, -k)
    rounding = math.ldexp(rounding, -k)
    exponent = int(exponent) + k
    if not np.allclose(tensor, tensor.T, rtol=0.0, atol=1e-12 * np.max(np.abs(tensor))):
        raise NonPhysicalBodyError("an inertia tensor must be symmetric")
    values, vectors = np.linalg.eigh(0.5 * (tensor + tensor.T))
    if not values[0] > 0.0:
        shown = ", ".join(_decimal(float(v), exponent) for v in values)
        raise NonPhysicalBodyError(
            f"the inertia tensor of the {what} has eigenvalues ({shown}), not all "
            "positive: these are not the moments of a rigid body"
        )
    values = np.array(
        _at_scale(
            [float(v) for v in values],
            exponent,
            f"inertia tensor of the {what}",
            ("I1", "I2", "I3"),
            small="give the body in smaller units (larger numbers)",
            large="give the body in larger units (smaller numbers)",
        )
    )
    with np.errstate(under="ignore"):
        rounding = math.ldexp(rounding, exponent) if rounding > 0.0 else 0.0
    symmetric_within_rounding(
        values, rounding + _EIGEN_ROUNDING * _EPS * float(np.max(np.abs(values))), what
    )
    values = np.array(remove_flat_excess(*values, defect, what=f"the moments of the {what}"))
    return cls(values, name=name, frame=vectors.T)


# ------------------------------------------------------- exact scaling of constructors
# A moment computed as ``unit * 2**exponent`` from lengths and masses scaled by
# exact powers of two: ``m * 2**t`` with ``m`` in [1/2, 1) is a normal double
# iff ``t >= -1021`` and finite iff ``t <= 1024``.
_LOWEST_EXPONENT = -1021
_HIGHEST_EXPONENT = 1024
# At the working scale (largest length and mass in [1/2, 1)) every term of a
# moment is a sum of positive products; an intermediate that underflowed
# there is off by at most a few 2^-1074 in absolute value, which is below
# eps of any working-scale moment above this bound.
_SAFE_UNIT = 2.0**-960
_SMALLEST_NORMAL = float(np.finfo(float).tiny)


def _decimal(value, exponent=0):
    """``value * 2**exponent`` in decimal (3 digits), even beyond the doubles."""
    if value == 0.0:
        return "0"
    mantissa, power = math.frexp(abs(value))
    log = math.log10(mantissa) + (power + exponent) * math.log10(2.0)
    tens = math.floor(log)
    digits = 10.0 ** (log - tens)
    if digits >= 9.995:  # rounds up to 10.0
        digits, tens = 1.0, tens + 1
    sign = "-" if value < 0.0 else ""
    return f"{sign}{digits:.3g}e{tens:+03d}"


def _binary_exponent(value):
    """``e`` with ``value * 2**-e`` in [1/2, 1) (0 for a zero)."""
    return math.frexp(value)[1]


def _scaled_square_sum(p, q):
    """``p^2 + q^2`` as ``(s, e)`` with ``s * 2**e`` the sum, free of under/overflow.

    Both lengths are scaled by the exact power of two that brings the larger
    into [1/2, 1), so ``s`` is the correctly ordered ``fl(p*p + q*q)`` of the
    scaled lengths: bit for bit the plain formula wherever that is normal.
    """
    k = _binary_exponent(max(p, q))
    p, q = math.ldexp(p, -k), math.ldexp(q, -k)
    return p * p + q * q, 2 * k


def _at_scale(values, exponents, what, labels, unit="", small="", large=""):
    """``values[k] * 2**exponents[k]`` exactly, refusing what no normal double holds.

    Parameters
    ----------
    values : sequence of float
        Moments at the working scale (normal doubles, or 0 for a degenerate
        body, passed on as 0 for :class:`Body` to refuse).
    exponents : int or sequence of int
        Binary exponents of the scale factors.
    what : str
        The body, for the messages.
    labels : sequence of str
        Names of the moments.
    unit : str
        Unit of the moments, for the messages.
    small, large : str
        Advice when a moment underflows / overflows.

    Returns
    -------
    tuple of float
        The moments at the caller's scale, each a normal double.

    Raises
    ------
    NonPhysicalBodyError
        A moment beyond the largest double (overflow), or below the smallest
        normal double 2.2e-308 (underflow: it would keep fewer than 53 bits).
    """
    if isinstance(exponents, (int, np.integer)):
        exponents = [int(exponents)] * len(values)
    unit = f" {unit}" if unit else ""
    tops = [
        (value, exponent, label)
        for value, exponent, label in zip(values, exponents, labels)
        if value > 0.0
    ]
    # the most extreme moment is the one named
    tops.sort(key=lambda top: (_binary_exponent(top[0]) + top[1], math.frexp(top[0])[0]))
    for value, exponent, label in reversed(tops):
        if _binary_exponent(value) + exponent > _HIGHEST_EXPONENT:
            raise NonPhysicalBodyError(
                f"the {what} has {label} = {_decimal(value, exponent)}{unit}: it overflows "
                f"a double (above 1.8e+308){'; ' + large if large else ''}"
            )
    for value, exponent, label in tops:
        if _binary_exponent(value) + exponent < _LOWEST_EXPONENT:
            raise NonPhysicalBodyError(
                f"the {what} has {label} = {_decimal(value, exponent)}{unit}: it underflows "
                "below the smallest normal double (2.2e-308) and would lose precision"
                f"{'; ' + small if small else ''}"
            )
    return tuple(
        math.ldexp(value, exponent) if value > 0.0 else float(value)
        for value, exponent in zip(values, exponents)
    )


def _refuse_below_normal(label, value):
    """Refuse a subnormal input whose imprecision would scale every moment."""
    if 0.0 < abs(value) < _SMALLEST_NORMAL:
        raise NonPhysicalBodyError(
            f"{label} {value!r} is below the smallest normal double (2.2e-308) and "
            "would be stored with reduced precision; give it in larger units"
        )


def _real_number(label, value):
    """One real number (a Python float): text, booleans, complex numbers,
    ``None``, arrays of several numbers and integers beyond a double are
    refused with an :class:`~orbits.OrbitsError` naming ``label``."""
    return real_scalar(label, value, NonPhysicalBodyError)


def _positive_lengths(what, normal=False, **values):
    """The values, checked finite and positive (named in the error).

    With ``normal``, a subnormal value (below 2.2e-308, stored with fewer
    than 53 bits) is refused too: it would scale every moment.
    """
    checked = []
    for label, value in values.items():
        number = _real_number(f"{what} {label}", value)
        if not (math.isfinite(number) and number > 0.0):
            raise NonPhysicalBodyError(
                f"{what} {label} must be a finite positive number, got {value!r}"
            )
        if normal:
            _refuse_below_normal(f"{what} {label}", number)
        checked.append(number)
    return tuple(checked)


def _non_negative_lengths(what, **values):
    """The values, checked finite and ``>= 0`` (named in the error)."""
    checked = []
    for label, value in values.items():
        number = _real_number(f"{what} {label}", value)
        if not (math.isfinite(number) and number >= 0.0):
            raise NonPhysicalBodyError(f"{what} {label} must be finite and >= 0, got {value!r}")
        checked.append(number)
    return tuple(checked)


def _positive_mass(value, label="mass"):
    """A finite, positive, normal mass (or density); subnormal values are refused."""
    number = _real_number(label, value)
    if not (math.isfinite(number) and number > 0.0):
        raise NonPhysicalBodyError(f"{label} must be a finite positive number, got {value!r}")
    _refuse_below_normal(label, number)
    return number


def _check_defect(defect):
    if not isinstance(defect, str) or defect not in ("error", "flatten"):
        raise InputError(f"defect must be 'error' or 'flatten', got {defect!r}")


_SMALL_LENGTHS = "give the lengths or the mass in smaller units (larger numbers)"
_LARGE_LENGTHS = "give the lengths or the mass in larger units (smaller numbers)"


def cylinder_moments(radius, length, mass=1.0, *, radius_y=None):
    """Moments ``(I_x, I_y, I_z)`` of a uniform solid cylinder along z.

    Cross-section semi-axes ``radius`` (x) and ``radius_y`` (y, default
    ``radius``): ``I_x = m (b^2/4 + L^2/12)``, ``I_y = m (a^2/4 + L^2/12)``,
    ``I_z = m (a^2 + b^2)/4``.  Not validated as a :class:`Body` (a circular
    cylinder is a symmetric top).

    Lengths in m and the mass in kg give kg m^2.  Each moment is computed
    with its lengths and the mass scaled by exact powers of two, so the
    result does not depend on the scale (bit for bit the plain formula
    wherever that is free of underflow and overflow).

    Raises
    ------
    NonPhysicalBodyError
        A length or the mass not finite and positive, a subnormal mass, or a
        moment that overflows a double or underflows below the smallest
        normal double (2.2e-308).
    """
    a, length = _positive_lengths("cylinder", radius=radius, length=length)
    b = a if radius_y is None else _positive_lengths("cylinder", radius_y=radius_y)[0]
    mass = _positive_mass(mass)
    m_exp = _binary_exponent(mass)
    m = math.ldexp(mass, -m_exp)
    values, exponents = [], []
    for radius_across in (b, a):  # I_x, I_y
        k = _binary_exponent(max(radius_across, length))
        r, ell = math.ldexp(radius_across, -k), math.ldexp(length, -k)
        values.append(m * (r * r / 4.0 + ell * ell / 12.0))
        exponents.append(m_exp + 2 * k)
    square_sum, k = _scaled_square_sum(a, b)
    values.append(m * square_sum / 4.0)
    exponents.append(m_exp + k)
    return _at_scale(
        values,
        exponents,
        "cylinder",
        ("I_x", "I_y", "I_z"),
        small=_SMALL_LENGTHS,
        large=_LARGE_LENGTHS,
    )


# The region of physical asymmetric bodies in the paper's I1-I2 plane
# (|I| = 1, I1 < I2 < I3 <= I1 + I2), Fig. 2: bounded by the prolate curve
# I2 = sqrt((1 - I1^2)/2), the oblate line I2 = I1 and the flat curve
# I2 = (sqrt(2 - 3 I1^2) - I1)/2; corners rod (0, 1/sqrt2), disk
# (1/sqrt6, 1/sqrt6) and sphere (1/sqrt3, 1/sqrt3).
REGION_BOX = ((0.0, 1.0 / math.sqrt(3.0)), (1.0 / math.sqrt(6.0), 1.0 / math.sqrt(2.0)))


def region_moments(i1, i2):
    """Unit-norm moments ``(I1, I2, I3)`` and a mask of the physical ones.

    Inside means ``0 < I1 < I2 < I3`` and ``I3 <= I1 + I2`` (flat bodies
    included, symmetric tops excluded).
    """
    i1 = np.asarray(i1, dtype=float)
    i2 = np.asarray(i2, dtype=float)
    rest = 1.0 - i1 * i1 - i2 * i2
    i3 = np.sqrt(np.clip(rest, 0.0, None))
    inside = (
        (rest > 0.0) & (i1 > 0.0) & (i1 < i2) & (i2 < i3) & (i3 <= (i1 + i2) * (1.0 + FLAT_SLACK))
    )
    return np.stack([i1, i2, i3], axis=-1), inside


def region_grid(resolution):
    """Bodies on an N x N grid (cell centres) over the region's bounding box.

    Parameters
    ----------
    resolution : int
        N, the cells along each side of the box (``>= 2``); about 0.39 N^2
        of the cell centres lie inside the region.

    Returns
    -------
    ndarray, shape (n, 3)
        Unit-norm moments (``|I| = 1``, the paper's I1-I2 plane), the grid
        points inside the region, in row-major order of (I1, I2).

    Raises
    ------
    InputError
        ``resolution`` not an integer >= 2, or a grid larger than half the
        machine's memory (:func:`orbits.limits.check_resolution`).
    """
    from .core import region

    resolution = check_resolution(resolution)
    (lo1, hi1), (lo2, hi2) = REGION_BOX
    box = (resolution, lo1, hi1, lo2, hi2, FLAT_SLACK)
    # the compiled twin of region_moments on the meshgrid of cell
    # centres (the same bits, row by row; orbits.core.region)
    counts = np.empty(resolution, dtype=np.int64)
    region.row_counts(*box, counts)
    starts = np.zeros(resolution, dtype=np.int64)
    np.cumsum(counts[:-1], out=starts[1:])
    moments = np.empty((int(counts.sum()), 3))
    region.fill_rows(*box, starts, moments)
    return moments


# Halton draws (about 2.6 per body kept), moments and masks, per body
_BYTES_PER_SAMPLE = 400


def region_sample(count):
    """``count`` bodies spread evenly over the region (deterministic).

    A Halton sequence (bases 2 and 3) over the bounding box, keeping the
    points inside the region until there are ``count`` of them.

    Parameters
    ----------
    count : int
        Bodies wanted, ``>= 1``.

    Returns
    -------
    ndarray, shape (count, 3)
        Unit-norm moments (``|I| = 1``), in the order drawn.

    Raises
    ------
    InputError
        ``count`` not an integer >= 1, or more bodies than half the
        machine's memory holds.
    """
    from scipy.stats import qmc

    count = integer("count", count, minimum=1)
    if count * _BYTES_PER_SAMPLE > memory_budget():
        raise InputError(
            f"region_sample({count}) would need about "
            f"{format_bytes(count * _BYTES_PER_SAMPLE)} of memory, more than the "
            f"{format_bytes(memory_budget())} allowed (half of this machine's)"
        )
    (lo1, hi1), (lo2, hi2) = REGION_BOX
    sampler = qmc.Halton(d=2, scramble=False)
    sampler.fast_forward(1)  # skip the corner (0, 0)
    kept = []
    total = 0
    while total < count:
        points = sampler.random(max(64, 4 * (count - total)))
        moments, inside = region_moments(
            lo1 + points[:, 0] * (hi1 - lo1), lo2 + points[:, 1] * (hi2 - lo2)
        )
        kept.append(moments[inside])
        total += int(inside.sum())
    return np.concatenate(kept)[:count]


# --------------------------------------------------------------- separatrix
@size_aware
def critical_angle(body_or_moments, phi=0.0):
    """Polar angle ``theta_c`` of omega0 on the separatrix ``M^2 = 2 E I2``.

    ``tan(theta_c) = sqrt(I3 (I3 - I2) / (I1 (I2 - I1) cos^2 phi))``.  This is
    the paper's ``theta_crit = arccot(sqrt(beta))`` with the erratum in
    eqn:beta corrected: ``beta = I1 (I2-I1) / (I3 (I3-I2))``.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (..., 3)
    phi : float or array_like
        Azimuth of omega0 from the I1 axis, radians.

    Returns
    -------
    float or ndarray
        Radians in ``(0, pi/2]``; broadcast over bodies and ``phi``.

    Raises
    ------
    NonPhysicalBodyError, SymmetricTopError
        Invalid moments.
    AngleError
        ``phi`` not finite.

    Notes
    -----
    For :math:`\\boldsymbol\\omega_0 = (\\sin\\theta\\cos\\phi, \\sin\\theta\\sin\\phi,
    \\cos\\theta)`, :math:`M^2 - 2EI_2 = I_3(I_3-I_2)\\cos^2\\theta
    - I_1(I_2-I_1)\\cos^2\\phi\\,\\sin^2\\theta`, which vanishes at

    .. math::

        \\tan\\theta_c = \\sqrt{\\frac{I_3(I_3-I_2)}{I_1(I_2-I_1)\\cos^2\\phi}} .

    For :math:`\\phi = 0` this is the paper's Eq. (27),
    :math:`\\theta_\\text{crit} = \\cot^{-1}\\sqrt\\beta`, with Eq. (25)
    corrected to :math:`\\beta = I_1(I_2-I_1)/(I_3(I_3-I_2))` (erratum 1).
    """
    from .core import phase as _kernels

    moments, _ = unit_moments(body_or_moments)
    phi = finite_array("phi", phi, AngleError)
    shape = broadcast([("moments", moments.shape[:-1]), ("phi", phi.shape)])
    out = np.empty(shape)
    _kernels.critical_angle_many(
        *(flat_broadcast(moments[..., k], shape) for k in range(3)),
        flat_broadcast(phi, shape),
        out.reshape(-1),
    )
    return float(out) if out.ndim == 0 else out


PRESETS = {
    "t-handle": lambda: Body.t_handle(8.0, 4.0, 1.0, name="t-handle"),
    "fig6": lambda: Body((0.26, 0.55, 0.793662), name="fig6"),
}
