"""Closed orbits: the initial spins whose total phase is a whole number of turns.

On an orbit with ``Delta alpha = 2 pi p / q`` the body is back at its
starting orientation after q periods, and the herpolhode closes.  With the
paper's conventions (phi = 0, ``|omega0| = 1``) every such spin is a polar
angle ``theta`` in (0, pi/2) on one of the two branches; near the critical
angle they accumulate geometrically, so each root is stored as its offset
``dtheta = theta - theta_crit`` to full relative precision.
"""

from collections import namedtuple
from fractions import Fraction

import numpy as np

from ._args import integer, real_array, warn
from .bodies import Body, canonical_moments, unit_moments
from .cells import numbers_label
from .core import search as _kernels
from .device import check_device, cuda_kernels, run_cuda
from .errors import InputError
from .limits import check_search_bounds, format_bytes, memory_budget, plural
from .phases import phases_of_unit_moments
from .threads import threads_for

#: The catalog's columns, in order: name -> (unit, meaning).  The one
#: definition of the schema: :data:`CATALOG_COLUMNS` is its keys, and the
#: documentation's schema table is generated from it.  Units are those of
#: the normalised body (``|I| = 1``, ``|omega0| = 1``): a value times the
#: unit's |I| (kg m^2) and |omega0| (rad/s) is the SI value (J, J s, s);
#: meanings are reST.
CATALOG_SCHEMA = {
    "body": ("", "the body's name (``fig6``, ``t-handle``, a ``--bodies`` name, or the moments)"),
    "I1": ("|I|", r"smallest principal moment, normalised to :math:`|\mathbf I| = 1`"),
    "I2": ("|I|", r"intermediate principal moment, normalised to :math:`|\mathbf I| = 1`"),
    "I3": ("|I|", r"largest principal moment, normalised to :math:`|\mathbf I| = 1`"),
    "theta_crit": ("rad", r"critical angle :math:`\theta_c`, where :math:`M^2 = 2EI_2` (Eq. 27)"),
    "branch": (
        "",
        r"``SAM`` (:math:`\theta < \theta_c`, :math:`\mathbf M` circles the "
        r":math:`I_3` axis) or ``LAM`` (:math:`\theta > \theta_c`, it circles :math:`I_1`)",
    ),
    "n": (
        "",
        r"the multiple: :math:`\Delta\alpha = 2\pi n/q` (for :math:`q > 1`, the numerator p)",
    ),
    "q": (
        "",
        "number of periods after which the body is back at its start (1 for integer orbits)",
    ),
    "theta": (
        "rad",
        r"polar angle of :math:`\boldsymbol\omega_0` from the :math:`I_3` axis "
        r"(:math:`\phi = 0`): "
        r":math:`\boldsymbol\omega_0 = (\sin\theta, 0, \cos\theta)` (Eq. 23)",
    ),
    "dtheta": (
        "rad",
        r":math:`\theta - \theta_c` to full relative precision (near :math:`\theta_c`, "
        r"``theta`` rounds to :math:`\theta_c`; use this)",
    ),
    "total_phase": (
        "rad",
        r"total phase :math:`\Delta\alpha` (Eq. 20), :math:`\approx 2\pi n/q`",
    ),
    "dynamic_phase": ("rad", "dynamic phase :math:`2ET/M`"),
    "geometric_phase": (
        "rad",
        r"geometric phase :math:`\Omega = 2ET/M - \Delta\alpha` (Eq. 1), the signed solid angle "
        "of the polhode, from its own closed form (not the difference)",
    ),
    "period": (
        "1/|ω₀|",
        r"period :math:`T` of :math:`\boldsymbol\omega` in the body (Eq. 16a), "
        r"in units of :math:`1/|\boldsymbol\omega_0|`",
    ),
    "energy": (
        "|I| |ω₀|²",
        r":math:`E = \tfrac12\boldsymbol\omega_0\cdot\mathbf I\boldsymbol\omega_0` (Eq. 11)",
    ),
    "momentum": ("|I| |ω₀|", r":math:`M = |\mathbf I\boldsymbol\omega_0|` (Eq. 10)"),
    "D": (
        "|I|",
        ":math:`M^2/(2E)`, the orbit's label independent of the spin rate: "
        r":math:`I_1 \le D \le I_3`, :math:`D > I_2` on SAM, :math:`D < I_2` on LAM",
    ),
    "m": (
        "",
        r"elliptic parameter :math:`k^2` of Eq. (16b) "
        r"(indices :math:`1 \leftrightarrow 3` on LAM), in :math:`(0, 1]`: "
        "it rounds to 1.0 when :math:`1 - m < 1.1\\cdot 10^{-16}`, where ``dtheta`` labels "
        "the orbit",
    ),
    "residual": (
        "rad",
        r":math:`\Delta\alpha - 2\pi n/q`, each within :math:`10^{-10}\cdot 2\pi n/q`",
    ),
    "closes_after": (
        "",
        "periods after which the herpolhode closes, a fraction: ``1/2`` for odd n "
        "(q = 1), ``q/2`` when p and q are both odd, else ``q``",
    ),
}
CATALOG_COLUMNS = tuple(CATALOG_SCHEMA)
# every root must satisfy |Delta alpha - 2 pi p/q| <= RESIDUAL_TOLERANCE * 2 pi p/q
RESIDUAL_TOLERANCE = 1e-10


