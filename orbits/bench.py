"""``orbits bench``: our kernels and commands against named baselines.

Each row times one task two ways and reports the ratio (the baseline's
time over ours); its ``baseline`` says what it is compared with (the SciPy
route, ``import numpy``, the same command warm, the bracketing search it
replaced, a Python loop, one CPU or one numba thread, ``--columns all``, or
nothing) and its ``timed`` says what each figure is:

* ``phase``, ``motion*``, ``motion_rate`` and ``search``: best of several
  runs of each side (7, 5, 3, 20; the ``search`` baseline 3) after an
  untimed warm-up run, in this process (so numba compilation is excluded);
* ``search_scaling``: best of three runs of each thread count, taken in
  turns, after a warm-up on 64 bodies; ``survey_tables``: best of three
  passes of each thread count, taken in turns, after a warm-up pass;
* ``search_evaluations``, ``survey_threads``, ``survey_bytes`` and
  ``survey``: one timed run of each side after a warm-up, in this process
  (``survey``: one run of each format; its baseline is not run on every
  body: a loop over every k-th body of the grid, ``k = count // 500``
  (500 to 999 bodies, or all when fewer), is timed once and scaled to the
  whole grid);
* ``startup`` (medians), ``cold_compile`` (one cold and one warm run) and
  ``survey_scaling`` (best of several, in turns, after a grid-2 warm-up)
  time fresh processes; the children import this same package and get the
  thread count in effect (:func:`orbits.get_num_threads`) as ``--threads``;
* the GPU rows ``cuda_phase`` and ``cuda_search`` (``--device cuda``): the
  public call end to end with ``device="cuda"`` (copies included) against
  ``device="cpu"``, best of several after a warm-up; the kernel alone
  (inputs already on the GPU) is in the note only, not in the ratio.

Rows that compare results check that both sides agree (``agrees``, and
``agree`` or ``DISAGREE`` in the note): ``search_evaluations`` (the same
roots on every body, offsets within :data:`SEARCH_RTOL` relative),
``survey`` (the loop's orbit count of each sampled body equals the
survey's) and ``cuda_search`` (as ``search_evaluations``, GPU against
CPU); ``orbits bench`` exits 1 after the table when a row
disagrees (:func:`disagreements`).

With the under-load check (:func:`load_check`) each row's own task is timed
again beside a CPU-bound process and must slow down by at most
:data:`LOAD_LIMIT` (``orbits bench`` exits 1 when a row does not).  No test
ever asserts on these timings.
"""

import json
import math
import os
import platform
import sys
import time

import numba
import numpy as np
import scipy
from scipy import special

from .bodies import Body
from .errors import InputError, OrbitsError
from .limits import plural
from .phases import critical_angle, total_phase
from .threads import SERIAL_BELOW, get_num_threads


class BenchError(OrbitsError):
    """A benchmark that cannot run here: a child process failed, or the
    platform lacks what the row needs (the CLI: exit 2, one line)."""


def usable_cpus():
    """``(usable, total)``: the CPUs this process may run on, and the machine's.

    ``usable`` is ``len(os.sched_getaffinity(0))`` where the platform has it
    (under ``taskset -c 0`` that is 1 on any machine), else
    ``os.cpu_count()``; ``total`` is ``os.cpu_count()``.
    """
    total = os.cpu_count()
    try:
        usable = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        usable = total
    return usable, total


def best_time(function, repeats):
    """Smallest wall time of ``repeats`` calls (after one warm-up call)."""
    function()
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def scipy_total_phase(moments, theta):
    """eqn:GeometricPhase the obvious way: NumPy + SciPy, phi = 0.

    ``K = ellipk(m)``, ``Pi(n|m) = R_F(0, 1-m, 1) + n/3 R_J(0, 1-m, 1, 1-n)``
    (DLMF 19.25.2), with ``1 - m`` formed by subtraction as anyone would.
    """
    i1, i2, i3 = (np.sort(np.asarray(moments, float))[..., k] for k in range(3))
    s2, c2 = np.sin(theta) ** 2, np.cos(theta) ** 2
    two_e = i1 * s2 + i3 * c2
    m_sq = i1 * i1 * s2 + i3 * i3 * c2
    momentum = np.sqrt(m_sq)
    sam = m_sq > two_e * i2
    # eqn:TK and eqn:GeometricPhase, indices 1 <-> 3 in k and D on LAM
    k2 = np.where(
        sam,
        (i2 - i1) * (two_e * i3 - m_sq) / ((i3 - i2) * (m_sq - two_e * i1)),
        (i3 - i2) * (m_sq - two_e * i1) / ((i2 - i1) * (two_e * i3 - m_sq)),
    )
    rate = np.where(
        sam,
        np.sqrt((i3 - i2) * (m_sq - two_e * i1) / (i1 * i2 * i3)),
        np.sqrt((i2 - i1) * (two_e * i3 - m_sq) / (i1 * i2 * i3)),
    )
    n = np.where(
        sam,
        -i3 * (i2 - i1) / (i1 * (i3 - i2)),
        -i3 * (m_sq - two_e * i1) / (i1 * (two_e * i3 - m_sq)),
    )
    one_minus_m = 1.0 - k2
    big_k = special.ellipk(k2)
    big_pi = special.elliprf(0.0, one_minus_m, 1.0) + n / 3.0 * special.elliprj(
        0.0, one_minus_m, 1.0, 1.0 - n
    )
    period = 4.0 * big_k / rate
    return (
        momentum * period / i3
        + 4.0 * momentum * (i3 - i1) * big_pi / (i1 * i3 * rate)
        - np.where(sam, 2.0 * np.pi, 0.0)
    )


def _scalar_total_phase(moments, theta):
    """The scalar kernel path (one looping ``cel`` per angle), for comparison."""
    from .core.phase import total_phase_one_body_scalar

    out = np.empty(theta.size)
    status = np.empty(theta.size, dtype=np.int8)
    total_phase_one_body_scalar(*(float(v) for v in moments), 0.0, theta, False, out, status)
    return out


def bench_total_phase(points=1_000_000, repeats=7, seed=0):
    """Total phase of the Fig. 6 body at ``points`` random angles."""
    body = Body.preset("fig6")
    theta = np.random.default_rng(seed).uniform(0.0, 0.5 * np.pi, points)
    ours = best_time(lambda: total_phase(body, theta), repeats)
    scalar = best_time(lambda: _scalar_total_phase(body.moments, theta), repeats)
    theirs = best_time(lambda: scipy_total_phase(body.moments, theta), repeats)
    difference = np.abs(total_phase(body, theta) / scipy_total_phase(body.moments, theta) - 1)
    worst = int(np.argmax(difference))
    offset = float(theta[worst] - critical_angle(body))
    return {
        "_ours": (lambda: total_phase(body, theta), repeats),
        "task": f"total phase, {points:.0e} random theta (fig6 body)",
        "timed": f"best of {repeats} runs of each after a warm-up run, in this process",
        "ours_s": ours,
        "baseline": "NumPy + scipy.special ellipk/elliprf/elliprj",
        "baseline_s": theirs,
        "speedup": theirs / ours,
        "scalar_s": scalar,
        "note": f"scalar-cel kernel path {_seconds(scalar)} ({theirs / scalar:.1f}x); "
        f"max relative difference ours vs baseline {difference[worst]:.1e}, at "
        f"theta - theta_c = {offset:.1e} (next to theta_c the phase is "
        "ill-conditioned in theta)",
    }


def _herpolhode_by_integration(motion, times):
    """The obvious route: solve_ivp(DOP853, rtol 1e-12, dense output)."""
    from scipy.integrate import solve_ivp
    from scipy.spatial.transform import Rotation

    from .core.ode import euler_rhs

    inertia = motion.body.moments
    w0 = motion.omega0
    # start oriented with space z along M and phi = 0, like the exact motion
    momentum = inertia * w0
    theta0 = np.arctan2(np.hypot(momentum[0], momentum[1]), momentum[2])
    psi0 = np.arctan2(momentum[0], momentum[1])
    q0 = np.roll(Rotation.from_euler("ZXZ", [0.0, theta0, psi0]).as_quat(), 1)

    def rhs(t, y):
        dy = np.empty(7)
        euler_rhs(inertia, y, dy)
        return dy

    solution = solve_ivp(
        rhs,
        (0.0, times[-1]),
        np.concatenate([w0, q0]),
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        dense_output=True,
    )
    states = solution.sol(times)
    rotation = Rotation.from_quat(np.roll(states[3:].T, -1, axis=-1))
    return rotation.apply(states[:3].T)


