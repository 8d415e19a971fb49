"""The ``orbits`` command line: the top-level parser and :func:`main`.

Every failure the user can cause (a bad argument, non-physical moments, an
unwritable path, a damaged input file, a size beyond the machine) ends with
exit code 2 and one line on stderr, never a traceback.  Ctrl-C (exit 130),
SIGTERM (143) and SIGHUP (129) end with one line and leave no partial
output: the handlers turn the signals into exceptions, so every atomic
write removes its temporary file.

One module per subcommand (:mod:`~orbits.cli.phase`,
:mod:`~orbits.cli.catalog`, :mod:`~orbits.cli.figures`,
:mod:`~orbits.cli.animate`, :mod:`~orbits.cli.survey`,
:mod:`~orbits.cli.verify`, :mod:`~orbits.cli.bench`), each with its
``add_parser`` and the function it runs; what they share (body and number
arguments, progress, exit codes) is in :mod:`orbits.cli.shared`.
"""

import os
import signal
import sys
import threading

from .._version import __version__
from ..errors import ArgumentTypeError, InputError, OrbitsError
from ..startup import release_collector
from . import animate, bench, catalog, figures, phase, survey, verify
from .phase import OMEGA_UNITS, format_value
from .shared import (
    BODY_SELECTORS,
    EXIT_CHECK_FAILED,
    EXIT_INTERRUPTED,
    EXIT_USAGE,
    Parser,
    add_body_options,
    announce,
    bodies_file_from_args,
    bodies_from_args,
    body_from_args,
    check_arguments,
    command_line,
    positive_int,
    progress_bar,
)

__all__ = [
    "BODY_SELECTORS",
    "EXIT_CHECK_FAILED",
    "EXIT_INTERRUPTED",
    "EXIT_USAGE",
    "OMEGA_UNITS",
    "add_body_options",
    "announce",
    "announce_compilation",
    "bodies_file_from_args",
    "bodies_from_args",
    "body_from_args",
    "build_parser",
    "check_arguments",
    "command_line",
    "format_value",
    "main",
    "progress_bar",
]


def build_parser():
    """The ``orbits`` argument parser: global options and one subparser per subcommand."""
    parser = Parser(
        prog="orbits",
        description="Geometric phase, exact motion and closed orbits of the "
        "force-free asymmetric top (Mecholsky 2019).  An option given where it "
        "does not apply (--mass with --t-handle, --units with --theta, ...) is "
        "refused, never ignored.",
    )
    parser.add_argument("--version", action="version", version=f"orbits {__version__}")
    parser.add_argument(
        "--threads",
        type=positive_int,
        metavar="N",
        help="threads for large inputs (default: all of numba's; small inputs always run on one)",
    )
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    phase.add_parser(subparsers)
    catalog.add_parser(subparsers)
    figures.add_parser(subparsers)
    survey.add_parser(subparsers)
    verify.add_parser(subparsers)
    bench.add_parser(subparsers)
    animate.add_parser(subparsers)
    return parser


_STOP_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")


def _hold_signals():
    """Ignore further stop signals: the first one's clean-up must finish.

    A second Ctrl-C (or a SIGTERM after it) while the first unwinds would
    interrupt the removal of a temporary file or the one-line message, and
    a traceback would escape.  A handler that does nothing, not SIG_IGN: a
    signal already caught but not yet handled would find SIG_IGN and raise
    "OSError: Signal 15 ignored due to race condition".  :func:`main`
    restores the handlers after.
    """
    import signal

    for name in _STOP_SIGNALS:
        number = getattr(signal, name, None)
        if number is not None:
            signal.signal(number, _ignore_signal)


def _ignore_signal(signum, frame):
    """A stop signal after the first: the run is already ending."""


# a stop signal that came while numba was compiling: (signal, SIGALRM's
# handler before), until the main thread is back in code of ours
_DEFERRED = []
# how often a deferred stop looks again (s)
_RETRY_SECONDS = 0.02


def _in_compiler(frame):
    """Whether the main thread is inside numba or llvmlite (compiling or loading a kernel)."""
    while frame is not None:
        if frame.f_globals.get("__name__", "").partition(".")[0] in (
            "numba",
            "numba_cuda",
            "llvmlite",
        ):
            return True
        frame = frame.f_back
    return False


