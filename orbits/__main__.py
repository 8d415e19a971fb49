"""``python -m orbits`` and the ``orbits`` script: :func:`orbits.cli.main`.

:func:`entry` also covers the start-up: a Ctrl-C or SIGTERM while the
command line's modules are imported (NumPy and pandas take a few tenths of
a second) ends with one line and exit 130 (128 + the signal), not a
traceback; nothing can have been written yet.

The start-up runs on one core however many the machine has, so
:func:`entry` keeps it short (:mod:`orbits.startup`): the cyclic garbage
collector is held off while the libraries are imported (the command line
releases it before a command, the survey after its first chunk), OpenBLAS's
idle threads sleep instead of spinning for 0.1 s each, and ``numpy.f2py``
and ``numpy.testing``, which SciPy's copy of the NumPy namespace would
import for nothing, load only if used.  When the command is
over, the living objects are frozen out of the collector
(:func:`gc.freeze`): the interpreter's shutdown then frees them without
tracing the whole heap of NumPy, numba and pandas several times over, a few
tenths of a second that every command paid on one core.  No collection runs
first (it took 0.06 s after a survey): every file a command writes is
written, closed and renamed into place before :func:`orbits.cli.main`
returns, so no finaliser is left with work to do.
"""

import gc
import signal
import sys

from . import startup


class _Stopped(BaseException):
    def __init__(self, signum):
        super().__init__(signum)
        self.signum = signum


def _stop(signum, frame):
    raise _Stopped(signum)


def _ignore(signum, frame):
    """A signal once the run is over (not SIG_IGN: see orbits.cli._hold_signals)."""


def _numba_environment():
    """Why ``NUMBA_NUM_THREADS`` is unusable, or '' when it is unset or a positive count.

    numba raises inside its import for a count <= 0 (a traceback) and
    warns and ignores any other value it cannot read as an integer.  It
    reads the value with ``int()``, which also takes ``1_0`` (as 10) and
    non-ASCII digits (an Arabic-Indic three as 3); here, as on the command
    line, a count is ASCII digits only, with an optional sign and
    surrounding ASCII whitespace.
    """
    import os

    text = os.environ.get("NUMBA_NUM_THREADS")
    if text is None:
        return ""
    body = text.strip(" \t\n\r\f\v")
    digits = body[1:] if body[:1] in ("+", "-") else body
    if digits.isascii() and digits.isdigit() and int(body) > 0:
        return ""
    return (
        f"NUMBA_NUM_THREADS={text.strip()!r} is not a positive whole number of threads; "
        "unset it or give one (--threads N chooses fewer for one command)"
    )


def _say(line):
    """One line on stderr, if it can take it (closed: ``2>&-``; full: ``2>/dev/full``)."""
    try:
        if sys.stderr is not None:
            print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def entry():
    """Run the command line; returns the exit code."""
    previous = {}
    for name in ("SIGINT", "SIGTERM", "SIGHUP"):
        number = getattr(signal, name, None)
        if number is not None:
            previous[number] = signal.signal(number, _stop)
    try:
        refusal = _numba_environment()
        if refusal:  # numba would raise inside its import: a traceback
            _say(f"orbits: error: {refusal}")
            return 2
        startup.hold_collector()
        startup.calm_blas_threads()  # before NumPy loads OpenBLAS
        startup.defer_unused_modules()
        from .cli import main

        # main installs its own handlers and gives ours back when it ends
        code = main()
    except (_Stopped, KeyboardInterrupt) as stop:
        for number in previous:  # a second signal must not cut the message short
            signal.signal(number, _ignore)
        number = getattr(stop, "signum", signal.SIGINT)
        name = signal.Signals(number).name
        _say(f"orbits: stopped by {name}; no partial output was written")
        return 128 + number
    finally:
        # the run is over: a signal during interpreter shutdown changes nothing
        for number in previous:
            signal.signal(number, _ignore)
        # a command that ended before it released the start-up's hold (an
        # error, a stop) gives the collector back too
        startup.release_collector()
        # the shutdown's collections would trace every object still alive
        # (0.25-0.5 s after a survey, on one core): leave them all to be
        # freed by reference counting as the modules are cleared
        gc.freeze()
    return code


def run():
    """The ``orbits`` script and ``python -m orbits``: :func:`entry`, then a quick exit.

    Once the command is over, every file it wrote is closed and renamed
    into place, so the interpreter's tear-down of the heap (every module,
    object and kernel of NumPy, numba, pandas and pyarrow freed one by one:
    35-40 ms after a survey, on one core) serves nobody.  The standard
    streams are flushed and the :mod:`atexit` handlers run as at any exit,
    then the process ends with :func:`os._exit`.  Should another thread
    that is not a daemon still run (none of orbits' own does by then), the
    ordinary exit waits for it instead.
    """
    import atexit
    import os
    import threading

    code = entry()  # main turns argparse's SystemExit (--help, a usage error) into a code
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except BrokenPipeError:  # the reader (e.g. `head`) closed the pipe: not ours
            if stream is sys.stdout:
                sys.stdout = None  # the interpreter's own exit would flush it again
        except OSError as error:
            if stream is sys.stdout and code == 0:
                # `orbits --help >/dev/full`: what was asked for is not written
                _say(f"orbits: error: standard output: {error.strerror or error}")
                code = 2
        except ValueError:  # a closed stream: nothing to tell
            pass
    others = [
        thread
        for thread in threading.enumerate()
        if thread is not threading.main_thread() and not thread.daemon and thread.is_alive()
    ]
    if others:
        return code
    atexit._run_exitfuncs()
    os._exit(code)


if __name__ == "__main__":
    sys.exit(run())