def _herpolhode_direct(motion, times):
    """The herpolhode kernel without the even-grid block path."""
    from .core.grid import omega_space_on_grid
    from .threads import threads_for

    out = np.empty((times.size, 3))
    with threads_for(times.size):
        omega_space_on_grid(motion._orbit, times, False, out)
    return out


def bench_motion(points=2001, repeats=5, dtheta=None):
    """The herpolhode of one orbit: exact motion against solve_ivp.

    The fig6 body at theta = 0.9 (a moderate SAM orbit, m = 0.62), or at
    the offset ``dtheta`` from the separatrix.
    """
    from .motion import Motion, herpolhode

    body = Body.preset("fig6")
    theta = 0.9 if dtheta is None else None
    unit_body = Body(body.normalized_moments)
    motion = Motion.from_spin(unit_body, theta, dtheta=dtheta)
    if dtheta is not None:
        # the same double-precision spin for both methods
        motion = Motion.from_omega(unit_body, motion.omega0)
        theta = float(np.arctan2(motion.omega0[0], motion.omega0[2]))
    times = np.linspace(0.0, motion.period, points)
    ours = best_time(lambda: herpolhode(body, theta, points=points), repeats)
    theirs = best_time(lambda: _herpolhode_by_integration(motion, times), repeats)
    note = "accuracy vs mpmath: "
    try:
        import mpmath  # noqa: F401  (only whether it is there)
    except ImportError as error:
        if error.name != "mpmath":
            raise
        note += "n/a (install mpmath)"
    else:
        from .checks import exact_motion_mpmath

        sample = np.arange(0, points, max(1, points // 40))
        reference = exact_motion_mpmath(unit_body.moments, motion.omega0, times[sample])[2]
        err_ours = np.max(np.abs(herpolhode(body, theta, points=points)[1][sample] - reference))
        err_theirs = np.max(np.abs(_herpolhode_by_integration(motion, times)[sample] - reference))
        note += f"ours {err_ours:.1e}, solve_ivp {err_theirs:.1e} (max |omega| error)"
    rate = points / ours
    where = "theta 0.9" if dtheta is None else f"1 - m = {motion.one_minus_m:.0e}"
    direct = best_time(lambda: _herpolhode_direct(motion, times), repeats)
    note += f"; the direct path (one R_J per point) {_seconds(direct)}"
    return {
        "_ours": (lambda: herpolhode(body, theta, points=points), repeats),
        "task": f"herpolhode, {points} points, 1 period ({where})",
        "timed": f"best of {repeats} runs of each after a warm-up run, in this process",
        "ours_s": ours,
        "baseline": "solve_ivp DOP853 rtol 1e-12, dense output",
        "baseline_s": theirs,
        "speedup": theirs / ours,
        "note": f"{note}; exact motion {rate:.2e} points/s",
    }


def bench_motion_rate(points=1_000_000, repeats=3):
    """Throughput of the exact motion on a long grid (points per second)."""
    from .motion import Motion

    motion = Motion.from_spin(Body.preset("fig6"), 0.9)
    times = np.linspace(0.0, 10.0 * motion.period, points)
    ours = best_time(lambda: motion.state(times), repeats)
    return {
        "_ours": (lambda: motion.state(times), repeats),
        "task": f"exact motion, full state, {points:.0e} times",
        "timed": f"best of {repeats} runs after a warm-up run, in this process",
        "ours_s": ours,
        "baseline": "none (throughput row)",
        "baseline_s": None,
        "speedup": None,
        "note": f"{points / ours:.2e} points/s (omega, Euler angles, R, omega_space)",
    }


def _roots_by_scipy(body, n_max, points=2000):
    """The obvious route: scan theta, brentq on the SciPy-route phase.

    The grid is refined geometrically towards ``theta_c`` on each branch
    (offsets from 1e-13 to the axis, ``points`` of them), where the roots
    crowd; the roots' theta, sorted.
    """
    from scipy.optimize import brentq

    moments = body.moments
    theta_c = float(critical_angle(body))
    found = []
    for side, span in ((-1.0, theta_c), (1.0, 0.5 * np.pi - theta_c)):
        theta = np.sort(theta_c + side * np.geomspace(1e-13, span, points)[:-1])
        values = scipy_total_phase(moments, theta)
        for n in range(1, n_max + 1):
            level = 2.0 * np.pi * n
            signs = np.flatnonzero(np.diff(np.sign(values - level)) != 0)
            for k in signs:
                found.append(
                    brentq(
                        lambda t: float(scipy_total_phase(moments, np.array([t]))[0]) - level,
                        theta[k],
                        theta[k + 1],
                        xtol=1e-15,
                    )
                )
    return np.sort(np.asarray(found))


# the search row's orbits: at n <= 15 every root of the fig6 body is at least
# 2.2e-12 rad from theta_c, so a grid in theta can hold them all (at n <= 20
# one is 2.2e-16 away, below an ulp of theta_c; at n <= 50, 2.5e-40)
SEARCH_N_MAX = 15
# the roots' theta agree to 4.4e-16 rad (measured); the row's check allows
SEARCH_THETA_ATOL = 1e-13


def _search_counts(function, bodies, levels, keep=None):
    """Kernel time, phase evaluations and roots of a search over ``bodies``.

    With ``keep`` (a list), each body's roots are appended to it as
    ``(branch, level, offset)`` arrays sorted by branch, level and offset
    (``None`` for a body the kernel refused): copies made inside the timed
    loop, so the timed runs pass no ``keep``.
    """
    from .core import search as kernels

    capacity = 4 * levels.size + 16
    branch = np.empty(capacity, dtype=np.int8)
    level = np.empty(capacity, dtype=np.int64)
    offset = np.empty(capacity)
    info = np.empty(kernels.INFO_SIZE)
    evaluations = 0.0
    roots = 0
    start = time.perf_counter()
    for moments in bodies:
        found = function(moments[0], moments[1], moments[2], levels, branch, level, offset, info)
        roots += found
        evaluations += info[kernels.INFO_EVALUATIONS]
        if keep is not None:
            keep.append(sorted_roots(branch, level, offset, found))
    return time.perf_counter() - start, evaluations, roots


def sorted_roots(branch, level, offset, found):
    """One body's first ``found`` roots as ``(branch, level, offset)`` arrays
    sorted by branch, level and offset (copies), or None where ``found < 0``
    (the body was refused): what :func:`roots_agreement` compares."""
    if found < 0:
        return None
    order = np.lexsort((offset[:found], level[:found], branch[:found]))
    return branch[order], level[order], offset[order]


# two searches agree when they find the same roots (branch and level) on every
# body, each root's offset from theta_c within this relative difference
SEARCH_RTOL = 1e-10


def roots_agreement(ours, theirs, rtol=SEARCH_RTOL):
    """Compare two lists of per-body roots (as :func:`_search_counts` keeps them).

    Returns
    -------
    tuple of (int, float)
        How many bodies differ (a body refused by one side only, or another
        count, branch or level of root, or an offset further than ``rtol``
        relative), and the largest relative offset difference over the
        bodies whose roots match in count, branch and level.
    """
    differ, worst = 0, 0.0
    for a, b in zip(ours, theirs, strict=True):
        if a is None or b is None:
            differ += (a is None) != (b is None)
            continue
        if not (np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])):
            differ += 1
            continue
        if a[2].size:
            with np.errstate(divide="ignore", invalid="ignore"):
                gap = float(np.max(np.abs(a[2] / b[2] - 1.0)))
            if not gap <= rtol:  # NaN too
                differ += 1
            worst = max(worst, gap) if math.isfinite(gap) else math.inf
    return differ, worst


def _per_body(rows):
    """:class:`orbits.search.SearchRows` as :func:`roots_agreement` takes them."""
    return [
        sorted_roots(rows.branch[b], rows.level[b], rows.offset[b], int(found))
        for b, found in enumerate(rows.counts)
    ]


def _agreement(agrees, text):
    """The note's clause for a row's agreement check: ``agree`` or ``DISAGREE``."""
    return f"{'agree' if agrees else 'DISAGREE'}: {text}"