class UnresolvedOrbitsWarning(UserWarning):
    """Closed orbits exist but lie closer to the separatrix than a double can hold."""


def phase_levels(n_max, q_max=1):
    """The target phases ``2 pi p / q``, ascending.

    All fractions ``p/q`` in lowest terms with ``1 <= q <= q_max`` and
    ``0 < p/q <= n_max``.

    Parameters
    ----------
    n_max : int
        Largest multiple of 2 pi, ``>= 1``.
    q_max : int
        Largest denominator (periods after which an orbit closes), ``>= 1``;
        1 gives the whole multiples ``2 pi n`` only.

    Returns
    -------
    p, q : ndarray of int
    values : ndarray of float
        ``2 pi p / q``.

    Raises
    ------
    InputError
        ``n_max`` or ``q_max`` not an integer >= 1 (``ArgumentTypeError`` for
        a wrong type), or so many levels that building them would exceed the
        machine (:func:`orbits.limits.check_search_bounds`).
    """
    n_max = _count("n_max", n_max)
    q_max = _count("q_max", q_max)
    check_search_bounds(n_max, q_max, 0, "the phase levels")
    fractions = sorted(
        {Fraction(p, q) for q in range(1, q_max + 1) for p in range(1, n_max * q + 1)}
    )
    p = np.array([f.numerator for f in fractions], dtype=np.int64)
    q = np.array([f.denominator for f in fractions], dtype=np.int64)
    return p, q, 2.0 * np.pi * p / q


def _count(name, value):
    return integer(name, value, minimum=1)


def _label(body, unit, exponent):
    """The body's name, or ``I=(I1, I2, I3)``: its moments as given (sorted,
    at their own scale; see :func:`orbits.cells.numbers_label`)."""
    if isinstance(body, Body):
        if body.name:
            return str(body.name)
        return numbers_label("I=", body.moments)
    return numbers_label("I=", np.ldexp(unit, exponent))


TWO_PI = 2.0 * np.pi


def searched(p, q):
    """Mask of the levels ``2 pi p/q`` that can have roots: ``p > q``.

    ``Delta alpha > 2 pi`` for every spin of every physical body (the limits
    eqn:alphamin1 and eqn:alphamin2 are >= 2 pi by the triangle
    inequalities, and the minimum lies at an end), with equality only in the
    limit theta -> 0 on the flat edge ``I3 = I1 + I2``.  So ``p/q <= 1`` has
    no closed orbit, and is not searched: near theta = 0 on a flat body
    rounding alone could put the computed phase a few ulp below 2 pi.
    """
    return np.asarray(p) > np.asarray(q)


def find_roots_at(moments, p, q, values):
    """:func:`find_roots` over the searchable levels; level indices into ``values``."""
    keep = np.flatnonzero(searched(p, q))
    branch, level, offset, info = find_roots(moments, np.ascontiguousarray(values[keep]))
    return branch, keep[level], offset, info


def find_roots(moments, levels):
    """Kernel call for one body; returns (branch, level index, dtheta, info)."""
    capacity = 4 * levels.size + 16
    info = np.empty(_kernels.INFO_SIZE)
    while True:
        branch = np.empty(capacity, dtype=np.int8)
        level = np.empty(capacity, dtype=np.int64)
        offset = np.empty(capacity)
        count = _kernels.search_body_newton(
            moments[0], moments[1], moments[2], levels, branch, level, offset, info
        )
        if count == _kernels.NEEDS_BRACKETING:  # rare: compiled only when needed
            count = _kernels.search_body(
                moments[0], moments[1], moments[2], levels, branch, level, offset, info
            )
        if count >= 0:
            return branch[:count], level[:count], offset[:count], info
        capacity *= 4


