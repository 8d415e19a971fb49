"""Whole-command ``orbits survey`` scaling on CPU sets: fresh processes, interleaved.

Usage::

    python benchmarks/scale.py RES NMAX REPS CPUSET [CPUSET ...]

    python benchmarks/scale.py 500 30 9 0 0,1     # the figures in docs/benchmarks.md

Each CPU set is written as ``taskset -c`` takes it: ``0``, ``0,1``,
``0-15``, ``0-3,8``.  For each of ``REPS`` repetitions and, within it, each
CPU set in the order given (so the sets are interleaved and a drift of the
machine's speed touches them all alike), one fresh process runs::

    python -m orbits survey --resolution RES --n-max NMAX --out TMPDIR/s

pinned to that set with ``os.sched_setaffinity`` before it starts (numba
then uses as many threads as the set has CPUs), into a new temporary
directory that is deleted after the run.  The wall time of the whole
process (interpreter start-up, grid, search, tables, files, report) is
measured from the parent.  One line per run is printed as it ends, then per
set the median and smallest wall seconds and the ratio of the first set's
median to this set's median (above 1: this set is faster than the first).

Exit status: 0; 1 when a survey process failed (its status and the last
line of its standard error are printed); 2, with one line, for a usage
error or a CPU not in this process's own affinity (``os.sched_getaffinity``;
Linux only).  The command runs the ``orbits`` that ``python -m orbits``
imports from this interpreter.
"""

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

USAGE = "usage: python benchmarks/scale.py RES NMAX REPS CPUSET [CPUSET ...]"


class UsageError(Exception):
    """A command line this script cannot run (exit 2, one line)."""


def parse_cpus(text):
    """The set of CPU numbers in ``text`` (``0``, ``0,1``, ``0-15``, ``0-3,8``)."""
    cpus = set()
    for part in text.split(","):
        first, dash, last = part.partition("-")
        try:
            low = int(first)
            high = int(last) if dash else low
        except ValueError:
            raise UsageError(f"not a CPU set: {text!r} (write it like 0, 0,1 or 0-15)") from None
        if low < 0 or high < low:
            raise UsageError(f"not a CPU set: {text!r} (write it like 0, 0,1 or 0-15)")
        cpus.update(range(low, high + 1))
    return cpus


def parse_args(argv):
    """``(resolution, n_max, reps, [(label, cpus), ...])`` from the command line."""
    if len(argv) < 4:
        raise UsageError(USAGE)
    try:
        resolution, n_max, reps = (int(value) for value in argv[:3])
    except ValueError:
        raise UsageError(f"RES, NMAX and REPS must be whole numbers; {USAGE}") from None
    if resolution < 2 or n_max < 1 or reps < 1:
        raise UsageError(f"need RES >= 2, NMAX >= 1 and REPS >= 1; {USAGE}")
    sets = [(label, parse_cpus(label)) for label in argv[3:]]
    labels = [label for label, _ in sets]
    if len(set(labels)) != len(labels):
        raise UsageError("each CPU set may be given once")
    if not hasattr(os, "sched_getaffinity"):
        raise UsageError("needs os.sched_getaffinity and os.sched_setaffinity (Linux)")
    allowed = os.sched_getaffinity(0)
    for label, cpus in sets:
        outside = sorted(cpus - allowed)
        if outside:
            raise UsageError(
                f"CPU set {label}: CPU(s) {','.join(map(str, outside))} not available to "
                f"this process (its affinity: {','.join(map(str, sorted(allowed)))})"
            )
    return resolution, n_max, reps, sets


def run_once(resolution, n_max, cpus):
    """Wall seconds of one survey process pinned to ``cpus``; raises
    RuntimeError (one line) when the process fails."""
    directory = tempfile.mkdtemp(prefix="orbits-scale-")
    argv = [sys.executable, "-m", "orbits", "survey", "--resolution", str(resolution)]
    argv += ["--n-max", str(n_max), "--out", os.path.join(directory, "s")]
    try:
        start = time.perf_counter()
        done = subprocess.run(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=lambda: os.sched_setaffinity(0, cpus),
        )
        wall = time.perf_counter() - start
    finally:
        shutil.rmtree(directory, ignore_errors=True)
    if done.returncode != 0:
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        last = f": {lines[-1].strip()}" if lines else ""
        raise RuntimeError(f"exit {done.returncode}: {' '.join(argv[1:])}{last}")
    return wall


def main(argv=None):
    try:
        resolution, n_max, reps, sets = parse_args(sys.argv[1:] if argv is None else argv)
    except UsageError as error:
        print(f"scale.py: error: {error}", file=sys.stderr)
        return 2
    walls = {label: [] for label, _ in sets}
    for rep in range(reps):
        for label, cpus in sets:
            try:
                wall = run_once(resolution, n_max, cpus)
            except RuntimeError as error:
                print(f"scale.py: error: CPUs {label}: survey failed ({error})", file=sys.stderr)
                return 1
            walls[label].append(wall)
            print(f"rep {rep + 1}/{reps}  CPUs {label:<12} {wall:8.3f} s wall", flush=True)
    first = sets[0][0]
    base = statistics.median(walls[first])
    print(
        f"\norbits survey --resolution {resolution} --n-max {n_max}: wall seconds of "
        f"{reps} fresh process(es) per CPU set, taken in turns"
    )
    print(f"{'CPUs':<12} {'median':>9} {'min':>9} {f'median ratio {first} / set':>24}")
    for label, _ in sets:
        median = statistics.median(walls[label])
        print(f"{label:<12} {median:>7.3f} s {min(walls[label]):>7.3f} s {base / median:>23.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
