"""``orbits survey``: the closed-orbit search over many bodies, and ``--check`` of a survey."""

import math
import sys

from ..atomic import Terminated
from ..errors import InputError, OrbitsError
from ..limits import check_resolution
from .shared import (
    EXIT_CHECK_FAILED,
    announce,
    bodies_file_from_args,
    integer_at_least,
    positive_int,
    progress_bar,
    report_skipped,
)


def _cmd_survey(args):
    import time

    from ..survey import Survey, check_survey

    if args.check:
        from ..startup import release_collector

        release_collector()  # --check reads every part: no start-up hold
        return _check_survey_directory(args, check_survey)
    if args.out is None:
        raise InputError("orbits survey: --out DIR is required (or --check DIR)")
    if args.out == "-":
        raise InputError(
            "orbits survey writes a directory of parts; --out - (standard output) "
            "cannot take them: give a directory"
        )
    from ..atomic import refuse_link

    refuse_link(args.out.rstrip("/") or args.out)  # before the estimate, the grid, any file
    from ..survey import check_unlocked

    check_unlocked(args.out)  # "another run holds it" as the one line, not after an estimate
    if args.n_max is None:
        raise InputError("orbits survey: the following arguments are required: --n-max")
    if (args.resolution is None) == (args.bodies is None):
        raise InputError("orbits survey: give exactly one of --resolution N and --bodies FILE")
    if args.skip_invalid and args.bodies is None:
        raise InputError("--skip-invalid applies to a --bodies file")
    if args.scheduler is not None and not args.scheduler.strip():
        raise InputError("--scheduler is empty; give tcp://HOST:PORT")
    if args.scheduler is not None and args.device == "cuda":
        # before the GPU is looked for: the two never go together
        raise InputError(
            "--device cuda searches on this machine's GPU; the workers of --scheduler "
            "search on their CPUs: give one or the other"
        )
    if args.scheduler is not None and getattr(args, "threads", None) is not None:
        # the chunks run in the workers' processes, which never see it
        raise InputError(
            "--threads sets this machine's threads; the workers of --scheduler search "
            "with their own (dask worker --nthreads N, NUMBA_NUM_THREADS on the worker)"
        )
    options = dict(
        q_max=args.q_max,
        fmt=args.format,
        chunk=args.chunk,
        columns=args.columns or "compact",
        device=args.device,
    )
    from ..survey import survey_estimate

    announced = False
    if args.resolution is not None:
        # say it before building the grid, which itself takes seconds when large
        from ..survey import GRID_INSIDE, Ledger, check_survey_bounds

        check_resolution(args.resolution, "--resolution")
        count = max(1, int(GRID_INSIDE * args.resolution**2))
        check_survey_bounds(count, args.n_max, args.q_max, args.chunk)
        # the directory judged on what is known before the grid is built, so
        # that a refusal is one line, not after the estimate (the run checks
        # every parameter again, touching nothing)
        known = {
            "bodies": {"grid": int(args.resolution)},
            "n_max": args.n_max,
            "q_max": args.q_max,
            "format": args.format,
            "chunk": args.chunk,
            "columns": options["columns"],
        }
        # (--out as a link was refused above)
        ledger = Ledger(args.out, known, {"grid": args.resolution}, ())
        ledger.refuse_foreign_directory()
        ledger.refuse_other_parameters(partial=True)
        announce("survey", *reversed(survey_estimate(count, args.n_max, args.q_max, args.chunk)))
        announced = True
        survey = Survey.grid(args.out, args.resolution, args.n_max, **options)
    else:
        table = bodies_file_from_args(args, report=False)
        survey = Survey(
            args.out,
            table.moments,
            {"file": str(args.bodies)},
            args.n_max,
            names=table.names,
            skipped=[message for _, message in table.skipped],
            **options,
        )
        # once the directory has accepted these parameters (a refusal is one
        # line; the run checks them again, touching nothing)
        survey.ledger.refuse_foreign_directory()
        survey.ledger.refuse_other_parameters()
        report_skipped(table)
    memory, seconds = survey_estimate(
        survey.moments.shape[0], survey.n_max, survey.q_max, survey.chunk
    )
    total = survey.moments.shape[0]
    start = time.perf_counter()
    with progress_bar(total, "survey", unit="body") as bar:

        def notify(message):
            bar.write(f"orbits survey: {message}", file=sys.stderr)

        def status(message):
            if sys.stderr.isatty():
                notify(message)

        if not announced:
            announce("survey", seconds, memory)
        try:
            report = survey.run(
                scheduler=args.scheduler, progress=bar.update, notify=notify, status=status
            )
        except (KeyboardInterrupt, Terminated) as stop:
            stop.outcome = _stopped_outcome(survey, args.out)
            raise
    try:
        _finish(args, survey, report, total, start)
    except (KeyboardInterrupt, Terminated) as stop:
        stop.output_complete = True  # the survey and its report.json are written
        raise
    return 0


