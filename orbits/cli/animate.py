"""``orbits animate``: Poinsot's construction in motion, written as GIF or MP4."""

import argparse
import math
import sys

from ..cells import literal_text
from ..errors import InputError
from ..limits import check_animation
from .shared import add_body_options, announce, body_from_args, finite, positive_int


def _cmd_animate(args):
    import time

    from .. import animate

    # sizes first, with the options' own names: nothing is computed for a run
    # that cannot fit the machine
    memory, seconds = check_animation(
        args.frames,
        args.dpi,
        keep_frames=str(args.out).lower().endswith(".gif"),
        frames_name="--frames",
        dpi_name="--dpi",
    )
    body = body_from_args(args)
    spins = [
        args.theta is not None,
        args.dtheta is not None,
        args.n is not None,
        args.p is not None,
        args.flip is not None,
    ]
    if sum(spins) != 1:
        raise InputError(
            "orbits animate: give exactly one spin: --theta, --dtheta, --n, --p/--q or --flip"
        )
    if args.q is not None and args.p is None:
        raise InputError("orbits animate: --q needs --p")
    solid = args.solid
    if solid == "auto" and args.t_handle is not None:
        solid = ("t-handle",) + tuple(args.t_handle)
    start = time.perf_counter()
    if args.flip is not None:
        source = animate.flip_motion(body, offset=args.flip)
    elif args.n is not None or args.p is not None:
        source = animate.orbit_row(body, n=args.n, p=args.p, q=args.q or 1, branch=args.branch)
    else:
        from ..motion import Motion

        source = Motion.from_spin(body, args.theta, dtheta=args.dtheta, phi=args.phi)
    _check_out(args.out)
    # every input checked: say how long the drawing will take
    announce("animate", seconds, memory)
    title = None
    if args.flip is not None:
        title = (
            f"{literal_text(body.name or 'body')}: the Dzhanibekov (tennis-racket) flip, spin "
            f"{args.flip:g} rad from the intermediate axis $I_2$, "
            f"T = {source.period:.4g} s"
        )
    drawn = animate.poinsot_animation(
        source,
        periods=args.periods,
        frames=args.frames,
        fps=args.fps,
        dpi=args.dpi,
        solid=solid,
        out=args.out,
        title=title,
        body=body if args.n is not None or args.p is not None else None,
    )
    print(
        f"orbits animate: {len(drawn.times)} frames over "
        f"{drawn.times[-1] / drawn.motion.period:.4g} periods written to {args.out} "
        f"in {time.perf_counter() - start:.1f} s",
        file=sys.stderr,
    )
    return 0


def _check_out(path):
    """The output's format and directory, checked before the estimate is announced."""
    from pathlib import Path

    from ..animate import FORMATS
    from ..atomic import ensure_writable

    suffix = Path(path).suffix
    if suffix.lstrip(".").lower() not in FORMATS:
        raise InputError(f"unknown animation format {suffix!r}; use .gif or .mp4")
    ensure_writable(path)


def _flip_offset(text):
    value = finite(text)
    if not 0.0 < value < 0.25 * math.pi:
        raise argparse.ArgumentTypeError(f"must be in (0, pi/4), got {value}")
    return value


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "animate",
        help="animate Poinsot's construction for a body and spin (GIF/MP4)",
        description="Poinsot's construction in motion: in the space frame (L "
        "fixed, along z) the body as a solid, omega, L, the "
        "invariable plane, the inertia ellipsoid x.I.x = 1 rolling "
        "on it and the herpolhode being traced; in the body frame "
        "the polhode being traced.  The spin is given by its polar "
        "angle (--theta or --dtheta, with --phi), by a closed orbit "
        "of the catalog (--n, or --p and --q; --branch when both "
        "branches have it; drawn over q periods, so the last frame "
        "is the first), or --flip (a spin near the intermediate "
        "axis: the Dzhanibekov flip).  Written atomically and "
        "deterministically: .gif (Pillow) or .mp4 (needs the "
        "optional extra 'animation', imageio-ffmpeg).",
    )
    add_body_options(parser)
    spin = parser.add_argument_group("spin (exactly one)")
    spin.add_argument(
        "--theta", type=finite, help="polar angle of omega0 from I3 (rad, within [-2 pi, 2 pi])"
    )
    spin.add_argument(
        "--dtheta", type=finite, help="offset theta - theta_crit (rad, within [-2 pi, 2 pi])"
    )
    spin.add_argument("--n", type=positive_int, help="the closed orbit Delta alpha = 2 pi n")
    spin.add_argument("--p", type=positive_int, help="the closed orbit 2 pi p/q (with --q)")
    spin.add_argument("--q", type=positive_int, help="see --p")
    spin.add_argument(
        "--flip",
        type=_flip_offset,
        nargs="?",
        const=0.05,
        metavar="OFFSET",
        help="spin near the intermediate axis, tipped by OFFSET rad "
        "(default 0.05): the tennis-racket flip",
    )
    parser.add_argument(
        "--phi",
        type=finite,
        default=0.0,
        help="azimuth of omega0 from I1 with --theta/--dtheta (rad, within [-2 pi, 2 pi])",
    )
    parser.add_argument(
        "--branch",
        choices=["SAM", "LAM"],
        help="with --n or --p: the branch, when both have the orbit",
    )
    parser.add_argument(
        "--periods", type=finite, help="duration in periods T (default q for an orbit, else 1)"
    )
    parser.add_argument(
        "--frames", type=positive_int, default=120, help="number of frames (default 120)"
    )
    parser.add_argument(
        "--fps", type=positive_int, default=20, help="frames per second (default 20)"
    )
    parser.add_argument(
        "--dpi",
        type=positive_int,
        default=80,
        help="pixels per inch of the 9 x 4 in frames (default 80)",
    )
    parser.add_argument(
        "--solid",
        choices=["auto", "ellipsoid"],
        default="auto",
        help="the solid drawn: auto (the body's shape when known, "
        "else its equivalent ellipsoid) or ellipsoid",
    )
    parser.add_argument(
        "--out",
        required=True,
        metavar="FILE.gif|FILE.mp4",
        help="output file; the suffix picks the format",
    )
    parser.set_defaults(run=_cmd_animate)
