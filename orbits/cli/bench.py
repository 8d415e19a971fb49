"""``orbits bench``: our kernels against SciPy, timed in one process."""

from ..errors import InputError


def _cmd_bench(args):
    from .. import bench

    known = bench.CUDA_BENCHMARKS if args.device == "cuda" else bench.BENCHMARKS
    unknown = set(args.only or ()) - set(known)
    if unknown:
        raise InputError(
            f"unknown benchmark(s) for --device {args.device}: {', '.join(sorted(unknown))}; "
            f"known: {', '.join(known)}"
        )
    report = bench.run(
        args.only, quick=args.quick, load=not args.no_load_check, device=args.device
    )
    print(bench.to_json(report) if args.json else bench.format_table(report))
    return 0


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "bench",
        help="time our kernels against SciPy in the same process",
        description="Times each task with our compiled kernels and with the "
        "obvious SciPy alternative, best of several runs after a "
        "warm-up, and prints the ratio.",
    )
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument(
        "--only",
        nargs="+",
        metavar="NAME",
        help="run only these benchmarks (names as in the table; a wrong name lists them)",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="smaller problem sizes (a smoke test, not for the README)",
    )
    parser.add_argument(
        "--device",
        choices=["cpu", "cuda"],
        default="cpu",
        help="cpu (default): our kernels against SciPy; cuda: the same kernels on "
        "an NVIDIA GPU (needs orbits[cuda]) against the CPU path, in angles/s "
        "and bodies/s, the GPU named",
    )
    parser.add_argument(
        "--no-load-check",
        action="store_true",
        help="skip the under-load check (by default each task is "
        "timed again beside a CPU-bound process and must hold "
        "within 2x)",
    )
    parser.set_defaults(run=_cmd_bench)