def _finish(args, survey, report, total, start):
    """After a complete run: the warning of orbits left out, then the summary."""
    import time

    pending = sum(len(survey.chunk_moments(k)) for k in survey.last_todo)
    elapsed = time.perf_counter() - start
    unresolved = report["bodies_with_unresolved_orbits"]
    if unresolved:  # as orbits catalog warns of each such body
        print(
            f"orbits: warning: {unresolved} of {total} bodies "
            f"{'has' if unresolved == 1 else 'have'} closed orbits with "
            f"2 pi p/q <= 2 pi {args.n_max} closer than |dtheta| = 2.2e-308 to the "
            "separatrix, which cannot be stored in double precision; they are left out "
            "(the bodies table's column unresolved counts them)",
            file=sys.stderr,
        )
    try:
        _print_report(args, report, total, pending, elapsed)
        sys.stdout.flush()
    except BrokenPipeError:
        raise  # the reader left (`| head`): main ends quietly
    except OSError as error:
        # the survey is written whole: its summary is report.json
        print(
            f"orbits: warning: the summary could not be printed "
            f"({error.strerror or error}); the survey in {args.out} is complete and "
            "its report.json holds the summary",
            file=sys.stderr,
        )


def _stopped_outcome(survey, out):
    """The end of a stopped run's line: what the directory holds and how to go on.

    Counted from the manifest on disk (a chunk is recorded in memory just
    before its manifest is written, and the stop can come between).
    """
    from pathlib import Path

    from ..survey.ledger import MANIFEST, load_manifest, missing_chunks

    left = survey.chunks  # no manifest yet: no chunk recorded
    if (Path(out) / MANIFEST).is_file():
        try:
            left = len(missing_chunks(load_manifest(out)))
        except OrbitsError:  # a manifest that cannot be read: say nothing of it
            return "; the directory was not checked"
    done = survey.chunks - left
    if done == 0:
        return f"; no chunk was finished in {out}: rerun the same command to start again"
    if left == 0:
        return f"; every chunk is written in {out}: rerun the same command for its report"
    return (
        f"; {done} of {survey.chunks} chunks are written whole in {out} (the survey is "
        "incomplete, and read_survey refuses it): rerun the same command to compute the rest"
    )


def _print_report(args, report, total, pending, elapsed):
    """The survey's summary on standard output (``--json``: its report)."""
    import json

    if args.json:
        print(json.dumps(report, indent=2))
    else:
        conjecture = report["conjecture_minimum_at_the_ends"]
        rate = f", {pending / elapsed:.0f} bodies/s" if pending else ""
        print(
            f"orbits survey: {total} bodies ({pending} computed now in "
            f"{elapsed:.1f} s{rate}), {report['orbits']} closed orbits with "
            + (f"n <= {args.n_max}" if args.q_max == 1 else f"p/q <= {args.n_max}")
            + f", in {args.out}"
        )
        low, high = report["min_total_phase_range"]
        print(
            f"minimum total phase: {low / (2 * math.pi):.6f} to "
            f"{high / (2 * math.pi):.6f} x 2 pi; bodies with a 2 pi orbit: "
            f"{report['bodies_with_a_two_pi_orbit']}"
        )
        if conjecture["held_on_every_body"]:
            print("conjecture (the minimum lies at theta -> 0 or pi/2): held on every body")
        else:
            print(
                f"conjecture (the minimum lies at theta -> 0 or pi/2): FAILED on "
                f"{len(conjecture['counterexamples'])} bodies:"
            )
            for row in conjecture["counterexamples"]:
                print(
                    f"  body {row['body']}: I = ({row['I1']:.6f}, {row['I2']:.6f}, "
                    f"{row['I3']:.6f}), minimum {row['min_total_phase']:.9f} at "
                    f"theta = {row['min_theta']:.9f}"
                )