SearchRows = namedtuple("SearchRows", ["branch", "level", "offset", "counts", "info"])
SearchRows.__doc__ = """Per-body roots of :func:`search_bodies` (row ``b`` is body ``b``).

branch : ndarray (n, capacity) int8
    +1 SAM, -1 LAM, in ``[b, :counts[b]]``.
level : ndarray (n, capacity) int64
    Index into ``levels`` of each root.
offset : ndarray (n, capacity) float64
    ``dtheta`` of each root (radians, phi = 0, ``|omega0| = 1``).
counts : ndarray (n,) int64
    Roots of body ``b``, or -1 when its row was too short (search that body
    again with more room, e.g. :func:`orbits.core.search.search_body`).
info : ndarray (n, INFO_SIZE) float64
    Per body, the ``info`` of :func:`orbits.core.search.search_body`.
"""


def search_bodies(moments, levels, *, capacity=None, device="cpu"):
    """Every root of ``Delta alpha = levels[j]`` for many bodies: the survey's search.

    The arrays are those that :func:`orbits.core.search.search_many` fills,
    on the CPU (all of numba's threads) or, with ``device="cuda"``, on an
    NVIDIA GPU (one thread per body, the same scalar search code,
    :func:`orbits.core.search.search_body_with`).  The roots agree between
    the devices; on hardware the last bits may differ (fused multiply-adds):
    on an NVIDIA H200 the root counts were equal and ``dtheta`` within
    3.9e-13 relative over 61,625 bodies (n <= 30).

    Parameters
    ----------
    moments : array_like (n, 3) float64
        Principal moments per body, ascending in each row, any positive
        scale of doubles (the survey passes :func:`orbits.bodies.unit_moments`
        rows).  Each row is brought to the canonical form of
        :func:`orbits.bodies.canonical_moments` (an exact power-of-two
        scaling, a body within rounding of the flat edge moved onto it)
        before the search, so the roots do not depend on the scale.
    levels : array_like (m,) float64
        Target total phases ``2 pi p/q``, ascending, finite (e.g.
        :func:`phase_levels` masked by :func:`searched`).
    capacity : int, optional
        Roots per body row; default ``2 m + 8`` (the survey's).
    device : {"cpu", "cuda"}

    Returns
    -------
    SearchRows
        ``(branch, level, offset, counts, info)``, see :class:`SearchRows`;
        a body's SAM roots come first, then its LAM roots, each branch by
        ascending level (by monotone piece, then level, where the rare
        bracketing search ran), as :func:`orbits.core.search.search_many`.
        The rows are not sorted by ``dtheta``
        (:func:`orbits.core.rows.flat_rows` does that).

    Raises
    ------
    InputError
        Shapes, order or values not as above (levels positive, each once, in
        ascending order), or a ``capacity`` whose rows would exceed half of
        this machine's memory.
    NonPhysicalBodyError
        A row with ``I3 > I1 + I2`` beyond rounding (no rigid body).
    DeviceError
        ``device="cuda"`` unavailable.
    """
    device = check_device(device)
    # text, booleans, complex numbers and None refused by name (as elsewhere)
    moments = np.ascontiguousarray(real_array("moments", moments), dtype=float)
    levels = np.ascontiguousarray(real_array("levels", levels), dtype=float)
    if moments.ndim != 2 or moments.shape[1] != 3:
        raise InputError(f"moments must have shape (n, 3), got {moments.shape}")
    if (
        levels.ndim != 1
        or not np.all(np.isfinite(levels))
        or np.any(levels <= 0.0)
        or np.any(np.diff(levels) <= 0)
    ):
        raise InputError(
            "levels must be a 1-d array of finite positive values in strictly ascending "
            "order (each target phase once)"
        )
    if not (
        np.all(np.isfinite(moments))
        and np.all(moments > 0)
        and np.all(np.diff(moments, axis=1) > 0)
    ):
        raise InputError("moments must be finite, positive and strictly ascending in each row")
    if moments.size:
        # scale-free and physical, as every other entry point: the kernels
        # assume the largest moment in [1/2, 1) (no underflow or overflow)
        moments = np.ascontiguousarray(canonical_moments(moments)[0])
    if capacity is None:
        capacity = 2 * levels.size + 8
    capacity = integer("capacity", capacity, minimum=1)
    count = moments.shape[0]
    # branch (1 byte), level and offset (8 each) per root slot
    need = count * capacity * 17
    if need > memory_budget():
        raise InputError(
            f"search_bodies with capacity={capacity} for {count} bodies would need about "
            f"{format_bytes(need)} of memory, more than the {format_bytes(memory_budget())} "
            "allowed (half of this machine's); give a smaller capacity or fewer bodies"
        )
    rows = SearchRows(
        np.empty((count, capacity), dtype=np.int8),
        np.empty((count, capacity), dtype=np.int64),
        np.empty((count, capacity)),
        np.empty(count, dtype=np.int64),
        np.empty((count, _kernels.INFO_SIZE)),
    )
    if device == "cuda":
        run_cuda(cuda_kernels().search_many, moments, levels, *rows)
    else:
        with threads_for(count, serial_below=2):
            _kernels.search_many(moments, levels, *rows)
    return rows


