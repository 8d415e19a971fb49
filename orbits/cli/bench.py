"""``orbits bench``: our kernels and commands against named baselines, as ratios.

What each row times and compares with is in :mod:`orbits.bench`; most rows
run in this process, ``startup``, ``cold_compile`` and ``survey_scaling``
run fresh processes.  Exit 1 (after the table) when a row fails the
under-load check or its two sides disagree.
"""

import sys

from ..errors import InputError
from .shared import EXIT_CHECK_FAILED

# the --only names, without importing orbits.bench for --help (the same keys
# as orbits.bench.BENCHMARKS and CUDA_BENCHMARKS; tests/test_bench.py)
ROW_NAMES = (
    "startup",
    "cold_compile",
    "phase",
    "motion",
    "motion_near_separatrix",
    "motion_20001",
    "motion_near_separatrix_20001",
    "motion_rate",
    "search",
    "search_evaluations",
    "survey",
    "survey_scaling",
    "survey_threads",
    "search_scaling",
    "survey_bytes",
    "survey_tables",
)
CUDA_ROW_NAMES = ("cuda_phase", "cuda_search")


def _cmd_bench(args):
    from .. import bench

    if args.device == "cuda" and args.no_load_check:
        raise InputError(
            "--no-load-check applies only with --device cpu: the GPU rows have no under-load check"
        )
    report = bench.run(
        args.only, quick=args.quick, load=not args.no_load_check, device=args.device
    )
    print(bench.to_json(report) if args.json else bench.format_table(report), flush=True)
    status = 0
    differ = bench.disagreements(report)
    if differ:
        rows = "; ".join(row["task"] for row in differ)
        print(f"orbits: error: the two sides disagree: {rows}", file=sys.stderr)
        status = EXIT_CHECK_FAILED
    failed = bench.load_failures(report)
    if failed:
        rows = "; ".join(f"{row['task']} slowed {row['load']['slowdown']:.2f}x" for row in failed)
        print(
            f"orbits: error: under-load check failed (limit {bench.LOAD_LIMIT:g}x): {rows}",
            file=sys.stderr,
        )
        status = EXIT_CHECK_FAILED
    return status


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "bench",
        help="time our kernels and commands against named baselines, as ratios",
        description="Times each task two ways and prints the ratio (the "
        "baseline's time over ours).  Each row names its baseline (the SciPy "
        "route, import numpy, the same command warm, the search it replaced, a "
        "Python loop, one CPU or one numba thread, --columns all, or none) and "
        "says what was timed: phase, motion*, motion_rate and search the best of "
        "several runs after a warm-up run, in this process; search_scaling and "
        "survey_tables the best of three of each side, in turns, after a "
        "warm-up; search_evaluations, survey_threads, survey_bytes and survey "
        "one run of each side after a warm-up (survey: one run of each format; "
        "its baseline is timed on a sample of the grid's bodies, the row says "
        "how many, and scaled to all of them); startup, cold_compile and "
        "survey_scaling fresh processes (medians; one cold and one warm run; "
        "best of several).  The GPU rows (--device cuda) compare the public "
        "call end to end on the GPU and on the CPU; the kernel alone is in "
        "their note.  Rows that "
        "compare threads use the count in effect (orbits --threads N).  Rows "
        "that compare results (search_evaluations, survey, cuda_search) check "
        "that both sides agree; when one does not, the command exits 1 after "
        "the table, naming it.  Then, "
        "on the CPU, the under-load check: each row's own task again beside a "
        "CPU-bound process; when a row slows down more than 2x the command "
        "exits 1 after the table, naming it.",
    )
    parser.add_argument("--json", action="store_true", help="print JSON (no NaN: null)")
    parser.add_argument(
        "--only",
        nargs="+",
        metavar="NAME",
        help="run only these rows, each named once: "
        + ", ".join(ROW_NAMES)
        + " (CPU); "
        + ", ".join(CUDA_ROW_NAMES)
        + " (--device cuda); the name field of --json",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="smaller problem sizes, or fewer repeats where the size is the row's "
        "(motion, search); cold_compile runs as it is (a smoke test, not for the README)",
    )
    parser.add_argument(
        "--device",
        choices=["cpu", "cuda"],
        default="cpu",
        help="cpu (default): the CPU rows; cuda: total_phase and the survey's "
        "search on an NVIDIA GPU (needs orbits[cuda]) against the same calls on "
        "the CPU, end to end (copies included), in angles/s and bodies/s, the "
        "kernel alone in the note, the GPU named (no under-load check)",
    )
    parser.add_argument(
        "--no-load-check",
        action="store_true",
        help="skip the under-load check (CPU rows only; by default each row's "
        "own task is timed again beside a CPU-bound process, and a slowdown "
        "above 2x makes the command exit 1)",
    )
    parser.set_defaults(run=_cmd_bench)