def _check_survey_directory(args, check_survey):
    """``orbits survey --check DIR``: verify every part, compute nothing."""
    import json

    given = [
        name
        for name in ("resolution", "bodies", "n_max", "scheduler", "out", "columns")
        if getattr(args, name) is not None
    ]
    if given:
        raise InputError(
            f"orbits survey --check takes only the directory (and --json), "
            f"not --{given[0].replace('_', '-')}"
        )
    status = check_survey(args.check)
    if args.json:
        print(json.dumps(status, indent=2))
    else:
        if status["complete"]:
            verdict = "complete, every part and report.json verified"
        elif status["damaged"]:
            verdict = "DAMAGED" + (" and incomplete" if status["missing"] else "")
        else:
            verdict = "NOT complete"
        print(
            f"orbits survey --check {args.check}: {status['verified']} of "
            f"{status['chunks']} chunk(s) verified; {verdict}"
        )
        for line in status["damaged"]:
            print(f"  damaged {line}")
        if status["missing"]:
            print(
                f"  missing: {', '.join(status['missing'][:10])}"
                + (" ..." if len(status["missing"]) > 10 else "")
            )
    return 0 if status["complete"] else EXIT_CHECK_FAILED


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "survey",
        help="minimum phases and closed orbits over many bodies",
        description="Runs the closed-orbit search over the region of physical "
        "asymmetric bodies (the paper's I1-I2 plane, |I| = 1) or an "
        "explicit list, and writes DIR with manifest.json, the "
        "tables bodies/ and orbits/ (partitioned, one file per "
        "chunk) and report.json (the minimum-at-the-ends "
        "conjecture, bodies with a 2 pi orbit, ...).  Each chunk is "
        "written atomically and recorded in the manifest's ledger "
        "(SHA-256 per part); running the same command again checks "
        "every part and computes only the missing or damaged ones; "
        "other parameters in the same DIR are refused; one run at a "
        "time holds DIR (a lock).",
    )
    source = parser.add_mutually_exclusive_group()
    source.add_argument(
        "--resolution",
        type=integer_at_least(2),  # a grid needs two points a side
        metavar="N",
        help="an N x N grid over the bounding box of the region, keeping the points inside it",
    )
    source.add_argument(
        "--bodies", metavar="FILE.csv", help="a CSV with columns I1, I2, I3 (optionally name)"
    )
    source.add_argument(
        "--check",
        metavar="DIR",
        help="verify the survey in DIR against its ledger (SHA-256 of "
        "every part) without computing; exit 1 if it is damaged "
        "or incomplete",
    )
    parser.add_argument(
        "--skip-invalid",
        action="store_true",
        help="with --bodies: skip invalid rows (listed on stderr and "
        "in the manifest) instead of stopping",
    )
    parser.add_argument(
        "--n-max",
        type=positive_int,
        help="largest multiple n (or p/q) of 2 pi searched per body "
        "(required, except with --check)",
    )
    parser.add_argument(
        "--q-max", type=positive_int, default=1, help="also p/q orbits with q up to Q (default 1)"
    )
    parser.add_argument(
        "--format",
        choices=["csv", "parquet"],
        default="parquet",
        help="table format (default parquet: typed, exact, compact; csv is exact too)",
    )
    parser.add_argument(
        "--chunk", type=positive_int, default=20_000, help="bodies per chunk (default 20000)"
    )
    parser.add_argument(
        "--device",
        choices=["cpu", "cuda"],
        default="cpu",
        help="where the search runs: cpu (default, every core) or cuda (an NVIDIA "
        "GPU through numba-cuda: pip install 'orbits[cuda]'; the tables are "
        "built and written on the CPU; not with --scheduler)",
    )
    parser.add_argument(
        "--columns",
        choices=["compact", "all"],
        default=None,
        help="orbit columns kept on disk: compact (default: body, branch, n, q, "
        "dtheta; reading the survey derives the other catalog columns, the "
        "same bits) or all (every catalog column, about 7x the size)",
    )
    parser.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="run the chunks on this dask.distributed scheduler "
        "(needs orbits[distributed]); default: in-process on "
        "all cores",
    )
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.add_argument("--out", metavar="DIR", help="survey directory")
    # the survey releases the start-up's hold on the garbage collector
    # (orbits.startup) after its first chunk, not before the command
    parser.set_defaults(run=_cmd_survey, holds_collector=True)
