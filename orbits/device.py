"""The compute device of the array APIs: ``device="cpu"`` (default) or ``"cuda"``.

``"cuda"`` runs the kernels of :mod:`orbits.core.cuda` on an NVIDIA GPU
through numba-cuda (``pip install "orbits[cuda]"``).  That module, and
``numba.cuda`` with it, are imported here on first use only: the CPU path
never loads CUDA.  Every way the GPU path can be unavailable -- no numba-cuda,
no GPU or driver, a numba-cuda that cannot compile beside the installed
NumPy -- is one :class:`orbits.DeviceError` with a one-line message.
"""

import importlib.util

from .errors import DeviceError

DEVICES = ("cpu", "cuda")

_INSTALL = 'install the extra: pip install "orbits[cuda]"'


def check_device(device):
    """``device`` if it is ``"cpu"`` or ``"cuda"``, else :class:`DeviceError`."""
    if not isinstance(device, str) or device not in DEVICES:
        raise DeviceError(f'device must be "cpu" or "cuda", got {device!r}')
    return device


def _one_line(error):
    text = " ".join(str(error).split())
    if len(text) > 200:
        text = text[:197] + "..."
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def cuda_kernels():
    """The module :mod:`orbits.core.cuda`, imported now.

    Raises
    ------
    DeviceError
        numba-cuda not installed, no usable GPU (driver or device), or the
        module fails to import.
    """
    if importlib.util.find_spec("numba_cuda") is None:
        raise DeviceError(f'device="cuda" needs numba-cuda, which is not installed; {_INSTALL}')
    try:
        from numba import cuda
    except Exception as error:  # a broken install: one line, not a traceback
        raise DeviceError(f"numba.cuda does not import ({_one_line(error)})") from None
    try:
        usable = cuda.is_available()
    except Exception:
        usable = False
    if not usable:
        raise DeviceError(
            'device="cuda" found no usable NVIDIA GPU (no device or no driver); use device="cpu"'
        )
    try:
        from .core import cuda as kernels
    except Exception as error:
        raise DeviceError(f"the CUDA kernels do not import ({_one_line(error)})") from None
    return kernels


def run_cuda(kernel, *args):
    """Call a host launcher of :mod:`orbits.core.cuda`; a failure to compile or
    launch (e.g. numba-cuda 0.30.4 beside NumPy 2.5, which removed
    ``np.row_stack``) becomes :class:`DeviceError`."""
    try:
        return kernel(*args)
    except DeviceError:
        raise
    except Exception as error:
        import numpy
        from numba import cuda  # already imported by cuda_kernels

        version = getattr(cuda, "__version__", None) or _numba_cuda_version()
        text = _one_line(error)
        # seen on a GPU machine whose image paired numba-cuda 0.30.4 with
        # NumPy 2.5.2, which orbits[cuda] rules out
        hint = (
            "; orbits[cuda] needs NumPy < 2.5 with this numba-cuda: pip install 'numpy<2.5'"
            if "row_stack" in text
            else ""
        )
        raise DeviceError(
            f"the CUDA kernel {getattr(kernel, '__name__', kernel)} failed "
            f"(numba-cuda {version}, NumPy {numpy.__version__}): {text}{hint}"
        ) from None


def _numba_cuda_version():
    try:
        from importlib.metadata import version

        return version("numba-cuda")
    except Exception:
        return "unknown"
