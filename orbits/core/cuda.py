"""CUDA kernels over the same scalar functions as the CPU kernels (numba-cuda).

Imported only for ``device="cuda"`` (through :mod:`orbits.device`, which
turns a missing GPU, a missing ``orbits[cuda]`` extra or a failing compile
into :class:`orbits.DeviceError`); nothing on the CPU path imports this
module or ``numba.cuda``.

One source of truth: every kernel here is a thin launcher, one thread per
point or per body, that calls the ``@njit`` scalar functions of
:mod:`orbits.core.phase`, :mod:`orbits.core.phase_table` and
:mod:`orbits.core.search` (numba-cuda compiles them as device functions).
``theta`` is folded and checked in the kernels too
(:func:`orbits.core.phase.given_angle`).  Device code allocates nothing:
per-thread scratch is a fixed-size ``cuda.local.array``, the output rows are
arrays the caller provides.

With ``NUMBA_ENABLE_CUDASIM=1`` the kernels run in numba's CUDA simulator
(slow: Python per thread), which is how the tests check them without a GPU.
On hardware NVVM contracts ``a * b + c`` into fused multiply-adds and
CUDA's own ``log`` and trigonometric functions round differently, so the
last bits differ from the CPU path (measured on an NVIDIA H200: the total
phase within 2.4e-15 relative, the search's ``dtheta`` within 3.9e-13).
"""

import math
import threading
import time
import warnings

import numpy as np
from numba import config, cuda, float64, int64

from .phase import (
    STATUS_OK,
    at_least_two_pi,
    body_constants,
    given_angle,
    spin_from_angle,
    total_from_spin,
)
from .phase_table import N_COLUMNS, phases_row
from .search import SCRATCH_FLOATS, SCRATCH_INTS, search_body_with

TWO_PI = 2.0 * math.pi
THREADS_PER_BLOCK = 128
# the search: each thread holds ~13 kB of local scratch
SEARCH_THREADS_PER_BLOCK = 64


def _blocks(n, per_block):
    return max(1, (n + per_block - 1) // per_block)


_CONFIGURE_LOCK = threading.Lock()


def _configured(kernel, n, per_block):
    """``kernel[blocks, per_block]`` for ``n`` threads, without numba-cuda's
    low-occupancy warning: a small launch here (a survey's last chunk, the
    one-body check before a survey, a few angles) is what was asked for, and
    the warning offered the user nothing to act on (seen on an H200: "Grid
    size 1 will likely result in GPU under-utilization", once per launch).

    ``catch_warnings`` swaps the process's filter list, so two threads
    configuring at once could restore each other's copy (leaving the filter
    behind or dropping one added meanwhile): one configuration at a time."""
    with _CONFIGURE_LOCK, warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"Grid size \d+ will likely result in GPU")
        return kernel[_blocks(n, per_block), per_block]


@cuda.jit(device=True)
def _total_one(i1, i2, i3, phi, angle, from_offset, fold_limit):
    """``(total phase >= 2 pi, status)`` of one point, ``theta`` folded here: the
    scalar path of :func:`orbits.core.phase.total_phase_many_scalar`."""
    angle, code = given_angle(angle, from_offset, fold_limit)
    if code != STATUS_OK:
        return math.inf, code
    code, _, _, _, w1, w2, w3, scale, offset, closing = spin_from_angle(
        body_constants(i1, i2, i3, phi), angle, from_offset
    )
    if code != STATUS_OK:
        return math.inf, code
    total = total_from_spin(i1, i2, i3, w1, w2, w3, scale, offset, closing)
    return at_least_two_pi(total), code


@cuda.jit
def _total_phase_one_body_kernel(i1, i2, i3, phi, angles, from_offset, fold_limit, out, status):
    k = cuda.grid(1)
    if k < angles.shape[0]:
        out[k], status[k] = _total_one(i1, i2, i3, phi, angles[k], from_offset, fold_limit)


@cuda.jit
def _total_phase_many_kernel(i1, i2, i3, phi, angles, from_offset, fold_limit, out, status):
    k = cuda.grid(1)
    if k < angles.shape[0]:
        out[k], status[k] = _total_one(
            i1[k], i2[k], i3[k], phi[k], angles[k], from_offset, fold_limit
        )


@cuda.jit
def _phases_kernel(i1, i2, i3, phi, angles, from_offset, fold_limit, columns, branch, status):
    """:func:`orbits.core.phase_table.phases_columns` per thread.

    The per-point step is written out here as there: the scalar functions are
    shared, but an ``@njit`` helper taking arrays cannot be called from a
    kernel under the CUDA simulator (it cannot unbox the simulator's arrays).
    """
    k = cuda.grid(1)
    if k < angles.shape[0]:
        j = 0 if i1.shape[0] == 1 else k
        a = 0 if phi.shape[0] == 1 else k
        angle, code = given_angle(angles[k], from_offset, fold_limit)
        if code != STATUS_OK:
            status[k] = code
            branch[k] = 0
            for c in range(N_COLUMNS):
                columns[c, k] = math.nan
            return
        code, lam, row = phases_row(i1[j], i2[j], i3[j], phi[a], angle, from_offset)
        status[k] = code
        branch[k] = lam
        for c in range(N_COLUMNS):
            columns[c, k] = row[c]


if config.ENABLE_CUDASIM:

    def _plain(array):
        """The simulator's stand-in for a device array, as the NumPy array it
        wraps: the ``@njit`` search functions take NumPy arrays (on hardware
        this is the identity)."""
        while hasattr(array, "_item"):
            array = array._item
        return getattr(array, "_ary", array)