def bench_search(n_max=SEARCH_N_MAX, repeats=20):
    """Every closed orbit with n <= 15 on both branches of the fig6 body.

    Both arms find the same roots (checked: their count and each theta to
    :data:`SEARCH_THETA_ATOL`); at n <= 15 a theta grid can still hold every
    root (:data:`SEARCH_N_MAX`), beyond it only the offset from theta_c can.
    """
    from .core import search as kernels
    from .search import closed_orbits, find_roots, phase_levels

    body = Body.preset("fig6")
    ours = best_time(lambda: closed_orbits(body, n_max=n_max), repeats)
    levels = phase_levels(n_max)[2]
    kernel = best_time(lambda: find_roots(body.moments, levels), repeats)
    table = closed_orbits(body, n_max=n_max)
    roots = len(table)
    theirs = best_time(lambda: _roots_by_scipy(body, n_max), 3)
    found = _roots_by_scipy(body, n_max)
    ours_theta = np.sort(table["theta"].to_numpy())
    agrees = found.size == roots
    worst = float(np.max(np.abs(found - ours_theta), initial=0.0)) if agrees else np.inf
    agrees = agrees and worst <= SEARCH_THETA_ATOL
    _, new_evaluations, _ = _search_counts(kernels.search_body, [body.moments], levels)
    _, old_evaluations, _ = _search_counts(kernels.search_body_bracketing, [body.moments], levels)
    deepest = float(np.min(np.abs(table["dtheta"].to_numpy()), initial=np.inf))
    return {
        "_ours": (lambda: closed_orbits(body, n_max=n_max), repeats),
        "task": f"closed orbits n <= {n_max}, both branches (fig6)",
        "timed": f"ours best of {repeats} runs, the baseline best of 3, each after a "
        "warm-up run, in this process",
        "ours_s": ours,
        "baseline": "theta grid (2000 points, refined geometrically towards theta_c) "
        "+ scipy.optimize.brentq on the SciPy-route phase",
        "baseline_s": theirs,
        "speedup": theirs / ours,
        "agrees": agrees,
        "note": f"{roots} roots, the nearest {deepest:.1e} rad from theta_c "
        f"({kernel * 1e3:.2f} ms in the kernel, the rest is the DataFrame; "
        f"{new_evaluations / roots:.1f} phase evaluations per root, the bracketing "
        f"search {old_evaluations / roots:.1f}); "
        + _agreement(
            agrees,
            f"the baseline finds {found.size}"
            + (f", theta within {worst:.1e} rad" if found.size == roots else "")
            + "; beyond n = 15 the roots come closer to theta_c than a theta grid "
            "can hold (2.5e-40 rad at n = 50), where only the offset dtheta can",
        ),
    }


def bench_search_evaluations(resolution=60, n_max=10):
    """The Newton search against the bracketing search it replaced, kernel only."""
    from .bodies import region_grid
    from .core import search as kernels
    from .search import phase_levels

    bodies = region_grid(resolution)
    levels = phase_levels(n_max)[2]
    _search_counts(kernels.search_body, bodies[:2], levels)  # compile
    _search_counts(kernels.search_body_bracketing, bodies[:2], levels)
    ours, new_evaluations, roots = _search_counts(kernels.search_body, bodies, levels)
    theirs, old_evaluations, _ = _search_counts(kernels.search_body_bracketing, bodies, levels)
    # the agreement check: both searches once more, untimed, keeping the roots
    ours_roots, theirs_roots = [], []
    _search_counts(kernels.search_body, bodies, levels, ours_roots)
    _search_counts(kernels.search_body_bracketing, bodies, levels, theirs_roots)
    differ, worst = roots_agreement(ours_roots, theirs_roots)
    agrees = differ == 0
    return {
        "task": f"search kernel, {len(bodies)} bodies, n <= {n_max} (one thread)",
        "timed": "one run of each over all the bodies, after a warm-up on two bodies "
        "(kernels loaded), in this process",
        "ours_s": ours,
        "baseline": "the scan-and-bracket search (Brent) it replaced",
        "baseline_s": theirs,
        "speedup": theirs / ours,
        "evaluations_per_root": new_evaluations / roots,
        "baseline_evaluations_per_root": old_evaluations / roots,
        "agrees": agrees,
        "note": f"{roots} roots; phase evaluations per root {new_evaluations / roots:.2f} "
        f"vs {old_evaluations / roots:.2f} "
        f"({old_evaluations / new_evaluations:.1f}x fewer); "
        + _agreement(
            agrees,
            f"{len(bodies) - differ} of {len(bodies)} bodies have the same roots "
            f"(branch, level) in both, offsets within {SEARCH_RTOL:.0e} relative "
            f"(largest difference {worst:.1e}; both searches run again, untimed)",
        ),
    }


# the survey row's baseline loop runs on about this many bodies of the grid
SURVEY_SAMPLE = 500


def _ordinal(k):
    """``1st``, ``2nd``, ``3rd``, ``4th``, ..., ``11th``, ``21st``, ..."""
    suffix = "th" if k % 100 in (11, 12, 13) else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{suffix}"


