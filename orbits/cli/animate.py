"""``orbits animate``: Poinsot's construction in motion, written as GIF or MP4."""

import argparse
import math
import sys

from ..cells import literal_text
from ..errors import InputError
from ..limits import check_animation, short_number
from ..units import OMEGA_UNITS, REVOLUTIONS_NOTE
from .shared import (
    add_body_options,
    announce,
    body_from_args,
    finite,
    integer_at_least,
    offset_argument,
    positive_int,
)


def _cmd_animate(args):
    import time

    import numpy as np

    from .. import animate

    # sizes first, with the options' own names: nothing is computed for a run
    # that cannot fit the machine (a real-time run's frames: round(S x fps) + 1)
    gif = str(args.out).lower().endswith(".gif")
    animate.check_fps(args.fps, "gif" if gif else None, "--fps")
    animate.check_dpi(args.dpi, "--dpi")
    if args.periods is not None and args.periods <= 0:
        raise InputError(f"--periods must be positive, got {args.periods:g}")
    if args.seconds is not None:
        planned = animate.check_real_time(args.seconds, args.fps, "--seconds", "--fps")
    else:
        planned = 120 if args.frames is None else args.frames
    if args.omega is None or args.seconds is not None:
        memory, seconds_estimate = check_animation(
            planned,
            args.dpi,
            keep_frames=gif,
            frames_name="--seconds" if args.seconds is not None else "--frames",
            dpi_name="--dpi",
        )
    body = body_from_args(args)
    spins = [
        args.theta is not None,
        args.dtheta is not None,
        args.n is not None,
        args.p is not None,
        args.flip is not None,
        args.omega is not None,
    ]
    if sum(spins) != 1:
        raise InputError(
            "orbits animate: give exactly one spin: --theta, --dtheta, --n, --p/--q, "
            "--flip or --omega"
        )
    if args.q is not None and args.p is None:
        raise InputError("orbits animate: --q needs --p")
    if args.dtheta is not None:
        # as orbits phase: a subnormal offset keeping fewer than 12 digits is refused
        offset_argument(args.dtheta, args)
    if "units" in getattr(args, "given", ()) and args.omega is None and args.speed is None:
        raise InputError("--units applies to --omega and --speed, and neither was given")
    if args.speed is not None and (args.omega is not None or args.n or args.p):
        raise InputError("orbits animate: --speed applies to --theta, --dtheta and --flip")
    if args.seconds is not None and (args.frames is not None or args.periods is not None):
        raise InputError("orbits animate: --seconds (real time) or --frames/--periods, not both")
    if args.omega is not None and args.frames is not None:
        raise InputError(
            "orbits animate: --omega plays in real time: its length is --seconds "
            "(or --periods) at --fps, not --frames"
        )
    factor = OMEGA_UNITS[args.units]
    speed = 1.0 if args.speed is None else args.speed * factor
    solid = args.solid
    if solid == "auto" and args.t_handle is not None:
        solid = ("t-handle",) + tuple(args.t_handle)
    start = time.perf_counter()
    from ..motion import Motion

    rate = f"|omega0| = {speed / factor:g} {args.units}"
    if args.flip is not None:
        source = animate.flip_motion(body, offset=args.flip, speed=speed)
    elif args.n is not None or args.p is not None:
        source = animate.orbit_row(body, n=args.n, p=args.p, q=args.q or 1, branch=args.branch)
    elif args.omega is not None:
        source = Motion.from_omega(body, np.array(args.omega) * factor, axes="body")
    else:
        source = Motion.from_spin(body, args.theta, dtheta=args.dtheta, phi=args.phi, speed=speed)
    # what will be drawn: a catalog row is the body's motion at the row's dtheta
    motion, default_periods, _ = animate.animation_motion(source, body=body)
    if args.periods is not None and args.omega is None:
        if not math.isfinite(args.periods * motion.period):
            raise InputError(
                f"--periods {args.periods:g} of T = {motion.period:.4g} s is beyond a "
                "double's range; give fewer --periods"
            )
    seconds = args.seconds
    if args.omega is not None and seconds is None:
        # a throw plays in real time: one period, or --periods of them
        seconds = (1.0 if args.periods is None else args.periods) * source.period
        planned = _throw_frames(args, seconds, source.period, gif)
        memory, seconds_estimate = check_animation(
            planned,
            args.dpi,
            keep_frames=gif,
            frames_name="--seconds or --periods",
            dpi_name="--dpi",
        )
    # the frames' last time as poinsot_animation forms it: within Motion's
    # range of times (2**50 periods), checked here, not after the estimate
    if seconds is not None:
        periods = float(seconds) / motion.period
    elif args.periods is not None:
        periods = args.periods
    else:
        periods = default_periods
    animate.check_span(motion, periods * motion.period)
    animate.check_output(args.out, "--out")
    # every input checked: say how long the drawing will take
    announce("animate", seconds_estimate, memory)
    title = None
    if args.flip is not None:
        title = (
            f"{literal_text(body.name or 'body')}: the Dzhanibekov (tennis-racket) flip, spin "
            f"on $I_2$ tipped {args.flip:g} rad towards $I_1$ and $I_3$\n"
            f"at {rate}: T = {source.period:.4g} s, "
            f"flips every T/2 = {0.5 * source.period:.4g} s"
        )
    elif args.omega is not None:
        spin = ", ".join(f"{v:g}" for v in args.omega)
        name = literal_text(body.name or "body")
        title = (
            f"{name} thrown at omega = ({spin}) {args.units} (body axes), "
            f"{source.branch}\nT = {source.period:.4g} s, omega along $I_2$ reverses "
            f"every T/2 = {0.5 * source.period:.4g} s"
        )
    elif args.n is None and args.p is None:
        title = (
            f"{literal_text(body.name or 'body')}: Poinsot construction, {source.branch}, "
            f"T = {source.period:.4g} s at {rate}"
        )
    drawn = animate.poinsot_animation(
        source,
        periods=args.periods if args.omega is None else None,
        frames=args.frames,
        fps=args.fps,
        dpi=args.dpi,
        solid=solid,
        out=args.out,
        title=title,
        body=body if args.n is not None or args.p is not None else None,
        seconds=seconds,
    )
    count = len(drawn.times)
    span = drawn.times[-1]
    turns = span / drawn.motion.period
    pace = " (real time)" if seconds is not None else ""
    print(
        f"orbits animate: {count} frames over {span:.4g} s = {turns:.4g} "
        f"{'period' if turns == 1 else 'periods'} at {args.fps} frames/s{pace} written to "
        f"{args.out} in {time.perf_counter() - start:.1f} s",
        file=sys.stderr,
    )
    return 0