def closed_orbits(body, n_max=10, q_max=1):
    """Every closed orbit of a body up to ``n_max`` turns.

    Parameters
    ----------
    body : Body or array_like, shape (3,)
    n_max : int
        Largest multiple: orbits with ``Delta alpha = 2 pi p / q <= 2 pi n_max``.
    q_max : int
        Largest number of periods after which the orbit closes; 1 (default)
        gives the paper's integer multiples ``Delta alpha = 2 pi n``.

    Returns
    -------
    pandas.DataFrame
        One row per closed orbit, sorted by ``theta`` (i.e. by ``dtheta``),
        with the columns of :data:`CATALOG_COLUMNS` (see :data:`CATALOG_SCHEMA`
        and the documentation's catalog schema).  ``n`` is ``p``; ``q`` is 1 for integer orbits.
        ``attrs["unresolved"]`` counts the orbits left out (below), and
        ``attrs["unresolved_by_branch"]`` per branch (``{"SAM": n, "LAM":
        n}``); ``attrs["reach"]`` maps each branch to its phase at
        ``|dtheta| = 2.2e-308`` (radians): the levels above it are the ones
        left out;
        ``attrs["minimum_phase"]`` maps ``"SAM"`` and ``"LAM"`` to each
        branch's smallest phase and its ``dtheta``, as the search found
        them: the end of the branch wherever the phase decreased at every
        point tested (:func:`orbits.core.search.monotone_at_probes`), else
        the minimum of a full scan (:func:`minimum_phase` always scans).

    Raises
    ------
    NonPhysicalBodyError, SymmetricTopError
        Invalid moments.
    InputError
        ``n_max`` or ``q_max`` not an integer >= 1.

    Warns
    -----
    UnresolvedOrbitsWarning
        When some levels are reached only closer to the separatrix than
        ``|dtheta| = 2.2e-308`` (the smallest normal double): those orbits
        exist but cannot be stored, and are left out.

    Notes
    -----
    The search (see :mod:`orbits.core.search` and the documentation's
    Numerics page) first tests that ``Delta alpha`` falls monotonically
    through 14 fixed points of each branch (log-spaced from 1e-256 of its
    width to 0.95 of it); where it does, each level between the branch's
    end values has one root, placed by the separatrix expansion and
    refined by safeguarded Newton steps.  Only a branch that fails the test
    is scanned and split into pieces on which ``Delta alpha`` is monotone
    (a fallback no real body has needed: none of 699,266 audited bodies).
    The test is a sample, not a proof: a rise narrower than the spacing
    of its points could pass it.  Every root is checked:
    ``|Delta alpha - 2 pi p/q| <= 1e-10 * 2 pi p/q``.
    """
    n_max, q_max = _count("n_max", n_max), _count("q_max", q_max)
    check_search_bounds(n_max, q_max, 1, "this search")
    moments, exponent = unit_moments(body)
    if moments.shape != (3,):
        raise InputError("closed_orbits takes one body; use orbits.catalog.catalog for many")
    p, q, values = phase_levels(n_max, q_max)
    _, level, offset, info = find_roots_at(moments, p, q, values)
    per_branch = {
        "SAM": int(info[_kernels.INFO_UNREACHED_SAM]),
        "LAM": int(info[_kernels.INFO_UNREACHED_LAM]),
    }
    unreached = sum(per_branch.values())
    if unreached:
        left = [(name, count) for name, count in per_branch.items() if count]
        where = (
            f"on {left[0][0]}"
            if len(left) == 1
            else " and ".join(f"{count} on {name}" for name, count in left)
        )
        name = getattr(body, "name", None)
        warn(
            f"{f'{name}: ' if name else ''}"
            f"{plural(unreached, 'closed orbit')} ({where}) with 2 pi p/q <= 2 pi {n_max} "
            f"{'lies' if unreached == 1 else 'lie'} "
            "closer than |dtheta| = 2.2e-308 to the separatrix and cannot be "
            "stored in double precision; they are left out",
            UnresolvedOrbitsWarning,
        )
    order = np.argsort(offset, kind="stable")
    frame = catalog_rows(
        _label(body, moments, exponent), moments, level[order], offset[order], p, q, values
    )
    frame.attrs["unresolved"] = unreached
    frame.attrs["unresolved_by_branch"] = per_branch
    frame.attrs["reach"] = {
        "SAM": float(info[_kernels.INFO_TOP_SAM]),
        "LAM": float(info[_kernels.INFO_TOP_LAM]),
    }
    frame.attrs["minimum_phase"] = branch_minima(info)
    return frame


