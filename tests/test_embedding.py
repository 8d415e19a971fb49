"""The package inside a long-lived process (a notebook kernel, a service, a
dask worker): ``orbits.cli.main`` called again and from threads, and the
process-wide state it and the writers touch given back as it was."""

import io
import os
import sys
import threading
import warnings

import numpy as np
import pytest

import orbits
from orbits import Body, poinsot_animation, write_catalog
from orbits.cli import main

FIG6 = Body.preset("fig6")
PHASE = ["phase", "--preset", "fig6", "--theta", "0.5"]


def _quiet(argv):
    out, err = io.StringIO(), io.StringIO()
    stdout, stderr = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = out, err
    try:
        return main(argv), out.getvalue(), err.getvalue()
    finally:
        sys.stdout, sys.stderr = stdout, stderr


def test_threads_hold_for_the_run_only():
    """--threads 1 left the whole process on one thread for every later call."""
    before = orbits.get_num_threads()
    assert _quiet(["--threads", "1", *PHASE])[0] == 0
    assert orbits.get_num_threads() == before


@pytest.mark.parametrize(
    "argv, code, words",
    [
        (["--version"], 0, None),
        (["--help"], 0, None),
        ("phase --preset fig6 --theta 0.5", 2, "argv must be a list of str"),
        (["phase", "--preset", "fig6", "--theta", 0.5], 2, "argv must be a list of str"),
    ],
)
def test_main_returns_its_exit_code(argv, code, words):
    """--help raised SystemExit; a string was parsed letter by letter
    ("invalid choice: 'p'"), a number among the words was a TypeError traceback."""
    got, out, err = _quiet(argv)
    assert got == code
    if words:
        assert err.count("\n") == 1 and words in err, err
    else:
        assert out


def test_runs_from_threads_take_turns_and_give_the_warnings_back(tmp_path):
    """Two runs at once swapped warnings.showwarning and the filters back in
    the wrong order: every later warning of the process went to a dead list."""
    bodies = tmp_path / "bodies.csv"
    bodies.write_text("I1,I2,I3\n" + "0.26,0.55,0.793662\n" * 6)
    main(["catalog", "--preset", "fig6", "--n-max", "3", "--out", str(tmp_path / "warm.csv")])
    filters, show, stderr = list(warnings.filters), warnings.showwarning, sys.stderr
    codes = []

    def run(k):
        argv = ["catalog", "--bodies", str(bodies), "--n-max", "420"]
        codes.append(main([*argv, "--out", str(tmp_path / f"c{k}.csv")]))

    threads = [threading.Thread(target=run, args=(k,)) for k in range(3)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert codes == [0, 0, 0]
    assert warnings.filters == filters and warnings.showwarning is show
    assert sys.stderr is stderr
    with pytest.warns(UserWarning, match="after the runs"):
        warnings.warn("after the runs", UserWarning, stacklevel=1)


def test_a_run_in_a_thread_leaves_other_threads_warnings_alone(tmp_path):
    """A command in a background thread printed the main thread's own
    warnings as 'orbits: warning:' lines, past the user's handler."""
    seen = [0]

    def count(message, *rest, **kw):
        seen[0] += 1

    main(["survey", "--resolution", "6", "--n-max", "3", "--out", str(tmp_path / "warm")])
    previous, filters = warnings.showwarning, list(warnings.filters)
    warnings.showwarning = count
    try:
        done = threading.Event()

        def run():
            argv = ["survey", "--resolution", "30", "--n-max", "5"]
            _quiet([*argv, "--out", str(tmp_path / "s")])
            done.set()

        warnings.simplefilter("always")
        thread = threading.Thread(target=run)
        thread.start()
        sent = 0
        while sent < 2000:  # one every 2 ms while the run lasts, at least one
            warnings.warn(f"user warning {sent}", RuntimeWarning, stacklevel=1)
            sent += 1
            if done.wait(0.002):
                break
        thread.join()
    finally:
        warnings.showwarning = previous
        warnings.filters[:] = filters
    assert sent and seen[0] == sent


def test_a_closed_pipe_keeps_the_callers_stdout():
    """A reader that closed the pipe set sys.stdout to None for the rest of
    the process (a kernel's later prints went nowhere)."""

    class ClosedPipe(io.StringIO):
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

    pipe, stdout = ClosedPipe(), sys.stdout
    sys.stdout = pipe
    try:
        assert main(PHASE) == 0
        assert sys.stdout is pipe
    finally:
        sys.stdout = stdout


def _umask_in_proc():
    try:
        with open("/proc/self/status") as status:
            return any(line.startswith("Umask:") for line in status)
    except OSError:
        return False


@pytest.mark.skipif(not _umask_in_proc(), reason="no Umask: line in /proc/self/status")
def test_a_new_file_takes_the_umask_without_setting_it(tmp_path, monkeypatch):
    """The writers read the umask by setting it to 0 for an instant: a file
    another thread created then was world-writable."""
    frame = orbits.catalog(FIG6, n_max=2)

    def refuse(mask):
        raise AssertionError("os.umask was called")

    old = os.umask(0o027)
    try:
        monkeypatch.setattr(os, "umask", refuse)
        write_catalog(frame, tmp_path / "c.csv")
    finally:
        monkeypatch.undo()
        os.umask(old)
    assert os.stat(tmp_path / "c.csv").st_mode & 0o777 == 0o640


def test_one_animation_saved_from_two_threads(tmp_path):
    """Both renders drew on the one figure: the two GIFs mixed frames, silently."""
    drawn = poinsot_animation(FIG6, 0.9, frames=20, dpi=40)
    reference = drawn.save(tmp_path / "ref.gif").read_bytes()
    threads = [
        threading.Thread(target=drawn.save, args=(tmp_path / f"{k}.gif",)) for k in range(2)
    ]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for k in range(2):
        assert (tmp_path / f"{k}.gif").read_bytes() == reference
    assert np.array_equal(
        drawn.render(3), poinsot_animation(FIG6, 0.9, frames=20, dpi=40).render(3)
    )


def test_a_library_that_cannot_load_is_one_line(tmp_path, monkeypatch):
    """pyarrow's shared objects failing to map under a memory limit ended a
    survey in a 49-line ImportError traceback, exit 1."""
    from orbits.survey import runner

    def cannot_load(self, *args, **kwargs):
        raise ImportError(
            "libarrow.so.2600: failed to map segment from shared object", name="pyarrow.lib"
        )

    monkeypatch.setattr(runner.Survey, "run", cannot_load)
    code, out, err = _quiet(
        ["survey", "--resolution", "6", "--n-max", "3", "--out", str(tmp_path / "s")]
    )
    assert code == 2
    assert err.strip().splitlines()[-1] == (
        "orbits: error: cannot load pyarrow.lib: libarrow.so.2600: failed to map segment "
        "from shared object"
    )
    assert "Traceback" not in err


def test_an_import_error_of_orbits_itself_keeps_its_traceback(tmp_path, monkeypatch):
    """A bug in the package (a name that is not there) is not the machine's
    fault: it is not turned into a one-line 'cannot load' error."""
    from orbits.survey import runner

    def broken(self, *args, **kwargs):
        raise ImportError("cannot import name 'write_stdot'", name="orbits.atomic")

    monkeypatch.setattr(runner.Survey, "run", broken)
    with pytest.raises(ImportError, match="write_stdot"):
        _quiet(["survey", "--resolution", "6", "--n-max", "3", "--out", str(tmp_path / "s")])