def _throw_frames(args, seconds, period, gif):
    """The frames of --omega in real time (``seconds`` of it), from 2 to MAX_FRAMES."""
    from ..animate import GIF_FPS, MAX_FRAMES, real_time_frames

    fps = args.fps
    frames = real_time_frames(seconds, fps)
    if args.periods is None:
        span = f"one period T = {period:.6g} s"
    else:
        span = f"--periods {args.periods:g} of T = {period:.6g} s ({seconds:.6g} s)"
    what = (
        f"--omega plays {span} in real time: at --fps {fps} that is "
        f"{short_number(frames)} {'frame' if frames == 1 else 'frames'}"
    )
    if frames > MAX_FRAMES:
        # the suggested bounds keep half a frame's margin from round(S x fps)
        lower_fps = ", or a lower --fps" if real_time_frames(seconds, 1) <= MAX_FRAMES else ""
        raise InputError(
            f"{what}, more than {MAX_FRAMES}: give --seconds of at most "
            f"{(MAX_FRAMES - 1) / fps:g} or --periods of at most "
            f"{(MAX_FRAMES - 2) / (fps * period):.4g}{lower_fps}"
        )
    if frames < 2:
        from ..motion import TIME_LIMIT_PERIODS

        top = max(GIF_FPS) if gif else 100
        if 1.0 / (top * period) > TIME_LIMIT_PERIODS:
            # even one frame interval at the highest rate is beyond what the
            # motion can place: no --seconds, --periods or --fps would do
            raise InputError(
                f"{what}, and one frame interval (1/{top} s) is {1.0 / (top * period):.3g} "
                f"periods, beyond the {TIME_LIMIT_PERIODS:.3g} (2^50) the motion can place: "
                "too fast to animate in real time; give a slower --omega (the orbit's "
                "shape does not depend on |omega|)"
            )
        higher_fps = ", or a higher --fps" if real_time_frames(seconds, top) >= 2 else ""
        raise InputError(
            f"{what}, and an animation needs at least 2: give --seconds of at least "
            f"{1 / fps:g} or --periods of at least {1 / (fps * period):.4g}{higher_fps}"
        )
    return frames