else:

    @cuda.jit(device=True, inline="always")
    def _plain(array):
        return array


@cuda.jit
def _search_kernel(moments, levels, root_branch, root_level, root_offset, counts, info):
    """One thread per body: :func:`orbits.core.search.search_body_with` with
    per-thread local scratch, roots into row ``b`` of the outputs."""
    b = cuda.grid(1)
    if b < moments.shape[0]:
        floats = cuda.local.array(SCRATCH_FLOATS, float64)
        ints = cuda.local.array(SCRATCH_INTS, int64)
        counts[b] = search_body_with(
            moments[b, 0],
            moments[b, 1],
            moments[b, 2],
            _plain(levels),
            _plain(root_branch[b]),
            _plain(root_level[b]),
            _plain(root_offset[b]),
            _plain(info[b]),
            _plain(floats),
            _plain(ints),
        )


def search_many(moments, levels, root_branch, root_level, root_offset, counts, info):
    """The GPU twin of :func:`orbits.core.search.search_many` (host arrays in
    and out, the same shapes and dtypes); returns the kernel's own wall
    seconds (launch to finish, without the copies)."""
    n = moments.shape[0]
    if n == 0:
        return 0.0
    d_moments = cuda.to_device(np.ascontiguousarray(moments))
    d_levels = cuda.to_device(np.ascontiguousarray(levels))
    outputs = [
        cuda.device_array(a.shape, dtype=a.dtype)
        for a in (root_branch, root_level, root_offset, counts, info)
    ]
    cuda.synchronize()
    start = time.perf_counter()
    _configured(_search_kernel, n, SEARCH_THREADS_PER_BLOCK)(d_moments, d_levels, *outputs)
    cuda.synchronize()
    seconds = time.perf_counter() - start
    for device_array, host in zip(outputs, (root_branch, root_level, root_offset, counts, info)):
        device_array.copy_to_host(host)
    return seconds


def total_phase_one_body(i1, i2, i3, phi, angles, from_offset, fold_limit, out, status):
    """The GPU twin of :func:`orbits.core.phase.total_phase_one_body` (host
    arrays in and out)."""
    n = angles.shape[0]
    if n == 0:
        return
    d_angles = cuda.to_device(angles)
    d_out = cuda.device_array(n, dtype=np.float64)
    d_status = cuda.device_array(n, dtype=np.int8)
    _configured(_total_phase_one_body_kernel, n, THREADS_PER_BLOCK)(
        float(i1), float(i2), float(i3), float(phi), d_angles, bool(from_offset),
        float(fold_limit), d_out, d_status,
    )  # fmt: skip
    d_out.copy_to_host(out)
    d_status.copy_to_host(status)


def total_phase_many(i1, i2, i3, phi, angles, from_offset, fold_limit, out, status):
    """The GPU twin of :func:`orbits.core.phase.total_phase_many`."""
    n = angles.shape[0]
    if n == 0:
        return
    args = [cuda.to_device(np.ascontiguousarray(a)) for a in (i1, i2, i3, phi, angles)]
    d_out = cuda.device_array(n, dtype=np.float64)
    d_status = cuda.device_array(n, dtype=np.int8)
    _configured(_total_phase_many_kernel, n, THREADS_PER_BLOCK)(
        *args, bool(from_offset), float(fold_limit), d_out, d_status
    )
    d_out.copy_to_host(out)
    d_status.copy_to_host(status)


def phases_columns(i1, i2, i3, phi, angles, from_offset, fold_limit, columns, branch, status):
    """The GPU twin of :func:`orbits.core.phase_table.phases_columns` (host
    arrays in and out)."""
    n = angles.shape[0]
    if n == 0:
        return
    args = [cuda.to_device(np.ascontiguousarray(a)) for a in (i1, i2, i3, phi, angles)]
    outputs = [cuda.device_array(a.shape, dtype=a.dtype) for a in (columns, branch, status)]
    _configured(_phases_kernel, n, THREADS_PER_BLOCK)(
        *args, bool(from_offset), float(fold_limit), *outputs
    )
    for device_array, host in zip(outputs, (columns, branch, status)):
        device_array.copy_to_host(host)


def total_phase_kernel_seconds(i1, i2, i3, angles, repeats):
    """Best wall seconds of the one-body total-phase kernel alone (``phi = 0``,
    the angles already on the GPU, no copies), over ``repeats`` launches
    after a warm-up; for ``orbits bench``."""
    n = angles.shape[0]
    d_angles = cuda.to_device(np.ascontiguousarray(angles))
    d_out = cuda.device_array(n, dtype=np.float64)
    d_status = cuda.device_array(n, dtype=np.int8)
    launch = _configured(_total_phase_one_body_kernel, n, THREADS_PER_BLOCK)
    args = (float(i1), float(i2), float(i3), 0.0, d_angles, False, 2.0**21, d_out, d_status)
    launch(*args)
    best = math.inf
    for _ in range(repeats):
        cuda.synchronize()
        start = time.perf_counter()
        launch(*args)
        cuda.synchronize()
        best = min(best, time.perf_counter() - start)
    return best


def device_name():
    """The current GPU's name (``"CUDA simulator"`` under ``NUMBA_ENABLE_CUDASIM``)."""
    if config.ENABLE_CUDASIM:
        return "CUDA simulator"
    device = cuda.get_current_device()
    name = device.name
    return name.decode() if isinstance(name, bytes) else str(name)


def synchronize():
    """Wait for the GPU (for timings)."""
    cuda.synchronize()
