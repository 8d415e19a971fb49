"""A long ``orbits catalog`` run in a child process, stopped by a signal.

Shared by the SIGINT test (test_catalog) and the SIGTERM/SIGHUP tests
(test_file_guarantees).  The signal is sent once the child has used
:data:`BUSY_CPU_SECONDS` of CPU time, not after a fixed wall-clock sleep:
by then it has imported everything and installed its handlers, on a quiet
machine and on a loaded one alike.
"""

import os
import subprocess
import sys
import time

import pandas as pd

import orbits

BUSY_CPU_SECONDS = 2.5


def _cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as handle:
        fields = handle.read().rsplit(")", 1)[1].split()
    # utime and stime (fields 14 and 15 of proc(5), counted from the state)
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def interrupted_catalog(tmp_path, signum, module="orbits", cache_dir=None):
    """Start a long catalog over a previous good file and send ``signum`` mid-run.

    ``cache_dir``: an empty directory for numba's cache (``NUMBA_CACHE_DIR``),
    so that the child compiles every kernel and the signal comes while
    numba compiles.  Returns ``(returncode, stderr lines after the estimate
    line, out path)``.
    """
    bodies = tmp_path / "bodies.csv"
    pd.DataFrame(orbits.region_grid(60), columns=["I1", "I2", "I3"]).to_csv(bodies, index=False)
    out = tmp_path / "out.csv"
    out.write_text("previous good catalog\n")
    argv = [sys.executable, "-m", module, "catalog", "--bodies", str(bodies)]
    argv += ["--n-max", "300", "--q-max", "5", "--out", str(out)]
    env = None if cache_dir is None else dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir))
    proc = subprocess.Popen(argv, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 120
    while proc.poll() is None and time.monotonic() < deadline:
        if _cpu_seconds(proc.pid) >= BUSY_CPU_SECONDS:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be stopped"
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)
    lines = err.strip().splitlines()
    # a long run says its estimate first (here more than a minute, GiB of memory)
    assert lines and lines[0].startswith("orbits catalog: estimated "), lines
    return proc.returncode, lines[1:], out