def _defer(signum, frame):
    """Put off a stop signal that comes while numba compiles, or while a set of
    files is moved into place (:func:`orbits.atomic.committing`); True when put off.

    An exception raised there can land in one of llvmlite's ctypes
    callbacks, where Python prints it and drops it: the compiler is left
    broken and the run ends in a traceback (exit 1) instead of the one-line
    stop.  The stop is raised as soon as the main thread is out of numba and
    llvmlite again, looked at every :data:`_RETRY_SECONDS` by ``SIGALRM``;
    a kernel compiles in a few seconds at most.
    """
    from ..atomic import committing

    if not hasattr(signal, "setitimer") or not (_in_compiler(frame) or committing()):
        return False
    _arm_retry(signum)
    return True


def _arm_retry(signum):
    """Raise the stop ``signum`` in :data:`_RETRY_SECONDS` (SIGALRM), or later if put off again."""
    if not _DEFERRED:
        _DEFERRED.append((signum, signal.signal(signal.SIGALRM, _retry_deferred)))
    signal.setitimer(signal.ITIMER_REAL, _RETRY_SECONDS)


def _swallowed_stop(unraisable):
    """``sys.unraisablehook`` of a run: a stop raised where Python drops exceptions.

    A signal handler raises in whatever Python code runs at that moment; in a
    weakref callback, a ``__del__`` or a ctypes callback the exception is
    printed ("Exception ignored in ...") and dropped, and the run went on to
    exit 0 with the stop signals ignored.  Such a stop is raised again
    :data:`_RETRY_SECONDS` later, in the main thread's own code; any other
    unraisable exception goes to the previous hook.
    """
    import threading

    from ..atomic import Terminated

    stop = unraisable.exc_value
    if isinstance(stop, (KeyboardInterrupt, Terminated)) and (
        threading.current_thread() is threading.main_thread() and hasattr(signal, "setitimer")
    ):
        _arm_retry(getattr(stop, "signum", signal.SIGINT))
        return
    _PREVIOUS_HOOK[-1](unraisable)


# sys.unraisablehook before main installed _swallowed_stop
_PREVIOUS_HOOK = [sys.__unraisablehook__]


def _retry_deferred(_alarm, frame):
    signum = _DEFERRED[0][0]
    if signum == signal.SIGINT:
        _raise_interrupt(signum, frame)
    else:
        _raise_terminated(signum, frame)


def _end_deferral():
    """Cancel a deferred stop's timer and give SIGALRM its handler back."""
    if _DEFERRED:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, _DEFERRED.pop()[1])


def _stop_outcome(stop):
    """The end of a stop's line: what became of the output."""
    if getattr(stop, "output_complete", False):
        return " as the run ended; its output was written whole"
    # a survey keeps the chunks it finished (orbits.cli.survey says which)
    return getattr(stop, "outcome", None) or "; no partial output was written"


def _raise_pending_stop():
    """Raise a stop that was put off (:func:`_defer`) and not yet raised again.

    A stop signal that came while the last files were moved into place
    waits for its retry timer; a run that ends before the timer fires
    would otherwise drop it in :func:`main`'s clean-up and exit 0.  The
    output is whole then (the move finished: an existing target is
    replaced), and the run still ends as stopped, 128 + N, with a line that
    says the output is complete.
    """
    if _DEFERRED:
        signum = _DEFERRED[0][0]
        _end_deferral()
        _hold_signals()
        if signum == signal.SIGINT:
            stop = KeyboardInterrupt()
        else:
            from ..atomic import Terminated

            stop = Terminated(signum)
        stop.output_complete = True  # main's line says so
        raise stop


def _raise_terminated(signum, frame):
    from ..atomic import Terminated

    if _defer(signum, frame):
        return
    _end_deferral()
    _hold_signals()
    raise Terminated(signum)


def _raise_interrupt(signum, frame):
    if _defer(signum, frame):
        return
    _end_deferral()
    _hold_signals()
    raise KeyboardInterrupt


