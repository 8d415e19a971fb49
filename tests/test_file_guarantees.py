"""What sits on disk is complete: the survey ledger and lock, atomic output."""

import fcntl
import importlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest
from long_run import interrupted_catalog

import orbits
import orbits.survey
from orbits.atomic import csv_float_options, remove_stale_temporaries, write_text_atomic
from orbits.cli import main
from orbits.survey import check_survey, read_survey

# a pid that no process has (above the kernel's pid_max of 2**22)
DEAD_PID = 2**22 + 7
GRID = ["survey", "--resolution", "6", "--n-max", "3", "--format", "csv", "--chunk", "3"]


def files(directory):
    return {
        p.relative_to(directory).as_posix(): p.read_bytes()
        for p in sorted(directory.rglob("*"))
        if p.is_file() and p.name != ".lock"
    }


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("ref") / "s"
    assert main(GRID + ["--out", str(out)]) == 0
    return out


def copy(reference, tmp_path):
    target = tmp_path / "s"
    shutil.copytree(reference, target)
    return target


# ------------------------------------------------------------------ ledger
def test_ledger_records_every_part(reference):
    document = json.loads((reference / "manifest.json").read_text())
    parameters, ledger = document["parameters"], document["parts"]
    assert len(ledger) == -(-parameters["body_count"] // parameters["chunk"])
    bodies, orbits_table = read_survey(reference)
    assert len(bodies) == parameters["body_count"]
    assert sum(entry["bodies"]["rows"] for entry in ledger.values()) == len(bodies)
    assert sum(entry["orbits"]["rows"] for entry in ledger.values()) == len(orbits_table)
    for key, entry in ledger.items():
        assert entry["first_body"] == int(key) * parameters["chunk"]
        part = pd.read_csv(reference / entry["bodies"]["file"], **csv_float_options())
        assert part["body"].tolist() == list(range(entry["first_body"], entry["last_body"] + 1))
    report = json.loads((reference / "report.json").read_text())
    assert report["bodies"] == len(bodies) and report["orbits"] == len(orbits_table)


def test_damaged_parts_are_found_and_recomputed(reference, tmp_path, capsys):
    target = copy(reference, tmp_path)
    (target / "orbits" / "part-00000.csv").unlink()
    part = target / "bodies" / "part-00001.csv"
    part.write_bytes(part.read_bytes()[:-30])
    # --check: exit 1, both named, nothing computed or written
    before = files(target)
    capsys.readouterr()
    assert main(["survey", "--check", str(target)]) == 1
    out = capsys.readouterr().out
    assert "chunk 0: orbits/part-00000.csv is missing" in out
    assert "chunk 1: bodies/part-00001.csv does not match its SHA-256" in out
    assert files(target) == before
    with pytest.raises(orbits.InputError, match="damaged or incomplete"):
        read_survey(target)
    # a rerun recomputes exactly those two chunks and says so
    assert main(GRID + ["--out", str(target)]) == 0
    err = capsys.readouterr().err
    assert "2 part(s) missing or damaged, recomputing" in err
    mine, theirs = files(target), files(reference)
    # the same parts, report and ledger (the ledger's key order may differ)
    assert json.loads(mine.pop("manifest.json")) == json.loads(theirs.pop("manifest.json"))
    assert mine == theirs
    assert check_survey(target)["complete"]


def test_foreign_files_are_ignored(reference, tmp_path, capsys):
    target = copy(reference, tmp_path)
    part = target / "bodies" / "part-00001.csv"
    shutil.copy(part, part.with_name(part.name + ".bak"))
    shutil.copy(part, target / "bodies" / "part-00099.csv")
    bodies, _ = read_survey(target)
    assert len(bodies) == len(read_survey(reference)[0])
    assert bodies["body"].is_unique
    assert main(GRID + ["--out", str(target), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report == json.loads((reference / "report.json").read_text())
    assert (target / "bodies" / "part-00099.csv").exists()  # not ours: left alone


def test_a_stale_temporary_is_removed_a_live_one_kept(reference, tmp_path):
    target = copy(reference, tmp_path)
    stale = target / "orbits" / f".part-00000.csv.{DEAD_PID}.x1.part"
    live = target / "orbits" / f".part-00000.csv.{os.getppid()}.x2.part"
    other = target / "orbits" / f".notes.txt.{DEAD_PID}.x3.part"
    for path in (stale, live, other):
        path.write_bytes(b"partial")
    orbits.survey.Survey.grid(target, 6, 3, fmt="csv", chunk=3).run()
    assert not stale.exists() and live.exists() and other.exists()


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux's /proc")
def test_a_zombie_writers_temporary_is_stale(reference, tmp_path):
    """A killed writer whose parent has not collected it yet is a zombie:
    os.kill(pid, 0) still succeeds, but it will never write again."""
    from orbits.atomic import _pid_alive

    child = subprocess.Popen([sys.executable, "-c", "pass"])
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:  # ended, not yet waited for
        with open(f"/proc/{child.pid}/stat", "rb") as handle:
            if handle.read().rsplit(b")", 1)[1].split()[0] == b"Z":
                break
        time.sleep(0.01)
    try:
        os.kill(child.pid, 0)  # still there for the kernel
        assert not _pid_alive(child.pid)
        assert _pid_alive(os.getppid())
        target = copy(reference, tmp_path)
        stale = target / "orbits" / f".part-00000.csv.{child.pid}.x1.part"
        stale.write_bytes(b"partial")
        orbits.survey.Survey.grid(target, 6, 3, fmt="csv", chunk=3).run()
        assert not stale.exists()
    finally:
        child.wait()


# ------------------------------------------------------------------ lock
def test_a_second_run_is_refused_while_the_lock_is_held(reference, tmp_path, capsys):
    target = copy(reference, tmp_path)
    before = files(target)
    with open(target / ".lock", "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        handle.seek(0)
        handle.truncate()
        handle.write("12345\n")
        handle.flush()
        capsys.readouterr()
        assert main(GRID + ["--out", str(target)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "being written by another orbits run (pid 12345)" in err[0]
    assert files(target) == before


def test_a_held_lock_is_the_only_line_before_any_estimate(tmp_path, capsys):
    """A long survey (its estimate would be announced) into a locked directory:
    one line, the lock's, and nothing created or built."""
    out = tmp_path / "s"
    out.mkdir()
    with open(out / ".lock", "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        handle.write("4242\n")
        handle.flush()
        capsys.readouterr()
        argv = ["survey", "--resolution", "3000", "--n-max", "30", "--out", str(out)]
        assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "being written by another orbits run (pid 4242)" in err[0]
    assert sorted(p.name for p in out.iterdir()) == [".lock"]


def test_a_directory_being_created_is_not_foreign(tmp_path, capsys):
    """Another run (or a killed one) has made DIR/.lock, bodies/, orbits/ but no manifest."""
    out = tmp_path / "s"
    for name in ("bodies", "orbits"):
        (out / name).mkdir(parents=True)
    with open(out / ".lock", "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        capsys.readouterr()
        assert main(GRID + ["--out", str(out)]) == 2
        assert "being written by another orbits run" in capsys.readouterr().err
    # the creator died: the next run takes over
    assert main(GRID + ["--out", str(out)]) == 0
    assert check_survey(out)["complete"]


def test_concurrent_runs_never_break_each_other(tmp_path):
    """Four identical runs at once: each finishes or is refused by the lock."""
    out = tmp_path / "s"
    argv = [
        sys.executable,
        "-m",
        "orbits",
        "survey",
        "--resolution",
        "40",
        "--n-max",
        "4",
        "--chunk",
        "50",
        "--format",
        "csv",
        "--out",
        str(out),
    ]
    runs = [
        subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        for _ in range(4)
    ]
    results = [(run.wait(timeout=600), run.stderr.read()) for run in runs]
    for code, err in results:
        assert code in (0, 2), err
        assert "Traceback" not in err
        if code == 2:
            assert "being written by another orbits run" in err
    assert any(code == 0 for code, _ in results)
    status = check_survey(out)
    assert status["complete"] and status["verified"] == status["chunks"]
    assert not list(out.rglob("*.part"))


# ------------------------------------------------------------------ atomic output
@pytest.mark.parametrize(
    "signum, code, message",
    [
        (signal.SIGTERM, 143, "orbits: stopped by SIGTERM; no partial output was written"),
        (signal.SIGHUP, 129, "orbits: stopped by SIGHUP; no partial output was written"),
    ],
)
def test_termination_leaves_no_partial_file(tmp_path, signum, code, message):
    returncode, err, out = interrupted_catalog(tmp_path, signum)
    assert returncode == code
    assert err == [message]
    assert out.read_text() == "previous good catalog\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bodies.csv", "out.csv"]


@pytest.mark.parametrize(
    "signum, code, message",
    [
        (signal.SIGTERM, 143, "orbits: stopped by SIGTERM; no partial output was written"),
        (signal.SIGINT, 130, "orbits: interrupted; no partial output was written"),
    ],
)
def test_a_stop_while_numba_compiles_is_one_line(tmp_path, signum, code, message):
    # with an empty kernel cache the child spends its first seconds
    # compiling; an exception raised inside llvmlite's ctypes callbacks was
    # dropped there and the run ended in a traceback with exit 1: the stop
    # now waits until the kernel being compiled is done
    cache = tmp_path / "numba-cache"
    cache.mkdir()
    work = tmp_path / "work"
    work.mkdir()
    returncode, err, out = interrupted_catalog(work, signum, cache_dir=cache)
    assert any(cache.rglob("*.nbi"))  # it was compiling when stopped
    assert (returncode, err) == (code, [message])
    assert out.read_text() == "previous good catalog\n"
    assert sorted(p.name for p in work.iterdir()) == ["bodies.csv", "out.csv"]


def test_stale_temporaries_of_the_same_name_only(tmp_path):
    target = tmp_path / "c.csv"
    stale = tmp_path / f".c.csv.{DEAD_PID}.abc.part"
    live = tmp_path / f".c.csv.{os.getpid()}.def.part"
    other_name = tmp_path / f".d.csv.{DEAD_PID}.abc.part"
    for path in (stale, live, other_name):
        path.write_text("x")
    write_text_atomic(target, "new\n")
    assert target.read_text() == "new\n"
    assert not stale.exists() and live.exists() and other_name.exists()
    assert remove_stale_temporaries(tmp_path, "d.csv") == 1


def test_out_dash_writes_a_checked_catalog_to_stdout(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["catalog", "--preset", "fig6", "--n-max", "4", "--out", "-"]) == 0
    out, err = capsys.readouterr()
    assert "written to standard output" in err
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "piped.csv").write_text(out)
    frame = orbits.read_catalog(tmp_path / "piped.csv")
    expected = orbits.closed_orbits(orbits.Body.preset("fig6"), n_max=4)
    pd.testing.assert_frame_equal(frame[expected.columns], expected)


def test_no_output_is_written_through_a_symlink(tmp_path, capsys):
    """--out naming a link is refused (exit 2, one line); the file it points to is untouched.

    An adversarial probe had ``--out link`` with the link to ``/etc/passwd``
    replace that file; a link inside a figure directory was written through.
    """
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    victim = outside / "victim.txt"
    victim.write_text("not yours\n")
    link = tmp_path / "link.csv"
    link.symlink_to(victim)
    table = orbits.closed_orbits(orbits.Body.preset("fig6"), n_max=2)
    with pytest.raises(orbits.InputError, match="symbolic link"):
        orbits.write_catalog(table, link)
    figures = tmp_path / "figs"
    figures.mkdir()
    (figures / "contact_sheet.png").symlink_to(victim)
    runs = [
        ["catalog", "--preset", "fig6", "--n-max", "2", "--out", str(link)],
        ["figures", "--preset", "fig6", "--n-max", "2", "--formats", "png", "--out", str(figures)],
    ]
    for argv in runs:
        capsys.readouterr()
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "symbolic link" in err[-1], err
    assert victim.read_text() == "not yours\n"
    assert link.is_symlink() and (figures / "contact_sheet.png").is_symlink()
    assert not [p for p in tmp_path.rglob("*.part")]


def test_a_file_name_of_255_bytes_can_be_written(tmp_path):
    """The temporary name (NAME.PID.RANDOM.part) must not push it past the limit."""
    table = orbits.closed_orbits(orbits.Body.preset("fig6"), n_max=2)
    for length in (200, 236, 251):
        path = tmp_path / ("c" * (length - 4) + ".csv")
        orbits.write_catalog(table, path)
        assert len(orbits.read_catalog(path)) == len(table)
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


# ------------------------------------------------- issue 20: survey ledger and links
def _edit_manifest(target, edit, forge):
    manifest = target / "manifest.json"
    document = json.loads(manifest.read_text())
    edit(document)
    if forge:
        document["sha256"] = orbits.survey.manifest_checksum(document)
    manifest.write_text(json.dumps(document))


def _same_survey(target, reference):
    mine, theirs = files(target), files(reference)
    assert json.loads(mine.pop("manifest.json")) == json.loads(theirs.pop("manifest.json"))
    assert mine == theirs


def test_the_manifest_carries_its_own_checksum(reference, tmp_path, capsys):
    document = json.loads((reference / "manifest.json").read_text())
    assert document["orbits_survey"] == 3
    assert document["sha256"] == orbits.survey.manifest_checksum(document)
    # indentation is not content: a re-indented manifest still verifies
    target = copy(reference, tmp_path)
    (target / "manifest.json").write_text(json.dumps(document, indent=4, sort_keys=True))
    assert check_survey(target)["complete"]
    # one changed value is damage, in one line
    _edit_manifest(target, lambda d: d["parts"]["0"]["orbits"].update(rows=0), forge=False)
    capsys.readouterr()
    assert main(["survey", "--check", str(target)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "does not match its own SHA-256" in err[0]


@pytest.mark.parametrize(
    "edit, problem",
    [
        (
            lambda d: d["parts"]["0"].update(bodies=d["parts"]["1"]["bodies"]),
            "chunk 0: ledger names 'bodies/part-00001.csv', not the chunk's bodies/part-00000.csv",
        ),
        (
            lambda d: d["parts"].update({"99": d["parts"]["0"]}),
            "chunk 99: not a chunk of this survey",
        ),
        (lambda d: d["parts"]["1"].update(first_body=0), "chunk 1: body ids 0..5"),
        (
            lambda d: d["parts"]["2"]["bodies"].update(rows=2),
            "chunk 2: bodies/part-00002.csv: 2 rows for 3 bodies",
        ),
        (
            # the orbits' count, which only read_survey compared with the
            # part: --check and a rerun passed a directory read_survey refused
            lambda d: d["parts"]["0"]["orbits"].update(rows=d["parts"]["0"]["orbits"]["rows"] - 1),
            "chunk 0: orbits/part-00000.csv has",
        ),
    ],
    ids=["another-chunks-file", "extra-entry", "body-range", "rows", "orbit-rows"],
)
def test_forged_ledger_entries_are_bound_to_their_chunk(
    reference, tmp_path, capsys, edit, problem
):
    """Entries edited with the checksum recomputed: still caught, and a rerun repairs them."""
    target = copy(reference, tmp_path)
    _edit_manifest(target, edit, forge=True)
    capsys.readouterr()
    assert main(["survey", "--check", str(target)]) == 1
    assert problem in capsys.readouterr().out
    with pytest.raises(orbits.InputError, match="damaged or incomplete"):
        read_survey(target)
    assert main(GRID + ["--out", str(target)]) == 0
    assert "recomputing" in capsys.readouterr().err
    _same_survey(target, reference)


def test_a_ledger_key_of_non_ascii_digits_is_damage(reference, tmp_path, capsys):
    """``"\u00b2".isdigit()`` is True but int() refuses it: one line, exit 2, no traceback."""
    target = copy(reference, tmp_path)
    _edit_manifest(target, lambda d: d["parts"].update({"\u00b2": d["parts"]["2"]}), forge=True)
    capsys.readouterr()
    for argv in (["survey", "--check", str(target)], GRID + ["--out", str(target)]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "damaged ledger" in err[0], err
    with pytest.raises(orbits.InputError, match="damaged ledger"):
        read_survey(target)


@pytest.mark.parametrize("kind", ["fifo", "directory"])
def test_a_lock_that_is_no_regular_file_is_refused_at_once(reference, tmp_path, capsys, kind):
    """A FIFO as DIR/.lock blocked the run forever (open without O_NONBLOCK);
    a directory gave 'Is a directory: 3'.  Both: one line naming the path."""
    target = copy(reference, tmp_path)
    lock = target / ".lock"
    lock.unlink(missing_ok=True)
    os.mkfifo(lock) if kind == "fifo" else lock.mkdir()
    capsys.readouterr()
    assert main(GRID + ["--out", str(target)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"orbits: error: cannot lock {target}: {lock} is not a regular file"]
    with pytest.raises(orbits.InputError, match="is not a regular file"):
        orbits.survey.Survey.grid(target, 6, 3, fmt="csv", chunk=3).run()


def test_a_part_of_another_chunk_is_caught_on_read(reference, tmp_path):
    """Chunk 0's bodies part replaced by chunk 1's and the ledger forged to match."""
    target = copy(reference, tmp_path)
    shutil.copy(target / "bodies" / "part-00001.csv", target / "bodies" / "part-00000.csv")

    def edit(document):
        document["parts"]["0"]["bodies"]["sha256"] = document["parts"]["1"]["bodies"]["sha256"]

    _edit_manifest(target, edit, forge=True)
    with pytest.raises(orbits.InputError, match="body ids are not the chunk's 0..2"):
        read_survey(target, verify=False)


def test_a_deleted_table_folder_is_recomputed(reference, tmp_path, capsys):
    target = copy(reference, tmp_path)
    shutil.rmtree(target / "bodies")
    with pytest.raises(orbits.InputError, match="bodies/part-00000.csv is missing"):
        read_survey(target)
    capsys.readouterr()
    assert main(GRID + ["--out", str(target)]) == 0
    assert "missing or damaged, recomputing" in capsys.readouterr().err
    _same_survey(target, reference)


def test_a_deleted_manifest_is_named(reference, tmp_path):
    target = copy(reference, tmp_path)
    (target / "manifest.json").unlink()
    before = files(target)
    rerun = orbits.survey.Survey.grid(target, 6, 3, fmt="csv", chunk=3).run
    for call in (lambda: check_survey(target), lambda: read_survey(target), rerun):
        with pytest.raises(orbits.InputError, match=r"no manifest.json \(deleted\?\)"):
            call()
    assert files(target) == before


@pytest.mark.parametrize(
    "planted", [".lock", "manifest.json", "report.json", "bodies", "bodies/part-00001.csv"]
)
def test_no_link_inside_a_survey_is_followed(reference, tmp_path, capsys, planted):
    """A link planted to a file outside (same bytes) is refused, and the file stays as it was."""
    target = copy(reference, tmp_path)
    outside = tmp_path / "outside"
    shutil.move(target / planted, outside)
    os.symlink(outside, target / planted)
    before = files(tmp_path)
    capsys.readouterr()
    for argv in (GRID + ["--out", str(target)], ["survey", "--check", str(target)]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "is a symbolic link" in err[0], err
    with pytest.raises(orbits.InputError, match="symbolic link"):
        read_survey(target)
    assert files(tmp_path) == before


def test_atomic_writes_can_refuse_a_link(tmp_path):
    real = tmp_path / "real.txt"
    real.write_text("mine\n")
    (tmp_path / "link.txt").symlink_to(real)
    with pytest.raises(orbits.InputError, match="symbolic link"):
        write_text_atomic(tmp_path / "link.txt", "new\n")
    assert real.read_text() == "mine\n" and (tmp_path / "link.txt").is_symlink()


def test_name_lists_are_hashed_unambiguously(tmp_path):
    moments = orbits.region_sample(2)
    one = orbits.survey.Survey(tmp_path / "s", moments, {"file": "x"}, 2, names=["a\nb", "c"])
    two = orbits.survey.Survey(tmp_path / "s", moments, {"file": "x"}, 2, names=["a", "b\nc"])
    assert one.parameters["names_sha256"] != two.parameters["names_sha256"]
    one.run()
    with pytest.raises(orbits.InputError, match="different parameters.*names_sha256"):
        two.run()


def test_a_stopped_figure_set_leaves_no_directory_it_made(tmp_path):
    """`timeout -s TERM 3 orbits figures ... --out nd/sub/dir` left the empty
    chain nd/sub/dir behind."""
    out = tmp_path / "nd" / "sub" / "dir"
    # n <= 24: about 10 s of drawing after the directory is made, so that a
    # busy machine still stops the run while it draws
    argv = [sys.executable, "-m", "orbits", "figures", "--preset", "fig6", "--n-max", "24"]
    argv += ["--formats", "png", "--out", str(out)]
    proc = subprocess.Popen(argv, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    # the directory is made once every input is checked: the set is being drawn
    while proc.poll() is None and not out.is_dir() and time.monotonic() < deadline:
        time.sleep(0.01)
    assert proc.poll() is None, "the run ended before it could be stopped"
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143
    assert err.strip().splitlines()[-1] == (
        "orbits: stopped by SIGTERM; no partial output was written"
    )
    assert list(tmp_path.iterdir()) == []


def test_only_the_directories_made_are_removed_and_only_while_empty(tmp_path):
    from orbits.atomic import make_directories, remove_directories

    (tmp_path / "a").mkdir()
    made = make_directories(tmp_path / "a" / "b" / ".." / "c" / "d")
    real = tmp_path.resolve() / "a"
    assert made == [real / "b", real / "c", real / "c" / "d"]
    assert (tmp_path / "a" / "c" / "d").is_dir()
    (tmp_path / "a" / "c" / "d" / "kept.txt").write_text("someone's file")
    remove_directories(made)
    # b was empty; d holds a file, and c holds d
    assert sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*")) == [
        "a",
        "a/c",
        "a/c/d",
        "a/c/d/kept.txt",
    ]
    (tmp_path / "a" / "c" / "d" / "kept.txt").unlink()
    remove_directories(made)
    assert [p.name for p in tmp_path.iterdir()] == ["a"]
    assert list((tmp_path / "a").iterdir()) == []


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux's /proc")
def test_an_unwritable_directory_is_refused_before_any_work(tmp_path, capsys):
    """/proc takes no new file even for root, whom os.access tells it can:
    the target is probed before the work (issue: catalog --verify ran to
    its end, verify --table printed its table, then both failed)."""
    from orbits.atomic import ensure_writable, probe_directory

    with pytest.raises(orbits.InputError, match="cannot write /proc/orbits-probe.csv"):
        ensure_writable("/proc/orbits-probe.csv")
    probe_directory(tmp_path)  # a writable one: no error, nothing left in it
    assert list(tmp_path.iterdir()) == []
    calls = []
    module = importlib.import_module("orbits.catalog")
    original = module.catalog
    spy = lambda *a, **k: calls.append(1) or original(*a, **k)  # noqa: E731
    module.catalog = spy
    try:
        argv = ["catalog", "--preset", "fig6", "--n-max", "3", "--verify"]
        assert main([*argv, "--out", "/proc/orbits-probe.csv"]) == 2
        assert main([*argv, "--out", str(tmp_path / "c.csv")]) == 0  # the spy works
    finally:
        module.catalog = original
    assert calls == [1]
    capsys.readouterr()
    assert main([*argv, "--out", "/proc/orbits-probe.csv"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.count("\n") == 1 and "cannot write /proc/orbits-probe.csv" in err
    assert main(["verify", "--bodies", "2", "--angles", "2", "--table", "/proc/t.csv"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and "cannot write /proc/t.csv" in err


def test_a_file_where_the_directory_should_be_is_named_so(tmp_path):
    from orbits.atomic import ensure_writable

    (tmp_path / "afile").write_text("x")
    with pytest.raises(orbits.InputError, match="afile is not a directory"):
        ensure_writable(tmp_path / "afile" / "a.csv")


def test_another_users_process_is_alive_even_where_proc_hides_it(monkeypatch):
    """kill(pid, 0) -> PermissionError: the process exists (someone else's);
    with /proc mounted hidepid=2 its /proc entry is missing, which must not
    read as ended (its live temporaries were removed)."""
    import orbits.atomic as atomic

    def refused(pid, signal):
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(atomic.os, "kill", refused)
    assert atomic._pid_alive(424242)
    monkeypatch.setattr(atomic.os, "kill", lambda pid, signal: None)
    assert atomic._pid_alive(2**22 + 12345)  # no /proc entry: taken as alive


def test_another_names_temporary_is_never_taken_for_a_stale_one(tmp_path):
    """Writing "run" removed ".run.4242.mp4.LIVEPID.X.part", the live temporary
    of "run.4242.mp4", reading 4242 as its (dead) process."""
    other = tmp_path / f".run.{DEAD_PID}.mp4.{os.getpid()}.abcd1234.part"
    also = tmp_path / f".run.{DEAD_PID}.{os.getpid()}.abcd1234.part"  # of "run.DEAD_PID"
    for path in (other, also):
        path.write_text("in flight")
    write_text_atomic(tmp_path / "run", "new\n")
    assert other.exists() and also.exists()
    assert remove_stale_temporaries(tmp_path, "run") == 0


def test_a_folder_swapped_for_a_link_during_a_survey_is_not_written_through(tmp_path, monkeypatch):
    """A survey's orbits/ swapped for a link to a folder outside while it ran:
    141 parts were written outside before the run failed."""
    import threading

    from orbits.survey import compute

    out, outside = tmp_path / "s", tmp_path / "outside"
    outside.mkdir()
    chunk_columns, calls, swapping = compute.chunk_columns, [], threading.Lock()

    def swap_first(found, first_id, columns="all"):
        # chunks are built and written on several threads: the swap happens
        # before any part is written, and no chunk goes on to be written
        # while orbits/ is missing between the rename and the link
        with swapping:
            calls.append(first_id)
            if len(calls) == 1:
                (out / "orbits").rename(tmp_path / "moved")
                (out / "orbits").symlink_to(outside)
        return chunk_columns(found, first_id, columns)

    monkeypatch.setattr(compute, "chunk_columns", swap_first)
    survey = orbits.survey.Survey.grid(out, 6, 3, chunk=3, fmt="csv")
    with pytest.raises(orbits.InputError, match="symbolic link"):
        survey.run()
    assert list(outside.iterdir()) == []
    assert len(calls) >= 1


def test_a_stage_swapped_for_a_link_is_not_written_through(tmp_path, monkeypatch):
    from orbits import figures

    out, outside = tmp_path / "figs", tmp_path / "outside"
    out.mkdir()
    outside.mkdir()
    draw, calls = figures.closed_herpolhode_figure, []

    def swap_after_first(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            (stage,) = out.glob(".orbits-set.*.part")
            stage.rename(tmp_path / "moved")
            stage.symlink_to(outside)
        return draw(*args, **kwargs)

    monkeypatch.setattr(figures, "closed_herpolhode_figure", swap_after_first)
    with pytest.raises(orbits.InputError, match="symbolic link"):
        figures.herpolhode_set(orbits.Body.preset("fig6"), 3, out, formats="png")
    assert list(outside.iterdir()) == []
    assert [p.name for p in out.iterdir() if not p.is_symlink()] == []


def test_a_figure_set_is_not_written_through_a_linked_directory(tmp_path, monkeypatch):
    """The command line refused a link as --out; herpolhode_set and
    paper_figures wrote through it."""
    from orbits import figures

    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "link").symlink_to(real)
    with pytest.raises(orbits.InputError, match="symbolic link"):
        figures.herpolhode_set(orbits.Body.preset("fig6"), 2, tmp_path / "link")
    with pytest.raises(orbits.InputError, match="symbolic link"):
        figures.paper_figures(tmp_path / "link", names="fig5")
    (tmp_path / "file").write_text("x")
    with pytest.raises(orbits.InputError, match="file is not a directory"):
        figures.herpolhode_set(orbits.Body.preset("fig6"), 2, tmp_path / "file")
    monkeypatch.chdir(real)
    for stem in (".", ".."):  # "." wrote a hidden ./.png
        with pytest.raises(orbits.InputError, match="names a directory"):
            figures.save_figure(figures.new_figure(), stem)
    assert list(real.iterdir()) == []


@pytest.mark.parametrize("option", ["--bodies", "--point-masses"])
def test_an_output_that_is_the_input_file_is_refused(tmp_path, monkeypatch, capsys, option):
    """catalog --bodies in.csv --out in.csv replaced the bodies with the catalog."""
    monkeypatch.chdir(tmp_path)
    if option == "--bodies":
        text = "I1,I2,I3\n1,1.5,2\n"
    else:
        text = "mass,x,y,z\n1,1,0,0\n1,-1,0,0\n2,0,0.7,0\n2,0,-0.7,0\n1.5,0,0,0.3\n1.5,0,0,-0.3\n"
    (tmp_path / "in.csv").write_text(text)
    (tmp_path / "alias.csv").symlink_to(tmp_path / "in.csv")
    runs = [["catalog", option, "in.csv", "--n-max", "2", "--out", "./in.csv"]]
    runs.append(["catalog", option, "alias.csv", "--n-max", "2", "--out", "in.csv"])
    if option == "--point-masses":
        runs.append(["verify", option, "in.csv", "--angles", "2", "--table", "in.csv"])
    for argv in runs:
        capsys.readouterr()
        assert main(argv) == 2, argv
        out, err = capsys.readouterr()
        assert err.strip().splitlines() == [
            f"orbits: error: {'--table' if 'verify' in argv else '--out'} "
            f"{argv[-1]} is the input file of {option}: writing it would replace "
            "the input; give another path"
        ]
        assert out == ""
    assert (tmp_path / "in.csv").read_text() == text


def test_a_link_as_the_target_is_refused_before_the_work(tmp_path, monkeypatch, capsys):
    """catalog and verify --table refused a link only after the whole run."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "real.csv").write_text("mine\n")
    (tmp_path / "link.csv").symlink_to(tmp_path / "real.csv")
    runs = [
        ["catalog", "--preset", "fig6", "--n-max", "2", "--out", "link.csv"],
        ["verify", "--moments", "1", "2", "3", "--angles", "2", "--table", "link.csv"],
    ]
    for argv in runs:
        capsys.readouterr()
        assert main(argv) == 2
        out, err = capsys.readouterr()
        assert out == "" and len(err.strip().splitlines()) == 1, (out, err)
        assert "symbolic link" in err
    assert (tmp_path / "real.csv").read_text() == "mine\n"


@pytest.mark.parametrize("out", ["home/new/..", "fresh/a/.."])
def test_a_refused_survey_leaves_nothing(tmp_path, monkeypatch, capsys, out):
    """--out home/new/.. made home/new and home/.lock before the refusal."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "home").mkdir()
    (tmp_path / "home" / "notes.txt").write_text("mine\n")
    before = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*"))
    assert main(GRID + ["--out", out]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"orbits: error: {out} exists and is not a survey directory"]
    after = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*"))
    assert after == before
    assert main(GRID + ["--out", "-"]) == 2
    assert "give a directory" in capsys.readouterr().err
    assert not (tmp_path / "-").exists()


def test_names_too_long_and_paths_of_other_types_are_one_error(tmp_path):
    table = orbits.closed_orbits(orbits.Body.preset("fig6"), n_max=2)
    long = "c" * 256
    calls = [
        lambda: orbits.write_catalog(table, tmp_path / (long + ".csv")),
        lambda: orbits.survey.Survey.grid(tmp_path / long, 6, 3).run(),
        lambda: check_survey(tmp_path / long),
        lambda: orbits.poinsot_animation(orbits.Body.preset("fig6"), theta=0.5).save(
            tmp_path / (long + ".gif")
        ),
    ]
    for call in calls:
        with pytest.raises(orbits.InputError, match="name of 2.. bytes is too long"):
            call()
    for path in (None, 123, b"x.csv"):
        with pytest.raises(orbits.ArgumentTypeError, match="path must be a path"):
            orbits.write_catalog(table, path)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(os.geteuid() == 0, reason="root can read any directory")
def test_a_drop_box_directory_takes_files(tmp_path):
    """Directory descriptors opened O_RDONLY needed read permission: a
    drop box (mode 0733) refused every figure and survey part."""
    from orbits import atomic, figures

    box = tmp_path / "box"
    box.mkdir()
    box.chmod(0o733)
    try:
        atomic.write_bytes_under(box, "a.bin", b"x")
        figures.save_figure(figures.new_figure(), box / "f", "png")
    finally:
        box.chmod(0o755)
    assert sorted(p.name for p in box.iterdir()) == ["a.bin", "f.png"]


def test_directory_descriptors_need_no_read_permission():
    from orbits import atomic

    if hasattr(os, "O_PATH"):  # Linux: the drop box above works even as root's test
        assert atomic._DIRECTORY_ACCESS == os.O_PATH


def test_a_figure_into_the_survey_it_reads_is_no_overwrite(reference, tmp_path, capsys):
    """figures --survey S --out S was refused as 'the input file of --survey'."""
    target = copy(reference, tmp_path)
    capsys.readouterr()
    assert (
        main(["figures", "--survey", str(target), "--out", str(target), "--formats", "png"]) == 0
    )
    assert (target / "fig2.png").is_file()
    assert main(["survey", "--check", str(target)]) == 0


def test_a_failed_write_names_the_target_not_the_stage(tmp_path, monkeypatch):
    """From Python 3.12 mkdtemp returns an absolute path: the message named
    figs/.orbits-set.PID.X.part/... (simulated here)."""
    import tempfile

    from orbits import atomic, figures

    make = tempfile.mkdtemp
    monkeypatch.setattr(tempfile, "mkdtemp", lambda *a, **k: os.path.abspath(make(*a, **k)))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "figs").mkdir()

    def full(descriptor):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", full)
    with pytest.raises(orbits.InputError) as caught:
        figures.herpolhode_set(orbits.Body.preset("fig6"), 3, "figs", formats="png")
    assert ".orbits-set" not in str(caught.value)
    assert str(caught.value).startswith("cannot write ")
    assert list((tmp_path / "figs").iterdir()) == []


def test_a_catalog_to_standard_output_is_written_whole_or_refused(tmp_path, monkeypatch):
    """Python's buffered stdout drops the rest of a large write silently when
    the system takes only part of it: `orbits catalog --out - > file` on a
    full disk or under a file-size limit left a truncated file, exit 0."""
    import errno

    frame = orbits.catalog(orbits.Body.preset("fig6"), n_max=10, q_max=3)
    real_write = os.write
    calls = []

    def short(descriptor, data):  # the system takes 100 bytes at a time
        calls.append(len(data))
        return real_write(descriptor, bytes(data[:100]))

    with open(tmp_path / "out.csv", "w", encoding="utf-8") as stream:
        monkeypatch.setattr(sys, "stdout", stream)
        monkeypatch.setattr(os, "write", short)
        orbits.write_catalog(frame, "-")
        monkeypatch.undo()
    assert len(calls) > 10
    assert orbits.read_catalog(tmp_path / "out.csv")["dtheta"].tolist() == frame["dtheta"].tolist()

    def full(descriptor, data):
        if calls:
            calls.clear()
            return real_write(descriptor, bytes(data[:100]))
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    calls.append(0)
    with open(tmp_path / "full.csv", "w", encoding="utf-8") as stream:
        monkeypatch.setattr(sys, "stdout", stream)
        monkeypatch.setattr(os, "write", full)
        with pytest.raises(
            orbits.InputError,
            match="cannot write the catalog to standard output: No space left on device",
        ):
            orbits.write_catalog(frame, "-")
        monkeypatch.undo()


@pytest.mark.skipif(not hasattr(os, "fork"), reason="resource limits of POSIX")
def test_a_catalog_to_standard_output_under_a_file_size_limit(tmp_path):
    import resource

    argv = [sys.executable, "-m", "orbits", "catalog", "--preset", "fig6", "--n-max", "10"]
    argv += ["--q-max", "3", "--out", "-"]
    subprocess.run(argv, capture_output=True, timeout=300, check=True)  # kernels cached

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))

    with open(tmp_path / "c.csv", "wb") as out:
        done = subprocess.run(
            argv, stdout=out, stderr=subprocess.PIPE, text=True, timeout=300, preexec_fn=limit
        )
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        "orbits: error: cannot write the catalog to standard output: File too large"
    ]


@pytest.mark.skipif(not hasattr(os, "fork"), reason="resource limits of POSIX")
def test_a_survey_that_cannot_write_its_lock_names_it(tmp_path):
    """The lock's pid line failed to write and closing the lock flushed it
    again, so the error left was a bare "No space left on device"."""
    import resource

    argv = [sys.executable, "-m", "orbits", "survey", "--resolution", "20", "--n-max", "5"]
    subprocess.run([*argv, "--out", str(tmp_path / "warm")], capture_output=True, timeout=300)

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (0, 0))

    done = subprocess.run(
        [*argv, "--out", str(tmp_path / "s")],
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=limit,
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"orbits: error: cannot write {tmp_path / 's' / '.lock'}: File too large"
    ]


# ------------------------------------- each guard on its own (mutation audit)
def test_the_temporary_is_synced_before_it_is_moved(tmp_path, monkeypatch):
    """fsync of the finished temporary, then os.replace (no copy: a copy
    writes through a link planted at the target, and truncates in place)."""
    from orbits import atomic

    events = []
    real_fsync, real_replace = os.fsync, os.replace
    monkeypatch.setattr(atomic.os, "fsync", lambda fd: (events.append("fsync"), real_fsync(fd)))
    monkeypatch.setattr(
        atomic.os, "replace", lambda a, b: (events.append("replace"), real_replace(a, b))
    )
    target = tmp_path / "a.txt"
    target.write_text("old\n")
    inode = target.stat().st_ino
    write_text_atomic(target, "new\n")
    assert events[-2:] == ["fsync", "replace"]
    assert target.read_text() == "new\n" and target.stat().st_ino != inode


def test_a_link_or_fifo_planted_during_the_write_is_not_written_through(tmp_path):
    from orbits.atomic import atomic_path
    from orbits.errors import InputError

    outside = tmp_path / "outside.txt"
    outside.write_text("precious\n")
    target = tmp_path / "a.txt"
    with atomic_path(target) as temporary:
        temporary.write_text("new\n")
        os.symlink(outside, target)  # between the first check and the move
    assert outside.read_text() == "precious\n"
    assert not target.is_symlink() and target.read_text() == "new\n"
    fifo = tmp_path / "f.txt"
    with pytest.raises(InputError, match="FIFO"):
        with atomic_path(fifo) as temporary:
            temporary.write_text("new\n")
            os.mkfifo(fifo)
    assert stat_is_fifo(fifo)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "f.txt", "outside.txt"]


def test_a_fifo_planted_under_a_survey_root_during_the_write_is_kept(tmp_path, monkeypatch):
    from orbits import atomic
    from orbits.errors import InputError

    target = tmp_path / "f.bin"
    real_fsync = os.fsync

    def fsync_then_plant(fd):
        real_fsync(fd)
        os.mkfifo(target)

    monkeypatch.setattr(atomic.os, "fsync", fsync_then_plant)
    with pytest.raises(InputError, match="not a regular file"):
        atomic.write_bytes_under(tmp_path, "f.bin", b"new\n")
    assert stat_is_fifo(target)


def stat_is_fifo(path):
    import stat

    return stat.S_ISFIFO(os.lstat(path).st_mode)


def test_reads_never_follow_a_link_nor_open_a_fifo(tmp_path):
    from orbits.atomic import open_nofollow, read_bytes_nofollow
    from orbits.errors import InputError

    secret = tmp_path / "secret.txt"
    secret.write_text("secret\n")
    link = tmp_path / "link"
    os.symlink(secret, link)
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for read in (open_nofollow, read_bytes_nofollow):
        with pytest.raises(InputError, match="symbolic link"):
            read(link)
        with pytest.raises(InputError, match="not a regular file"):
            read(fifo)
    assert read_bytes_nofollow(secret) == b"secret\n"


def test_a_catalog_whose_header_miscounts_its_rows_is_damaged(tmp_path):
    # the checksum covers the data only: the row count is checked on its own
    path = tmp_path / "c.csv"
    orbits.write_catalog(orbits.catalog(orbits.Body.preset("fig6"), n_max=5, q_max=2), path)
    text = path.read_text()
    count = len(orbits.read_catalog(path))
    assert f"# rows: {count}\n" in text
    path.write_text(text.replace(f"# rows: {count}\n", "# rows: 999\n"))
    with pytest.raises(orbits.InputError, match=f"{count} rows, the header records 999"):
        orbits.read_catalog(path)


def test_two_runs_never_hold_a_survey_directory_at_once(tmp_path):
    """The lock is exclusive between two orbits runs (the tests held the
    lock from outside with LOCK_EX, which a shared lock would also respect)."""
    first = orbits.survey.Survey.grid(tmp_path / "s", 20, 4)
    second = orbits.survey.Survey.grid(tmp_path / "s", 20, 4)
    (tmp_path / "s").mkdir()
    with first.lock():
        with pytest.raises(orbits.InputError, match="being written by another orbits run"):
            with second.lock():
                pass