def _positive(text):
    value = finite(text)
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f"must be positive, got {text!r}")
    return value


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
        "--theta",
        type=finite,
        help="polar angle of omega0 from I3 (rad, within [-2 pi, 2 pi])",
    )
    spin.add_argument(
        "--dtheta",
        type=finite,
        help="offset theta - theta_crit (rad, not folded: theta_crit + dtheta must lie "
        "in [0, pi/2], i.e. dtheta in [-theta_crit, pi/2 - theta_crit], and not be 0; "
        "as in orbits phase, subnormal offsets below |dtheta| = 4.941e-312 are refused)",
    )
    spin.add_argument("--n", type=positive_int, help="the closed orbit Delta alpha = 2 pi n")
    spin.add_argument(
        "--p", type=positive_int, help="the closed orbit 2 pi p/q (with --q; default q = 1)"
    )
    spin.add_argument("--q", type=positive_int, help="see --p")
    spin.add_argument(
        "--omega",
        nargs=3,
        type=finite,
        metavar=("W1", "W2", "W3"),
        help="a real throw: the angular velocity along the body's own axes (x y z "
        "of --box, the order of --moments, a b c of --rotational-constants), "
        "in --units; plays in real time: "
        "one period T, --periods X of them, or --seconds S (not --frames)",
    )
    spin.add_argument(
        "--flip",
        type=_flip_offset,
        nargs="?",
        const=0.05,
        metavar="OFFSET",
        help="spin near the intermediate axis I2, tipped OFFSET rad towards I1 and "
        "OFFSET rad towards I3 (theta = phi = pi/2 - OFFSET; about sqrt(2) OFFSET "
        "from I2), 0 < OFFSET < pi/4 (default 0.05): the tennis-racket flip",
    )
    parser.add_argument(
        "--phi",
        type=finite,
        default=0.0,
        help="azimuth of omega0 from I1 with --theta/--dtheta (rad, within "
        "[-2 pi, 2 pi]; default 0)",
    )
    parser.add_argument(
        "--branch",
        choices=["SAM", "LAM"],
        help="with --n or --p: the branch, when both have the orbit",
    )
    parser.add_argument(
        "--units",
        choices=list(OMEGA_UNITS),
        default="rad/s",
        help="unit of --omega and --speed (default rad/s); times are then in s; "
        + REVOLUTIONS_NOTE,
    )
    parser.add_argument(
        "--speed",
        type=_positive,
        metavar="W",
        help="|omega0| of --theta, --dtheta or --flip, in --units (default 1 rad/s)",
    )
    parser.add_argument(
        "--periods",
        type=finite,
        help="duration in periods T (default q for an orbit, else 1; in real time with --omega)",
    )
    parser.add_argument(
        "--seconds",
        type=_positive,
        metavar="S",
        help="real time: S seconds of the motion played in S seconds "
        "(round(S x fps) + 1 frames); not with --frames/--periods",
    )
    parser.add_argument(
        "--frames",
        type=integer_at_least(2),
        help="number of frames, >= 2 (default 120; not with --seconds or --omega)",
    )
    parser.add_argument(
        "--fps",
        type=positive_int,
        default=20,
        help="frames per second, 1 to 100 (default 20); a .gif plays only "
        "1, 2, 4, 5, 10, 20, 25 or 50 at their speed",
    )
    parser.add_argument(
        "--dpi",
        type=positive_int,
        default=120,
        help="pixels per inch of the 9 x 4 in frames (default 120: 1080 x 480 px)",
    )
    parser.add_argument(
        "--solid",
        choices=["auto", "ellipsoid"],
        default="auto",
        help="the solid drawn: auto (default: the body's shape when known, "
        "else its equivalent ellipsoid) or ellipsoid",
    )
    parser.add_argument(
        "--out",
        required=True,
        metavar="FILE.gif|FILE.mp4",
        help="output file; the suffix picks the format",
    )
    parser.set_defaults(run=_cmd_animate)