def _install_signal_handlers():
    """SIGINT raises KeyboardInterrupt, SIGTERM and SIGHUP :class:`~orbits.atomic.Terminated`.

    Each handler ignores the stop signals that follow it (:func:`_hold_signals`).
    Main thread only; returns the previous handlers.
    """
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return {}
    previous = {}
    for name in _STOP_SIGNALS:
        number = getattr(signal, name, None)
        if number is not None:
            handler = _raise_interrupt if name == "SIGINT" else _raise_terminated
            previous[number] = signal.signal(number, handler)
    return previous


def announce_compilation(stream=None):
    """On a terminal, say once that the first run compiles the kernels.

    numba caches compiled kernels (``cache=True``) next to their source, in
    ``orbits/core/__pycache__`` (or under ``NUMBA_CACHE_DIR``); when no index
    file is there yet the first call compiles them, which takes seconds.
    Returns True when the line was printed.
    """
    import os
    from pathlib import Path

    stream = sys.stderr if stream is None else stream
    if not stream.isatty():
        return False
    core = Path(__file__).resolve().parent.parent / "core"
    # numba uses NUMBA_CACHE_DIR instead of __pycache__ when it is set
    if os.environ.get("NUMBA_CACHE_DIR"):
        places = [Path(os.environ["NUMBA_CACHE_DIR"])]
    else:
        places = [core / "__pycache__"]
    if any(next(place.rglob("*.nbi"), None) is not None for place in places if place.is_dir()):
        return False
    print(
        "orbits: first run: compiling the numerical kernels (cached for later runs)...",
        file=stream,
        flush=True,
    )
    return True


# the options that set the size of each command's work (for an out-of-memory line)
_SIZE_OPTIONS = {
    "phase": "fewer --theta or --dtheta values",
    "catalog": "--n-max, --q-max, --bodies",
    "figures": "--n-max, --q-max",
    "survey": "--resolution, --n-max, --q-max, --chunk, --bodies",
    "verify": "--bodies, --angles",
    "animate": "--frames, --dpi",
    None: "--n-max, --q-max, --resolution, --chunk, --bodies",
}

# commands whose results go to standard output (catalog too with --out -)
_PRINTING = ("phase", "survey", "verify", "bench")


# the commands that draw with matplotlib (off screen, with its Agg canvas)
_DRAWING = ("figures", "animate")


def _check_matplotlib():
    """Refuse, before any work, an environment in which matplotlib cannot start.

    ``import matplotlib`` raises a ValueError when ``MPLBACKEND`` names no
    backend; the commands draw off screen with Agg whatever it says.
    """
    import os

    try:
        import matplotlib  # noqa: F401
    except ValueError as error:
        backend = os.environ.get("MPLBACKEND")
        if backend is None:
            raise InputError(f"matplotlib cannot start: {error}") from None
        raise InputError(
            f"MPLBACKEND={backend!r} is not a matplotlib backend, and matplotlib cannot "
            "start; orbits draws off screen with Agg: unset MPLBACKEND or give a valid "
            "one (e.g. agg)"
        ) from None


def _check_stdout(args):
    """Refuse, before any work, a run whose results would go to a closed stdout.

    Python sets ``sys.stdout`` to None when descriptor 1 is closed
    (``orbits phase ... >&-``); ``print`` then drops every line silently.
    """
    if sys.stdout is not None and not getattr(sys.stdout, "closed", False):
        return
    if args.command in _PRINTING or getattr(args, "out", None) == "-":
        where = "--out -" if getattr(args, "out", None) == "-" else f"orbits {args.command}"
        raise InputError(f"standard output is closed, so {where} has nowhere to write its results")


