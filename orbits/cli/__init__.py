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

import sys

from .._version import __version__
from ..errors import OrbitsError
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


def _raise_terminated(signum, frame):
    from ..atomic import Terminated

    raise Terminated(signum)


def _install_signal_handlers():
    """SIGTERM and SIGHUP raise :class:`~orbits.atomic.Terminated` (main thread only)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return {}
    previous = {}
    for name in ("SIGTERM", "SIGHUP"):
        number = getattr(signal, name, None)
        if number is not None:
            previous[number] = signal.signal(number, _raise_terminated)
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


def main(argv=None):
    """Entry point of the ``orbits`` console script; returns the exit code."""
    import signal

    from ..atomic import Terminated

    previous = _install_signal_handlers()
    try:
        args = build_parser().parse_args(argv)
        args.argv = argv
        check_arguments(args)
        if args.threads is not None:
            from ..threads import set_num_threads

            set_num_threads(args.threads)
        announce_compilation()
        return args.run(args)
    except KeyboardInterrupt:
        print("orbits: interrupted; no partial output was written", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated as stop:
        name = signal.Signals(stop.signum).name
        print(f"orbits: stopped by {name}; no partial output was written", file=sys.stderr)
        return 128 + stop.signum
    except OrbitsError as error:
        print(f"orbits: error: {' '.join(str(error).split())}", file=sys.stderr)
        return EXIT_USAGE
    except MemoryError:
        print(
            "orbits: error: out of memory; use smaller sizes (--n-max, --q-max, "
            "--resolution, --chunk, --bodies)",
            file=sys.stderr,
        )
        return EXIT_USAGE
    except BrokenPipeError:
        # the reader (e.g. `head`) closed the pipe: not an error of ours
        sys.stdout = None
        return 0
    except OSError as error:
        print(
            f"orbits: error: {error.strerror or error}: {error.filename or ''}".rstrip(": "),
            file=sys.stderr,
        )
        return EXIT_USAGE
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