def closes_after(p, q):
    """Periods after which the herpolhode of a ``2 pi p/q`` orbit closes, as a fraction.

    Over half a period the motion repeats up to symmetries (derivation in
    docs/conventions.md, "Half-period closure"): the body-frame angular
    velocity is mirrored, ``omega(t + T/2) = D omega(t)`` with
    ``D = diag(-1, -1, 1)`` on SAM and ``diag(1, -1, -1)`` on LAM, and the
    orientation is ``R(t + T/2) = Rot(z, Delta alpha/2 + pi) R(t) D``, so
    the herpolhode turns by ``beta = pi (p + q)/q`` about M every half
    period.  It closes after the least h half periods with
    ``h (p + q) / (2 q)`` whole: ``q/2`` periods when p and q are both odd
    (``p + q`` even; ``q = 1``: the odd multiples close after ``T/2``), else
    ``q``.  The body itself is back at its start only after q periods.

    Parameters
    ----------
    p, q : int or array_like of int
        The orbit's ``Delta alpha = 2 pi p/q``, ``gcd(p, q) = 1``.

    Returns
    -------
    str or ndarray of str
        ``"1/2"``, ``"1"``, ``"3/2"``, ... (a :class:`fractions.Fraction`
        as text).
    """
    names, inverse, shape = _closes_after_codes(p, q)
    text = np.array(names, dtype=object)[inverse].reshape(shape)
    return str(text[()]) if text.ndim == 0 else text