def _warning_shower(previous):
    """``warnings.showwarning`` for a run in this thread: :func:`_show_warning`
    for the run's warnings (raised in this thread, in a thread started
    after it, such as a survey's workers, or of the package's own
    categories); a warning of any thread that was already running goes to
    ``previous``, the handler the run replaced (a command run in a
    notebook's background thread printed the notebook's own warnings as
    ``orbits: warning:`` lines)."""
    # the Thread objects, not their idents: an ended thread's ident is
    # handed to the next thread started (a survey's worker)
    others = set(threading.enumerate()) - {threading.current_thread()}

    def show(message, category, filename, lineno, file=None, line=None):
        ours = getattr(category, "__module__", "").split(".")[0] == "orbits"
        if threading.current_thread() in others and not ours:
            return previous(message, category, filename, lineno, file, line)
        return _show_warning(message, category, filename, lineno, file, line)

    return show


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """A warning as one ``orbits: warning:`` line (no source path, no code line)."""
    stream = sys.stderr if file is None else file
    if stream is None:
        return
    try:
        print(f"orbits: warning: {' '.join(str(message).split())}", file=stream, flush=True)
    except (OSError, ValueError):
        pass  # stderr closed: nothing to tell


class _TolerantStream:
    """Standard error for a run: a write that fails is dropped.

    With stderr closed (``2>&-``: ``sys.stderr`` is None) or full
    (``2>/dev/full``) a progress or status line raised in the middle of a
    run (or ``announce_compilation`` failed on None): the command ended in
    a traceback, exit 1, after its output was written.  The run's messages
    have nowhere to go then; its exit code still tells what happened.
    """

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except UnicodeEncodeError:
            # an ASCII stderr (PYTHONIOENCODING=ascii) and a name such as "é"
            # in the message: the line escaped, not lost
            encoding = getattr(self._stream, "encoding", None) or "ascii"
            try:
                self._stream.write(text.encode(encoding, "backslashreplace").decode(encoding))
            except (OSError, ValueError, LookupError):
                pass
            return len(text)
        except (OSError, ValueError):
            return len(text)

    def flush(self):
        try:
            self._stream.flush()
        except (OSError, ValueError):
            pass

    def isatty(self):
        try:
            return bool(self._stream.isatty())
        except (OSError, ValueError):
            return False

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _tolerant_stderr():
    """:class:`_TolerantStream` over ``sys.stderr`` (over ``os.devnull`` when it is closed)."""
    import os

    stream = sys.stderr
    if stream is None or getattr(stream, "closed", False):
        stream = open(os.devnull, "w", encoding="utf-8")  # noqa: SIM115 (closed in main)
    return _TolerantStream(stream)


# one run at a time in a process: a run swaps process-wide state (stderr,
# warnings.showwarning, sys.unraisablehook) and gives it back when it ends,
# which two overlapping runs (threads of a service or a notebook) undid in
# the wrong order
_RUN_LOCK = threading.RLock()


def _new_run_lock():
    global _RUN_LOCK
    _RUN_LOCK = threading.RLock()  # one held by another thread at a fork stays held


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_new_run_lock)


def main(argv=None):
    """Entry point of the ``orbits`` console script; returns the exit code.

    ``argv`` is a list of str, default ``sys.argv[1:]``; ``--help`` and
    ``--version`` return 0 after printing, a usage error 2.  Python
    warnings raised during the run are shown as one ``orbits: warning:``
    line each (``warnings.showwarning`` is replaced for the run and
    restored after; warnings of other threads pass to the handler it
    replaced).  Standard error is written best effort for the run
    (:class:`_TolerantStream`): a closed or full stderr loses the messages,
    never the exit code.  ``--threads`` holds for the run only.  Runs from
    several Python threads take turns (one at a time per process).
    """
    import signal
    import warnings

    from ..atomic import Terminated

    with _RUN_LOCK:
        given_stderr = sys.stderr
        tolerant = sys.stderr = _tolerant_stderr()
        try:
            return _main(argv, signal, warnings, Terminated)
        except SystemExit as done:  # argparse: --help, --version (0) or a usage error (2)
            return done.code if isinstance(done.code, int) else (0 if done.code is None else 2)
        finally:
            sys.stderr = given_stderr
            if tolerant._stream is not given_stderr:  # the os.devnull opened for a closed one
                tolerant._stream.close()


def _refuse_attached_separator(argv):
    """Refuse ``--OPT=--``: argparse reads the attached ``--`` as its separator.

    Python's argparse strips it and hands the option an empty list, past its
    type and choices checks (``--out=--`` was a TypeError traceback,
    ``--theta=--`` an empty table with exit 0).  Tokens after a bare ``--``
    are positional values and left alone.
    """
    for token in argv:
        if token == "--":
            return
        option, equals, value = token.partition("=") if isinstance(token, str) else ("", "", "")
        # only an attached value of exactly "--" (--name=a=-- names "a=--")
        if option.startswith("-") and equals and value == "--":
            raise InputError(
                f"{option}: '--' is not a value (argparse reads it as the end of the "
                f"options); give {option} a value"
            )