def bench_survey(resolution=400, n_max=10, repeats=1):
    """Survey throughput end to end: minimum-phase map plus orbits with n <= 10.

    The default format (Parquet, pyarrow is a core dependency) and CSV, each
    through :class:`orbits.survey.Survey` as ``orbits survey`` runs it.
    """
    import shutil
    import tempfile

    from .bodies import region_grid
    from .search import closed_orbits
    from .survey import Survey

    grid = region_grid(resolution)
    count = len(grid)
    times = {}

    def survey_once(fmt, check=None):
        directory = tempfile.mkdtemp(prefix="orbits-bench-")
        try:
            Survey.grid(directory, resolution, n_max, fmt=fmt).run()
            if check is not None:
                return check(directory)
        finally:
            shutil.rmtree(directory, ignore_errors=True)

    for fmt in ("csv", "parquet"):
        times[fmt] = best_time(lambda fmt=fmt: survey_once(fmt), repeats)
    step = max(1, count // SURVEY_SAMPLE)
    picked = np.arange(0, count, step)
    sample = grid[picked]
    loop_counts = []

    def loop():
        # the same work as the survey's: each body's orbits and its minimum
        # phase as the search found it (minimum_phase would scan every branch
        # in full, more than the survey does)
        loop_counts.clear()
        for moments in sample:
            found = closed_orbits(moments, n_max=n_max)
            found.attrs["minimum_phase"]
            loop_counts.append(len(found))

    per_body = best_time(loop, 1) / len(sample)

    def survey_counts(directory):
        from .survey import read_table

        bodies = read_table(directory, "bodies")
        by_body = dict(zip(bodies["body"].to_numpy().tolist(), bodies["orbits"].to_numpy()))
        return [by_body.get(int(index), -1) for index in picked]

    # the agreement check: one more survey (untimed), its bodies table read
    # back; the loop's orbit count of each sampled body must be the survey's
    survey_side = survey_once("parquet", survey_counts)
    differ = sum(int(a) != int(b) for a, b in zip(survey_side, loop_counts, strict=True))
    agrees = differ == 0
    runs = "one run" if repeats == 1 else f"best of {repeats} runs"
    which = "every body" if step == 1 else f"every {_ordinal(step)} body"
    return {
        "_ours": (lambda: survey_once("parquet"), 1),
        "task": f"survey {count} bodies, n <= {n_max} (grid {resolution}), Parquet",
        "timed": f"ours {runs} of each format after a warm-up run; the baseline one "
        f"run over {len(sample)} sampled bodies after a warm-up run, scaled to "
        f"{count}; in this process",
        "ours_s": times["parquet"],
        "baseline": f"a Python loop of closed_orbits per body (its attrs hold the minimum phase), "
        f"extrapolated from {len(sample)} of the {count} bodies",
        "baseline_s": per_body * count,
        "speedup": per_body * count / times["parquet"],
        "bodies_per_s": count / times["parquet"],
        "baseline_sample": len(sample),
        "agrees": agrees,
        "note": f"{count / times['parquet']:.0f} bodies/s to Parquet (the default), "
        f"{count / times['csv']:.0f} bodies/s to CSV (end to end: search, "
        f"tables, atomic files, report); the baseline loop ran on {which} of the "
        f"grid ({len(sample)} bodies, {_seconds(per_body)} per body), scaled by "
        f"{count}/{len(sample)}; "
        + _agreement(
            agrees,
            f"{len(sample) - differ} of the {len(sample)} sampled bodies have as many "
            "orbits in the survey's bodies table (one more Parquet survey, untimed) "
            "as in the loop",
        ),
    }


def _child_env(extra=None):
    """The environment of a child process: ours, with this package's parent
    directory first on ``PYTHONPATH`` (the user's entries kept after it), so
    that the child imports this same ``orbits``; ``extra`` added."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ)
    before = env.get("PYTHONPATH")
    env["PYTHONPATH"] = root + (os.pathsep + before if before else "")
    env.update(extra or {})
    return env


def _shown(argv):
    """A child's command line as one would type it (``python`` for the interpreter)."""
    import shlex

    return shlex.join(["python" if a == sys.executable else str(a) for a in argv])


def _run_child(argv, env, stdout=None, **options):
    """Run one child process to its end; return its ``CompletedProcess``.

    Standard error is captured; a child that fails is :class:`BenchError`
    (one line: the exit status or signal, the command and the child's last
    line on stderr), and a child ended by Ctrl-C (which reaches the whole
    process group) is ``KeyboardInterrupt``.
    """
    import signal
    import subprocess

    done = subprocess.run(
        argv,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL if stdout is None else stdout,
        stderr=subprocess.PIPE,
        text=True,
        **options,
    )
    if done.returncode == 0:
        return done
    if done.returncode == -signal.SIGINT:
        raise KeyboardInterrupt
    if done.returncode > 0:
        why = f"exit {done.returncode}"
    else:
        try:
            why = f"killed by {signal.Signals(-done.returncode).name}"
        except ValueError:
            why = f"killed by signal {-done.returncode}"
    lines = [line.strip() for line in (done.stderr or "").splitlines() if line.strip()]
    last = f": {lines[-1][:300]}" if lines else ""
    raise BenchError(f"a benchmark's child process failed ({why}): {_shown(argv)}{last}")


def _fresh_interpreter(args, env=None):
    """Wall and CPU seconds of one ``python args`` run in a new process.

    ``env``: the child's environment (default :func:`_child_env`).  A child
    that fails is :class:`BenchError`.
    """
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    _run_child([sys.executable, *args], _child_env() if env is None else env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def uncompiled_modules():
    """This package's modules that every fresh process compiles from source.

    Python reads a module's bytecode from ``__pycache__`` when it is there
    and up to date, and otherwise compiles the source and writes it there,
    unless ``PYTHONDONTWRITEBYTECODE`` is set (inherited by every child
    process the benchmarks start).  With it set and no cached bytecode (an
    editable install on a machine that sets it), each fresh process
    compiles orbits' modules again: a fixed cost on one core that an
    installed package (whose bytecode pip wrote) does not pay.

    Returns
    -------
    tuple of (int, float)
        How many of the package's modules would be compiled by each fresh
        process, and the seconds compiling all of them takes here (both 0
        when bytecode is written or cached).
    """
    import importlib.util

    if not os.environ.get("PYTHONDONTWRITEBYTECODE"):
        return 0, 0.0
    root = os.path.dirname(os.path.abspath(__file__))
    missing = []
    for folder, _, names in os.walk(root):
        for name in names:
            if not name.endswith(".py"):
                continue
            source = os.path.join(folder, name)
            if not _bytecode_current(source, importlib.util):
                missing.append(source)
    start = time.perf_counter()
    for source in missing:
        with open(source, "rb") as handle:
            compile(handle.read(), source, "exec", dont_inherit=True)
    return len(missing), time.perf_counter() - start


def _bytecode_current(source, util):
    """Whether ``source`` has bytecode in ``__pycache__`` that Python would use.

    The header of a ``.pyc`` (PEP 552): this interpreter's magic number,
    then flags, then either a source hash (taken as current) or the
    source's modification time and size, which must match.
    """
    try:
        with open(util.cache_from_source(source), "rb") as handle:
            header = handle.read(16)
        status = os.stat(source)
    except (OSError, NotImplementedError):
        return False
    if len(header) < 16 or header[:4] != util.MAGIC_NUMBER:
        return False
    if int.from_bytes(header[4:8], "little") & 1:  # hash-based
        return True
    mtime = int.from_bytes(header[8:12], "little")
    size = int.from_bytes(header[12:16], "little")
    return mtime == int(status.st_mtime) & 0xFFFFFFFF and size == status.st_size & 0xFFFFFFFF


def _bytecode_note():
    """A note's clause when fresh processes compile orbits' modules (else '')."""
    count, seconds = uncompiled_modules()
    if not count:
        return ""
    return (
        f"; PYTHONDONTWRITEBYTECODE is set and {plural(count, 'module')} of orbits "
        f"have no cached bytecode: each fresh process compiles those it imports "
        f"(all of them: {seconds:.2f} s here), a start-up cost that an installed "
        "package does not pay"
    )


def _median_wall(args, repeats):
    return float(np.median([_fresh_interpreter(args)[0] for _ in range(repeats)]))


def bench_startup(repeats=7):
    """Start-up: ``orbits --help`` and ``import orbits`` against ``import numpy``.

    Each is a fresh interpreter: one untimed run of each command first (the
    files in the operating system's cache), then the median of ``repeats``;
    the target is within 4x of ``python -c "import numpy"``.
    """
    commands = (["-c", "import numpy"], ["-c", "import orbits"], ["-m", "orbits", "--help"])
    for args in commands:
        _fresh_interpreter(args)  # warm-up, untimed
    numpy_s, import_s, help_s = (_median_wall(args, repeats) for args in commands)
    return {
        "task": "start-up: python -m orbits --help (fresh process)",
        "timed": f"median of {repeats} fresh processes of each command, after one "
        "untimed run of each",
        "ours_s": help_s,
        "baseline": 'python -c "import numpy" (fresh process)',
        "baseline_s": numpy_s,
        "speedup": numpy_s / help_s,
        "note": f"--help takes {help_s / numpy_s:.1f}x and import orbits "
        f"{import_s / numpy_s:.1f}x the time of import numpy (target <= 4x); "
        f"medians of {repeats} runs" + _bytecode_note(),
    }


def bench_cold_compile():
    """A first ``orbits catalog --preset fig6 --n-max 30`` with an empty numba cache.

    The cache goes to a fresh ``NUMBA_CACHE_DIR`` (the package's own cache is
    not touched), so every kernel the command needs is compiled; the same
    command is then run again warm (kernels loaded from that cache).  One
    fresh process each (the cold run is the point: no warm-up), with
    ``--threads`` the count in effect here.  CPU seconds are those of the
    child process: on a shared machine they are what the command costs, the
    wall time is what it waited.
    """
    import shutil
    import tempfile

    threads = get_num_threads()
    cache = tempfile.mkdtemp(prefix="orbits-bench-cache-")
    out = os.path.join(cache, "fig6.csv")
    env = _child_env({"NUMBA_CACHE_DIR": cache})
    args = ["-m", "orbits", "--threads", str(threads), "catalog", "--preset", "fig6"]
    args += ["--n-max", "30", "--out", out]
    try:
        cold, cold_cpu = _fresh_interpreter(args, env)
        warm, warm_cpu = _fresh_interpreter(args, env)
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    return {
        "task": "cold compile: orbits catalog --preset fig6 --n-max 30",
        "timed": "one fresh process with an empty numba cache, then one more with "
        "that cache filled",
        "ours_s": cold,
        "baseline": "the same command warm (kernels from the numba cache, fresh process)",
        "baseline_s": warm,
        "speedup": warm / cold,
        "threads": threads,
        "note": f"cold {cold:.1f} s wall / {cold_cpu:.1f} s CPU (target <= 8 s), "
        f"warm {warm:.1f} s wall / {warm_cpu:.1f} s CPU; --threads {threads}",
    }


def _survey_argv(resolution, n_max, threads, out, extra=()):
    """The child's ``orbits survey`` command line."""
    argv = [sys.executable, "-m", "orbits", "--threads", str(threads), "survey"]
    argv += ["--resolution", str(resolution), "--n-max", str(n_max), "--json", "--out", out]
    return argv + list(extra)


def _survey_command_wall(resolution, n_max, cpus, threads=1, extra=()):
    """Wall seconds of one whole ``orbits survey`` command pinned to ``cpus``.

    The child runs on exactly those CPUs (as ``taskset -c``) with
    ``--threads threads``, in a fresh interpreter (start-up, grid, search,
    tables, files, report), into a new temporary directory; returns
    ``(wall, bodies, bytes on disk)``.  A child that fails is
    :class:`BenchError`.
    """
    import shutil
    import subprocess
    import tempfile

    directory = tempfile.mkdtemp(prefix="orbits-bench-")
    out = os.path.join(directory, "s")
    argv = _survey_argv(resolution, n_max, threads, out, extra)
    try:
        start = time.perf_counter()
        done = _run_child(
            argv,
            _child_env(),
            stdout=subprocess.PIPE,
            preexec_fn=lambda: os.sched_setaffinity(0, cpus),
        )
        wall = time.perf_counter() - start
        size = sum(
            os.path.getsize(os.path.join(root, name))
            for root, _, names in os.walk(out)
            for name in names
        )
        try:
            bodies = int(json.loads(done.stdout)["bodies"])
        except (ValueError, KeyError, TypeError):
            raise BenchError(
                f"a benchmark's child process printed no survey report: {_shown(argv)}"
            ) from None
        return wall, bodies, size
    finally:
        shutil.rmtree(directory, ignore_errors=True)


def unavailable(name):
    """Why the CPU row ``name`` cannot run on this machine, or None when it can."""
    if name == "survey_scaling":
        if not (hasattr(os, "sched_getaffinity") and hasattr(os, "sched_setaffinity")):
            return (
                "needs os.sched_getaffinity and os.sched_setaffinity (Linux) "
                "to pin the command to CPUs"
            )
        if len(os.sched_getaffinity(0)) < 2:
            return "only one CPU is available to this process"
    return None


def amdahl_bound(one, fixed, cpus):
    """Amdahl's estimate of the speed-up of ``cpus`` CPUs on a run of ``one`` s
    with ``fixed`` s serial.

    Amdahl's law: the fixed part stays on one core, the rest is shared
    perfectly, ``one / (fixed + (one - fixed) / cpus)``; 1 when the fixed
    part is the whole run (or more, as measured on a noisy machine).  With
    ``one`` and ``fixed`` measured (each a best of a few noisy runs) this is
    an estimate, not a limit: a measured ratio can exceed it.
    """
    if not one > fixed:
        return 1.0
    return one / (fixed + (one - fixed) / cpus)


def bench_survey_scaling(resolution=500, n_max=30, repeats=3):
    """Whole-command ``orbits survey`` on one CPU and on every CPU it may use.

    Issue #18's target: two CPUs >= 1.7x one (``taskset -c 0`` against
    ``taskset -c 0,1``).  The one-CPU command runs with ``--threads 1``,
    the all-CPU one with ``--threads`` the count in effect here
    (:func:`orbits.get_num_threads`).  After one untimed grid-2 run (a
    warm-up: kernels and files into the caches), the speedup column is one
    CPU's time over all CPUs' time, each the best of ``repeats`` fresh
    processes taken in turns (one CPU, all CPUs, the fixed cost), so that a
    drift of the machine's speed touches all three alike.  The note gives
    :func:`amdahl_bound` of those figures as an estimate (``bound`` in the
    row), not as a limit.

    Raises :class:`BenchError` where :func:`unavailable` gives a reason
    (no CPU-affinity API, one CPU).
    """
    reason = unavailable("survey_scaling")
    if reason:
        raise BenchError(f"survey_scaling cannot run here: {reason}")
    cpus = sorted(os.sched_getaffinity(0))
    threads = get_num_threads()
    _survey_command_wall(2, 1, {cpus[0]})  # warm-up, untimed
    ones, runs, fixeds = [], [], []
    for _ in range(repeats):
        ones.append(_survey_command_wall(resolution, n_max, {cpus[0]})[0])
        runs.append(_survey_command_wall(resolution, n_max, set(cpus), threads))
        # the fixed cost of a survey command (interpreter, NumPy, numba and
        # its first kernel, pyarrow, the files): a grid of 2, one CPU
        fixeds.append(_survey_command_wall(2, 1, {cpus[0]})[0])
    one, fixed = min(ones), min(fixeds)
    wall, bodies, size = min(runs)
    bound = amdahl_bound(one, fixed, len(cpus))
    runs_text = "one fresh process" if repeats == 1 else f"best of {repeats} fresh processes"
    return {
        "task": f"orbits survey, grid {resolution}, n <= {n_max}: {len(cpus)} CPUs "
        f"({plural(threads, 'thread')}) vs 1",
        "timed": f"{runs_text} of each command, taken in turns, after one untimed grid-2 run",
        "ours_s": wall,
        "baseline": "the same command pinned to one CPU, --threads 1 (fresh process)",
        "baseline_s": one,
        "speedup": one / wall,
        "bodies_per_s": bodies / wall,
        "bytes_per_body": size / bodies,
        "fixed_s": fixed,
        "bound": bound,
        "threads": threads,
        "command": _shown(_survey_argv(resolution, n_max, threads, "DIR")),
        "note": f"{bodies} bodies: {bodies / wall:.0f} bodies/s on CPUs {cpus} "
        f"(--threads {threads}), {bodies / one:.0f} on CPU {cpus[0]}; "
        f"{size / bodies:.0f} bytes per body "
        "(whole command: start-up, search, tables, files, report); "
        f"a grid-2 survey takes {fixed:.2f} s on one CPU ({fixed / one:.0%} of the "
        "one-CPU run), a fixed cost that more CPUs cannot shorten: with it, "
        f"{len(cpus)} CPUs give about {bound:.2f}x one (an Amdahl estimate from the "
        "best grid-2 and one-CPU runs, not a limit: measured ratios scatter around "
        "it)" + _bytecode_note(),
    }


def bench_search_scaling(resolution=500, n_max=30, repeats=3):
    """The survey's search kernel alone on one numba thread and on all in effect.

    The same bodies as :func:`bench_survey_scaling` (the grid, in the
    survey's chunks, each through :func:`orbits.survey.compute.search_chunk`),
    in this process: no start-up, no tables, no files.  "All" is the count
    in effect (:func:`orbits.get_num_threads`, which ``orbits --threads``
    sets).  After a warm-up on 64 bodies each figure is the best of
    ``repeats``, taken in turns.
    """
    from .bodies import region_grid
    from .survey.compute import search_chunk
    from .survey.runner import DEFAULT_CHUNK
    from .threads import using_threads

    moments = region_grid(resolution)
    chunks = [moments[i : i + DEFAULT_CHUNK] for i in range(0, len(moments), DEFAULT_CHUNK)]
    top = get_num_threads()
    search_chunk(chunks[0][:64], n_max)  # load the kernels first

    def once(threads):
        with using_threads(threads):
            start = time.perf_counter()
            for chunk in chunks:
                search_chunk(chunk, n_max)
            return time.perf_counter() - start

    singles, everys = [], []
    for _ in range(repeats):
        singles.append(once(1))
        everys.append(once(top))
    single, every = min(singles), min(everys)
    bodies = len(moments)
    runs = "one run" if repeats == 1 else f"best of {repeats} runs"
    return {
        "_ours": (lambda: once(top), 1),
        "task": f"search kernel, grid {resolution}, n <= {n_max}: {plural(top, 'thread')} vs 1",
        "timed": f"{runs} of each, taken in turns, after a warm-up on 64 bodies, in this process",
        "ours_s": every,
        "baseline": "the same search on one numba thread",
        "baseline_s": single,
        "speedup": single / every,
        "bodies_per_s": bodies / every,
        "threads": top,
        "note": f"{bodies} bodies: {bodies / every:.0f} bodies/s on "
        f"{plural(top, 'thread')}, {bodies / single:.0f} on one; the parallel part "
        "of the survey_scaling command (no start-up, tables or files)",
    }


def bench_survey_threads(resolution=300, n_max=30):
    """The same survey in-process on one numba thread and on all in effect.

    "All" is :func:`orbits.get_num_threads` (which ``orbits --threads``
    sets).  One warm-up run, then one timed run on each count.
    """
    import shutil
    import tempfile

    from .survey import Survey
    from .threads import using_threads

    def once(threads):
        directory = tempfile.mkdtemp(prefix="orbits-bench-")
        try:
            with using_threads(threads):
                start = time.perf_counter()
                survey = Survey.grid(os.path.join(directory, "s"), resolution, n_max)
                survey.run()
                return time.perf_counter() - start, survey.moments.shape[0]
        finally:
            shutil.rmtree(directory, ignore_errors=True)

    top = get_num_threads()
    once(top)  # compile and warm the caches first
    single, bodies = once(1)
    every, _ = once(top)
    return {
        "_ours": (lambda: once(top), 1),
        "task": f"survey {bodies} bodies, n <= {n_max}: {plural(top, 'thread')} vs 1",
        "timed": "one run on each count after a warm-up run, in this process",
        "ours_s": every,
        "baseline": "the same survey on one numba thread (one table thread)",
        "baseline_s": single,
        "speedup": single / every,
        "bodies_per_s": bodies / every,
        "threads": top,
        "note": f"{bodies / every:.0f} bodies/s on {plural(top, 'thread')}, "
        f"{bodies / single:.0f} on one (search, tables, files, ledger, report)",
    }


def bench_survey_tables(resolution=1612, n_max=10, chunks=16, chunk=20_000, repeats=3):
    """The survey's table work alone, on one thread and on all in effect.

    The part of a survey that runs beside the search: searched chunks made
    into their two tables, written, hashed and entered in the ledger
    (:func:`orbits.survey.compute.chunk_columns` and
    :meth:`orbits.survey.Survey.write_chunk`), ``chunks`` chunks of
    ``chunk`` bodies of the grid, by a pool of one thread and of
    :func:`orbits.get_num_threads` threads (the survey's own table pool
    has as many).  The searches are done first and not timed; each timed
    pass gets fresh searches (a chunk's flat rows are made by its table
    work) and a fresh directory.  Best of ``repeats`` passes of each,
    taken in turns, after a warm-up pass.  Where the pool stops gaining is
    the part of the work that holds the interpreter lock.
    """
    import shutil
    import tempfile
    from concurrent.futures import ThreadPoolExecutor

    from .survey import Survey, compute

    top = get_num_threads()
    directory = tempfile.mkdtemp(prefix="orbits-bench-")
    try:
        grid = Survey.grid(os.path.join(directory, "grid"), resolution, n_max, chunk=chunk)
        count = min(int(chunks), grid.chunks)
        bodies = sum(grid.chunk_moments(i).shape[0] for i in range(count))

        def one_pass(threads, label):
            found = [compute.search_chunk(grid.chunk_moments(i), n_max) for i in range(count)]
            survey = Survey.grid(os.path.join(directory, label), resolution, n_max, chunk=chunk)
            survey.out_dir.mkdir()

            def finish(index):
                tables = compute.chunk_columns(found[index], index * chunk, survey.columns)
                survey.write_chunk(index, *tables)

            with survey.lock():
                survey.prepare()
                start = time.perf_counter()
                with ThreadPoolExecutor(threads) as pool:
                    list(pool.map(finish, range(count)))
                elapsed = time.perf_counter() - start
            shutil.rmtree(survey.out_dir)
            return elapsed

        one_pass(top, "warm")
        singles, everys = [], []
        for k in range(repeats):
            singles.append(one_pass(1, f"one-{k}"))
            everys.append(one_pass(top, f"all-{k}"))
    finally:
        shutil.rmtree(directory, ignore_errors=True)
    single, every = min(singles), min(everys)
    return {
        "task": f"survey tables, {count} chunks of up to {chunk} bodies, n <= {n_max}: "
        f"{plural(top, 'thread')} vs 1",
        "timed": f"best of {repeats} passes of each, taken in turns, after a warm-up "
        "pass; the searches done first, untimed; in this process",
        "ours_s": every,
        "baseline": "the same chunks' tables and files on one thread",
        "baseline_s": single,
        "speedup": single / every,
        "bodies_per_s": bodies / every,
        "threads": top,
        "note": f"{single / count * 1e3:.1f} ms a chunk on one thread, "
        f"{every / count * 1e3:.1f} ms on {plural(top, 'thread')} ({bodies} bodies: "
        "tables, Parquet parts, SHA-256, ledger); what does not shrink with "
        "threads holds the interpreter lock",
    }


def bench_survey_bytes(resolution=300, n_max=30):
    """Bytes per body on disk: the compact layout (default) against ``columns="all"``.

    Each layout: one untimed warm-up survey, then one timed survey whose
    files are measured.
    """
    import shutil
    import tempfile

    from .survey import Survey

    sizes, times = {}, {}

    def once(columns, measure):
        directory = tempfile.mkdtemp(prefix="orbits-bench-")
        try:
            start = time.perf_counter()
            survey = Survey.grid(os.path.join(directory, "s"), resolution, n_max, columns=columns)
            survey.run()
            elapsed = time.perf_counter() - start
            if measure:
                times[columns] = elapsed
                sizes[columns] = sum(
                    os.path.getsize(os.path.join(root, name))
                    for root, _, names in os.walk(directory)
                    for name in names
                )
            return survey.moments.shape[0]
        finally:
            shutil.rmtree(directory, ignore_errors=True)

    for columns in ("compact", "all"):
        once(columns, measure=False)  # warm-up, untimed
    for columns in ("compact", "all"):
        bodies = once(columns, measure=True)
    return {
        "task": f"survey bytes per body, n <= {n_max} (grid {resolution}), Parquet",
        "timed": "one run of each layout after an untimed warm-up run of each, in this process",
        "ours_s": times["compact"],
        "baseline": "the same survey with every catalog column (--columns all)",
        "baseline_s": times["all"],
        "speedup": times["all"] / times["compact"],
        "bytes_per_body": sizes["compact"] / bodies,
        "baseline_bytes_per_body": sizes["all"] / bodies,
        "note": f"{sizes['compact'] / bodies:.0f} bytes per body compact (target <= 1,200), "
        f"{sizes['all'] / bodies:.0f} with every column; {bodies} bodies",
    }


BENCHMARKS = {
    "startup": bench_startup,
    "cold_compile": bench_cold_compile,
    "phase": bench_total_phase,
    "motion": bench_motion,
    "motion_near_separatrix": lambda **kw: bench_motion(dtheta=-2e-4, **kw),
    "motion_20001": lambda **kw: bench_motion(points=20001, **kw),
    "motion_near_separatrix_20001": lambda **kw: bench_motion(points=20001, dtheta=-2e-4, **kw),
    "motion_rate": bench_motion_rate,
    "search": bench_search,
    "search_evaluations": bench_search_evaluations,
    "survey": bench_survey,
    "survey_scaling": bench_survey_scaling,
    "survey_threads": bench_survey_threads,
    "search_scaling": bench_search_scaling,
    "survey_bytes": bench_survey_bytes,
    "survey_tables": bench_survey_tables,
}


# ------------------------------------------------------------------ GPU rows
def _best_of(count, singular, many=None):
    """``one run`` or ``best of 7 runs``."""
    return f"one {singular}" if count == 1 else f"best of {plural(count, singular, many)}"


def bench_cuda_total_phase(points=100_000_000, repeats=7, seed=0):
    """Total phase of the Fig. 6 body on the GPU against the CPU, end to end.

    The ratio compares the same call on both sides: ``total_phase(body,
    theta, device="cuda")`` against ``total_phase(body, theta,
    device="cpu")`` (argument checks, folds, copies to and from the GPU
    included on the GPU side).  The kernel alone (angles already on the GPU,
    no copies) is timed too and given in the note, labelled as such.

    Raises DeviceError (one line) without a usable GPU or numba-cuda.
    """
    from .device import cuda_kernels, run_cuda

    gpu = cuda_kernels()
    body = Body.preset("fig6")
    moments = body.normalized_moments
    theta = np.random.default_rng(seed).uniform(0.0, 0.5 * np.pi, points)
    # a numba-cuda that cannot compile here: DeviceError, one line
    kernel = run_cuda(gpu.total_phase_kernel_seconds, *moments, theta, repeats)
    end_to_end = best_time(lambda: total_phase(body, theta, device="cuda"), repeats)
    cpu_points = min(points, 10_000_000)
    cpu_runs = max(1, repeats // 2)
    cpu = best_time(lambda: total_phase(body, theta[:cpu_points], device="cpu"), cpu_runs)
    cpu = cpu * points / cpu_points
    sample = theta[:1_000_000]
    reference = total_phase(body, sample, device="cpu")
    difference = np.max(np.abs(total_phase(body, sample, device="cuda") / reference - 1.0))
    threads = 1 if cpu_points < SERIAL_BELOW else get_num_threads()
    scaled = (
        f"timed on the first {cpu_points:.0e} angles and scaled by {points / cpu_points:g}"
        if cpu_points < points
        else "timed on all the angles"
    )
    return {
        "task": f"total phase on the GPU, end to end, {points:.0e} random theta (fig6 body)",
        "timed": f"end to end, total_phase(..., device='cuda') against device='cpu': the "
        f"GPU {_best_of(repeats, 'run')} after a warm-up run, the CPU "
        f"{_best_of(cpu_runs, 'run')} after a warm-up run, {scaled}; the kernel alone "
        f"(in the note) {_best_of(repeats, 'launch', 'launches')}",
        "device": gpu.device_name(),
        "ours_s": end_to_end,
        "baseline": f"orbits.total_phase(..., device='cpu') ({plural(threads, 'thread')}), "
        f"{scaled}",
        "baseline_s": cpu,
        "speedup": cpu / end_to_end,
        "angles_per_s": points / end_to_end,
        "end_to_end_s": end_to_end,
        "kernel_s": kernel,
        "kernel_angles_per_s": points / kernel,
        "kernel_speedup": cpu / kernel,
        "threads": threads,
        "note": f"end to end {points / end_to_end:.3g} angles/s on {gpu.device_name()} "
        "(total_phase(..., device='cuda'): argument checks and the phi fold on the "
        "host, theta folded and checked in the kernel, copies both ways), "
        f"CPU {points / cpu:.3g} angles/s; kernel only (angles already on the GPU, "
        f"no copies; not the ratio column): {_seconds(kernel)}, "
        f"{points / kernel:.3g} angles/s ({cpu / kernel:.3g}x the CPU call); max "
        f"relative difference GPU vs CPU {difference:.1e}",
    }


def bench_cuda_search(resolution=400, n_max=30, repeats=3):
    """The survey's search on the GPU against the CPU, bodies/s, end to end.

    The ratio compares the same call on both sides:
    :func:`orbits.search.search_bodies` with ``device="cuda"`` (copies
    included) against ``device="cpu"``.  The kernel alone (inputs already
    on the GPU, no copies) is timed too and given in the note, labelled as
    such.  The two sides must find the same roots on every body, offsets
    within :data:`SEARCH_RTOL` relative (``agrees``, :func:`roots_agreement`).

    Raises DeviceError (one line) without a usable GPU or numba-cuda.
    """
    from .bodies import region_grid, unit_moments
    from .device import cuda_kernels, run_cuda
    from .search import phase_levels, search_bodies, searched

    gpu = cuda_kernels()
    moments = np.ascontiguousarray(unit_moments(region_grid(resolution))[0])
    count = moments.shape[0]
    p, q, values = phase_levels(n_max)
    levels = np.ascontiguousarray(values[searched(p, q)])
    capacity = 2 * levels.size + 8
    rows = search_bodies(moments, levels, device="cuda")  # compile, and the check

    def kernel_only():
        outputs = (
            np.empty((count, capacity), np.int8),
            np.empty((count, capacity), np.int64),
            np.empty((count, capacity)),
            np.empty(count, np.int64),
            np.empty((count, rows.info.shape[1])),
        )
        return run_cuda(gpu.search_many, moments, levels, *outputs)

    kernel = min(kernel_only() for _ in range(repeats))
    end_to_end = best_time(lambda: search_bodies(moments, levels, device="cuda"), repeats)
    cpu_rows = search_bodies(moments, levels, device="cpu")
    cpu_runs = max(1, repeats // 2)
    cpu = best_time(lambda: search_bodies(moments, levels, device="cpu"), cpu_runs)
    same_counts = bool(np.array_equal(rows.counts, cpu_rows.counts))
    differ, worst = roots_agreement(*(_per_body(found) for found in (rows, cpu_rows)))
    agrees = differ == 0
    threads = get_num_threads()
    return {
        "task": f"survey search on the GPU, end to end, {count} bodies, n <= {n_max} "
        f"(grid {resolution})",
        "timed": f"end to end, search_bodies(..., device='cuda') against device='cpu': "
        f"the GPU {_best_of(repeats, 'run')}, the CPU {_best_of(cpu_runs, 'run')}, each "
        f"after a warm-up run; the kernel alone (in the note) "
        f"{_best_of(repeats, 'launch', 'launches')}",
        "device": gpu.device_name(),
        "ours_s": end_to_end,
        "baseline": f"the same search_bodies call on the CPU ({plural(threads, 'thread')})",
        "baseline_s": cpu,
        "speedup": cpu / end_to_end,
        "bodies_per_s": count / end_to_end,
        "end_to_end_s": end_to_end,
        "kernel_s": kernel,
        "kernel_bodies_per_s": count / kernel,
        "kernel_speedup": cpu / kernel,
        "threads": threads,
        "agrees": agrees,
        "note": f"end to end (copies both ways) {count / end_to_end:.3g} bodies/s on "
        f"{gpu.device_name()}, CPU {count / cpu:.3g} bodies/s; kernel only (inputs "
        f"already on the GPU, no copies; not the ratio column): {_seconds(kernel)}, "
        f"{count / kernel:.3g} bodies/s ({cpu / kernel:.3g}x the CPU call); "
        + _agreement(
            agrees,
            f"{int(cpu_rows.counts.clip(0).sum())} roots, root counts "
            f"{'equal' if same_counts else 'DIFFER'}, largest relative dtheta "
            f"difference {worst:.1e} (limit {SEARCH_RTOL:.0e})",
        ),
    }


CUDA_BENCHMARKS = {
    "cuda_phase": bench_cuda_total_phase,
    "cuda_search": bench_cuda_search,
}


# under load, each row's own time may grow at most by this factor
LOAD_LIMIT = 2.0


def _median_time(function, repeats):
    """Median wall time of ``repeats`` calls after one warm-up call."""
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


# The busy child's loop: pure interpreter work on one core, with a look at
# its parent process every million turns (~10-50 ms) so that it ends by
# itself once the bench is gone (killed with SIGKILL, its ``finally`` never
# runs): it would otherwise spin forever, adopted by init.
_BUSY_LOOP = """\
import os, sys
parent = int(sys.argv[1])
while os.getppid() == parent:
    for _ in range(1_000_000):
        pass
"""


def _busy_process():
    """A CPU-bound child (a Python busy loop) standing for another user's job.

    Returns
    -------
    subprocess.Popen
        The child, spinning on one core until killed or until this process
        is gone (it watches its parent's pid, see :data:`_BUSY_LOOP`).
    """
    import subprocess

    return subprocess.Popen(
        [sys.executable, "-c", _BUSY_LOOP, str(os.getpid())],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def load_check(rows):
    """Re-time each row's own task idle and beside a CPU-bound process.

    For each row (in place) adds ``load``: ``idle_s`` and ``loaded_s``
    (each after a warm-up call, the median of ``runs`` calls: at least 3,
    one for the rows whose own figure is a single run; measured back to back
    so that the rest of the machine is the same), ``slowdown`` = loaded/idle
    and ``holds`` (slowdown <= :data:`LOAD_LIMIT`).  Rows without a task of
    their own (``_ours``: startup, cold_compile, search_evaluations,
    survey_scaling, survey_bytes, survey_tables) are not re-timed.  The busy process is
    ours and is always stopped.
    """
    for row in rows:
        task = row.pop("_ours", None)
        if task is None:
            continue
        function, repeats = task
        repeats = max(repeats, 3) if repeats > 1 else 1
        idle = _median_time(function, repeats)
        busy = _busy_process()
        try:
            time.sleep(0.3)  # let it start spinning
            loaded = _median_time(function, repeats)
        finally:
            busy.kill()
            busy.wait()
        row["load"] = {
            "idle_s": idle,
            "loaded_s": loaded,
            "slowdown": loaded / idle,
            "holds": bool(loaded / idle <= LOAD_LIMIT),
            "runs": repeats,
        }


def load_failures(report):
    """The rows of a :func:`run` report whose under-load check failed."""
    return [row for row in report["results"] if not row.get("load", {}).get("holds", True)]


def disagreements(report):
    """The rows of a :func:`run` report whose two sides disagree (``agrees``
    false: ``orbits bench`` exits 1 after the table, naming them)."""
    return [row for row in report["results"] if row.get("agrees", True) is False]


def _quick_kwargs(name, gpu):
    """The smaller sizes of ``--quick`` for the row ``name``."""
    if gpu:
        return {"cuda_phase": {"points": 10_000_000}, "cuda_search": {"resolution": 100}}.get(
            name, {}
        )
    if name in ("phase", "motion_rate"):
        return {"points": 100_000}
    if name in ("survey", "survey_scaling", "survey_threads", "search_scaling", "survey_bytes"):
        return {"resolution": 60}
    if name == "survey_tables":
        return {"resolution": 400, "chunks": 4}
    if name == "startup":
        return {"repeats": 2}
    if name == "search_evaluations":
        return {"resolution": 30}
    if name.startswith("motion"):  # one orbit: the size is the row's, fewer repeats
        return {"repeats": 2}
    if name == "search":
        return {"repeats": 3}
    return {}  # cold_compile: one compile, as it is


def _skipped(name, reason):
    """The row of a benchmark that cannot run here (see :func:`unavailable`)."""
    return {
        "name": name,
        "task": f"{name}: skipped",
        "timed": None,
        "ours_s": None,
        "baseline": None,
        "baseline_s": None,
        "speedup": None,
        "skipped": reason,
        "note": f"skipped: {reason}",
    }


def run(names=None, quick=False, load=True, device="cpu"):
    """Run the named benchmarks (all by default, each once); return a JSON-able dict.

    With ``load`` each CPU row's task is then re-timed beside a CPU-bound
    process (:func:`load_check`; the report's ``load_check`` says how many
    rows held).  With ``device="cuda"`` the rows are those of
    :data:`CUDA_BENCHMARKS` (the GPU named in ``machine["gpu"]``), ``load``
    does not apply (there is no under-load check of GPU rows), and without
    a usable GPU that raises :class:`orbits.DeviceError` before any timing.

    A row that cannot run on this machine (:func:`unavailable`) is refused
    with :class:`BenchError` when it is named, and is a row with
    ``skipped`` (the reason) and no figures when all rows run.  An unknown
    or repeated name is :class:`orbits.InputError`.
    """
    from .device import check_device, cuda_kernels

    table = CUDA_BENCHMARKS if check_device(device) == "cuda" else BENCHMARKS
    named = bool(names)
    names = list(table) if not names else list(names)
    unknown = [name for name in names if name not in table]
    if unknown:
        raise InputError(
            f"unknown benchmark(s) for --device {device}: {', '.join(sorted(set(unknown)))}; "
            f"known: {', '.join(table)}"
        )
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise InputError(
            f"benchmark(s) named more than once: {', '.join(repeated)}; give each name once"
        )
    gpu = cuda_kernels() if device == "cuda" else None
    if named and not gpu:
        for name in names:
            reason = unavailable(name)
            if reason:
                raise BenchError(f"{name} cannot run here: {reason}")
    rows = []
    for name in names:
        reason = None if gpu else unavailable(name)
        if reason:
            rows.append(_skipped(name, reason))
            continue
        kwargs = _quick_kwargs(name, gpu) if quick else {}
        rows.append(dict(name=name, **table[name](**kwargs)))
    checked = bool(load and not gpu)
    if checked:
        load_check(rows)
    for row in rows:
        row.pop("_ours", None)
    usable, total = usable_cpus()
    machine = {
        "cpus_usable": usable,
        "cpu_count": total,
        "numba_threads": get_num_threads(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
    }
    if gpu:
        machine["gpu"] = gpu.device_name()
    report = {"machine": machine, "results": rows}
    checked_rows = [row for row in rows if "agrees" in row]
    if checked_rows:
        report["agreement"] = {
            "rows": len(checked_rows),
            "agree": sum(bool(row["agrees"]) for row in checked_rows),
            "passed": not disagreements(report),
        }
    if checked:
        loaded = [row for row in rows if "load" in row]
        report["load_check"] = {
            "limit": LOAD_LIMIT,
            "rows": len(loaded),
            "held": sum(row["load"]["holds"] for row in loaded),
            "passed": not load_failures(report),
        }
    return report


# the task column is at least this wide
TASK_WIDTH = 52


def format_table(report):
    """Plain-text table of a :func:`run` report."""
    machine = report["machine"]
    rows = report["results"]
    width = max([TASK_WIDTH] + [len(row["task"]) for row in rows])
    lines = [
        f"orbits bench: {_cpus_label(machine)}, "
        f"{machine['numba_threads']} numba threads, Python "
        f"{machine['python']}, NumPy {machine['numpy']}, SciPy "
        f"{machine['scipy']}, numba {machine['numba']}"
        + (f", GPU {machine['gpu']}" if "gpu" in machine else ""),
        "",
        f"{'task':<{width}} {'ours':>10} {'baseline':>10} {'ratio':>8}",
    ]
    for row in rows:
        ours = _seconds(row["ours_s"]) if _finite(row["ours_s"]) else "-"
        baseline = _seconds(row["baseline_s"]) if _finite(row["baseline_s"]) else "-"
        ratio = f"{row['speedup']:.1f}x" if _finite(row["speedup"]) else "-"
        if row.get("agrees") is False:  # no ratio of two arms that did not agree
            ratio = "DISAGREE"
        lines.append(f"{row['task']:<{width}} {ours:>10} {baseline:>10} {ratio:>8}")
        if row.get("skipped"):
            lines.append(f"    skipped: {row['skipped']}")
            continue
        lines.append(f"    timed: {row['timed']}")
        lines.append(f"    baseline: {row['baseline']}; {row['note']}")
    checked_rows = [row for row in rows if "agrees" in row]
    if checked_rows:
        agree = sum(bool(row["agrees"]) for row in checked_rows)
        lines += [
            "",
            f"agreement check: both sides agree in {agree} of {len(checked_rows)} "
            "rows that compare results"
            + ("" if agree == len(checked_rows) else " (NOT ALL: DISAGREE)"),
        ]
    loaded = [row for row in rows if "load" in row]
    if loaded:
        lines += [
            "",
            (
                "under load: each task again, idle and then beside one CPU-bound "
                "process (a Python busy loop), each the median of `runs` runs after "
                f"a warm-up; each row must slow down by at most {LOAD_LIMIT:g}x"
            ),
            f"{'task':<{width}} {'idle':>10} {'loaded':>10} {'slowdown':>8} {'runs':>4}",
        ]
        for row in loaded:
            load = row["load"]
            lines.append(
                f"{row['task']:<{width}} {_seconds(load['idle_s']):>10} "
                f"{_seconds(load['loaded_s']):>10} {load['slowdown']:>7.2f}x "
                f"{load.get('runs', '-'):>4}" + ("" if load["holds"] else "  FAILS")
            )
        held = sum(row["load"]["holds"] for row in loaded)
        lines.append(
            f"under-load check: {held} of {len(loaded)} rows hold within "
            f"{LOAD_LIMIT:g}x" + ("" if held == len(loaded) else " (NOT ALL: FAILED)")
        )
    return "\n".join(lines)


def _cpus_label(machine):
    """``2 CPUs usable of 2`` (a report without ``cpus_usable``: ``2 CPUs``)."""
    total = machine.get("cpu_count")
    usable = machine.get("cpus_usable")
    if usable is None:
        return plural(total, "CPU") if total is not None else "CPUs unknown"
    return f"{plural(usable, 'CPU')} usable of {total if total is not None else '?'}"


def _finite(value):
    return value is not None and math.isfinite(value)


def _seconds(value):
    if value >= 1.0:
        return f"{value:.2f} s"
    if value >= 1e-3:
        return f"{value * 1e3:.2f} ms"
    return f"{value * 1e6:.1f} us"


def _json_ready(value):
    """``value`` with every NaN or infinity as None (JSON's null); NumPy scalars
    as Python numbers."""
    if isinstance(value, dict):
        return {key: _json_ready(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_ready(item) for item in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    return value


def to_json(report):
    """The report as strict JSON: a figure that does not exist is null, never NaN."""
    return json.dumps(_json_ready(report), indent=2, allow_nan=False)