def _closes_after_codes(p, q):
    """:func:`closes_after` as distinct texts and an index into them (and the shape)."""
    p_arr = np.asarray(p, dtype=np.int64)
    q_arr = np.asarray(q, dtype=np.int64)
    both_odd = (p_arr % 2 == 1) & (q_arr % 2 == 1)
    # few distinct (q, both odd) pairs: format each once (a catalog has ~1e6 rows)
    key, inverse = np.unique(2 * q_arr.ravel() + both_odd.ravel(), return_inverse=True)
    names = [str(Fraction(int(k // 2), 2 if k % 2 else 1)) for k in key]
    return names, inverse.reshape(-1), q_arr.shape


def _text_column(names, codes):
    """``names[codes]`` as a text column of the type ``astype(str)`` gives.

    Taking from the few distinct texts is ~20x faster than converting a
    categorical or object column (1.6 ms against 28 ms for 346,000 rows).
    """
    import pandas as pd

    return pd.Series(pd.Series(names, dtype=object).astype(str).array.take(codes))


def catalog_rows(body, moments, level, offset, p, q, levels):
    """Catalog rows (:data:`CATALOG_COLUMNS`) for roots of the search.

    Parameters
    ----------
    body : str, int or ndarray
        The ``body`` column: one label, or one id per root.
    moments : ndarray, shape (3,) or (n_roots, 3)
    level : ndarray of int
        Index of each root's level into ``p``, ``q``, ``levels``.
    offset : ndarray
        Each root's ``dtheta``.

    Raises
    ------
    RuntimeError
        A root misses its level by more than ``RESIDUAL_TOLERANCE`` (the
        search guarantees it does not: this would be a bug).
    """
    import pandas as pd

    # moments are canonical here (unit_moments): no second normalisation
    table = phases_of_unit_moments(moments, dtheta=offset)
    target = levels[level]
    residual = table["total_phase"].to_numpy() - target
    bad = np.abs(residual) > RESIDUAL_TOLERANCE * target
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise RuntimeError(f"root {offset[k]!r} misses its level {target[k]!r} by {residual[k]!r}")
    return pd.DataFrame(
        {
            "body": body,
            "I1": table["I1"],
            "I2": table["I2"],
            "I3": table["I3"],
            "theta_crit": table["theta_crit"],
            "branch": _text_column(
                list(table["branch"].cat.categories), table["branch"].cat.codes.to_numpy()
            ),
            "n": p[level],
            "q": q[level],
            "theta": table["theta"],
            "dtheta": offset,
            "total_phase": table["total_phase"],
            "dynamic_phase": table["dynamic_phase"],
            "geometric_phase": table["geometric_phase"],
            "period": table["period"],
            "energy": table["energy"],
            "momentum": table["momentum"],
            "D": table["D"],
            "m": table["m"],
            "residual": residual,
            "closes_after": _text_column(*_closes_after_codes(p[level], q[level])[:2]),
        },
        columns=list(CATALOG_COLUMNS),
        copy=False,  # one block per column: no consolidating copy
    )


def minimum_phase(body):
    """The smallest total phase over all spins of a body (phi = 0).

    Parameters
    ----------
    body : Body or array_like, shape (3,)
        The body, or its principal moments (any order, any scale).

    Returns
    -------
    value, dtheta : float
        The minimum of ``Delta alpha`` over both branches and the offset
        where it lies (``-theta_crit`` is theta = 0, ``pi/2 - theta_crit`` is
        theta = pi/2: the paper's conjecture is that it is always one of
        these ends).

    Notes
    -----
    Each branch is scanned (:func:`orbits.core.search.search_body_bracketing`:
    about 330 points in ``dtheta``, log-spaced towards the separatrix, and
    every interior extremum of the scan refined), so the minimum is found
    wherever it lies; the search for orbits assumes it at an end and only
    probes that (:func:`orbits.core.search.monotone_at_probes`).
    """
    moments, _ = unit_moments(body)
    if moments.shape != (3,):
        raise InputError("minimum_phase takes one body")
    levels = np.empty(0)
    info = np.empty(_kernels.INFO_SIZE)
    _kernels.search_body_bracketing(
        *moments, levels, np.empty(0, np.int8), np.empty(0, np.int64), np.empty(0), info
    )
    return min(branch_minima(info).values())


def branch_minima(info):
    """Each branch's smallest total phase, from a search's ``info``.

    Parameters
    ----------
    info : ndarray (INFO_SIZE,)
        As :func:`find_roots` (or :func:`orbits.core.search.search_body`)
        fills it.

    Returns
    -------
    dict
        ``{"SAM": (value, dtheta), "LAM": (value, dtheta)}``: the minimum
        (rad; raised to 2 pi at a branch's end, where only rounding puts it
        below) and the offset where it lies.
    """
    return {
        name: (_at_least_two_pi(info[low], info[at], info), float(info[at]))
        for name, low, at in (
            ("SAM", _kernels.INFO_MIN_SAM, _kernels.INFO_MIN_AT_SAM),
            ("LAM", _kernels.INFO_MIN_LAM, _kernels.INFO_MIN_AT_LAM),
        )
    }


def _at_least_two_pi(value, dtheta, info):
    """``max(value, 2 pi)`` for a minimum at an end of its branch, else ``value``.

    At the ends the phase is >= 2 pi for every physical body (eqns
    alphamin1/2 with the triangle inequalities); on the flat edge it is
    2 pi at theta -> 0, which rounding can miss by a few ulp from below.
    A minimum inside a branch (a counterexample to the paper's conjecture)
    is returned as found.
    """
    width = info[_kernels.INFO_WIDTH_SAM] if dtheta < 0.0 else info[_kernels.INFO_WIDTH_LAM]
    if abs(dtheta) != width:
        return float(value)
    return float(max(float(value), TWO_PI))