def _main(argv, signal, warnings, Terminated):
    """:func:`main` with standard error made tolerant."""
    from contextlib import ExitStack

    previous = _install_signal_handlers()
    shown = warnings.showwarning
    warnings.showwarning = _warning_shower(shown)
    held = ExitStack()
    _PREVIOUS_HOOK.append(sys.unraisablehook)
    sys.unraisablehook = _swallowed_stop
    args = None
    try:
        if argv is not None and (
            isinstance(argv, (str, bytes)) or not all(isinstance(token, str) for token in argv)
        ):
            # a string was parsed letter by letter, a number ended in a TypeError
            raise ArgumentTypeError(
                f"argv must be a list of str (the command line's words), got {argv!r}"
            )
        _refuse_attached_separator(sys.argv[1:] if argv is None else argv)
        args = build_parser().parse_args(argv)
        args.argv = argv
        check_arguments(args)
        _check_stdout(args)
        if args.command in _DRAWING:
            _check_matplotlib()
        if args.threads is not None:
            from ..threads import using_threads

            # for this run only (set_num_threads kept it for the whole process)
            held.enter_context(using_threads(args.threads))
        announce_compilation()
        if not getattr(args, "holds_collector", False):
            # the start-up ends here (orbits.startup); a survey ends it
            # after its first chunk, once pyarrow and its table kernels are loaded
            release_collector()
        code = args.run(args)
        _raise_pending_stop()
        for note in getattr(args, "notes", ()):
            print(f"orbits: note: {note}", file=sys.stderr)
        return code
    except KeyboardInterrupt as stop:
        print(f"orbits: interrupted{_stop_outcome(stop)}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated as stop:
        name = signal.Signals(stop.signum).name
        print(f"orbits: stopped by {name}{_stop_outcome(stop)}", file=sys.stderr)
        return 128 + stop.signum
    except OrbitsError as error:
        print(f"orbits: error: {' '.join(str(error).split())}", file=sys.stderr)
        return EXIT_USAGE
    except MemoryError:
        sizes = _SIZE_OPTIONS.get(getattr(args, "command", None), _SIZE_OPTIONS[None])
        print(f"orbits: error: out of memory; use smaller sizes ({sizes})", file=sys.stderr)
        return EXIT_USAGE
    except ImportError as error:
        # a library that cannot load here, e.g. pyarrow's shared objects under
        # a memory limit ("failed to map segment"): a traceback of 49 lines.
        # One of orbits' own modules (a bug, not the machine) keeps its traceback
        if not error.name or error.name.split(".")[0] == "orbits":
            raise
        print(
            f"orbits: error: cannot load {error.name}: {' '.join(str(error).split())}",
            file=sys.stderr,
        )
        return EXIT_USAGE
    except BrokenPipeError:
        # the reader (e.g. `head`) closed the pipe: not an error of ours
        return 0
    except UnicodeEncodeError as error:
        # printing results (a body name "é") to a stdout of another encoding
        text = error.object[error.start : error.end]
        stream = getattr(sys.stdout, "encoding", None)
        print(
            f"orbits: error: cannot write {text!r} in {error.encoding} (standard output's "
            f"encoding is {stream}); set PYTHONIOENCODING=utf-8 or a UTF-8 locale",
            file=sys.stderr,
        )
        return EXIT_USAGE
    except OSError as error:
        print(
            f"orbits: error: {error.strerror or error}: {error.filename or ''}".rstrip(": "),
            file=sys.stderr,
        )
        return EXIT_USAGE
    finally:
        held.close()
        warnings.showwarning = shown
        sys.unraisablehook = _PREVIOUS_HOOK.pop()
        _end_deferral()
        for number, handler in previous.items():
            if handler is not None:  # None: a handler not installed from Python
                signal.signal(number, handler)
