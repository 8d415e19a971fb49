"""Table-driven bad input: every case fails cleanly and leaves the disk as it was.

Each command-line case runs ``orbits.cli.main`` in-process (a subset also
through a real ``python -m orbits`` subprocess) inside a fresh directory
prepared by the case, and asserts

* exit code 2,
* exactly one line on stderr, starting ``orbits: error:``, no traceback,
* no file created, changed or left behind: a snapshot of the directory
  (every entry, hidden ``.NAME.*.part`` temporaries and ``.lock`` included,
  with the kind, mode, link target and SHA-256 of each) is the same
  before and after; special files (``/dev/null``, FIFOs, sockets) are still
  what they were.

The API cases assert an :class:`orbits.errors.OrbitsError` and the same
unchanged directory.  The number of cases is :data:`CASE_COUNT`.
"""

import hashlib
import json
import os
import shutil
import socket
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import orbits
import orbits.checks
import orbits.survey
from orbits.cli import main
from orbits.errors import OrbitsError

# ------------------------------------------------------------------ fixtures
FIFO, SOCKET, DIRECTORY = "<fifo>", "<socket>", "<directory>"


def link(target):
    return ("link", target)


def survey(kind, damage=None):
    """A copy of a prepared survey directory, optionally damaged."""
    return ("survey", kind, damage)


GOOD_BODIES = 'I1,I2,I3,name\n0.26,0.55,0.793662,"fig6"\n0.3,0.5,0.7,"b"\n'
LIST_BODIES = "I1,I2,I3\n0.26,0.55,0.793662\n0.3,0.5,0.7\n0.2,0.6,0.75\n0.25,0.5,0.7\n"


@pytest.fixture(scope="module")
def surveys(tmp_path_factory):
    """Two small finished surveys (CSV, 2 bodies per chunk): a grid and a list."""
    root = tmp_path_factory.mktemp("surveys")
    orbits.survey.Survey.grid(root / "grid", 4, 2, fmt="csv", chunk=2).run()
    moments = np.loadtxt(_write(root / "list.csv", LIST_BODIES), delimiter=",", skiprows=1)
    orbits.survey.Survey(root / "list", moments, {"file": "list.csv"}, 2, fmt="csv", chunk=2).run()
    return root


def _write(path, text):
    path.write_text(text)
    return path


def _damage(directory, damage):
    """Damage a survey directory the ways a crash, a user or a disk would."""
    manifest = directory / "manifest.json"
    part = directory / "bodies" / "part-00001.csv"
    orbits_part = directory / "orbits" / "part-00000.csv"
    if damage is None:
        return
    if damage == "no-manifest":
        manifest.unlink()
    elif damage == "manifest-not-json":
        manifest.write_text('{"orbits_survey": 2, "parameters": {')
    elif damage == "manifest-empty":
        manifest.write_text("")
    elif damage == "manifest-incomplete":
        document = json.loads(manifest.read_text())
        del document["parameters"]["n_max"]
        manifest.write_text(json.dumps(document))
    elif damage == "manifest-old-format":
        document = json.loads(manifest.read_text())
        del document["orbits_survey"]
        manifest.write_text(json.dumps(document))
    elif damage == "ledger-outside":
        document = json.loads(manifest.read_text())
        document["parts"]["0"]["bodies"]["file"] = "../../../etc/hostname"
        manifest.write_text(json.dumps(document))
    elif damage == "ledger-damaged":
        document = json.loads(manifest.read_text())
        document["parts"] = {"first": 1}
        manifest.write_text(json.dumps(document))
    elif damage == "part-missing":
        part.unlink()
    elif damage == "part-truncated":
        data = orbits_part.read_bytes()
        orbits_part.write_bytes(data[: len(data) // 2])
    elif damage == "part-empty":
        part.write_bytes(b"")
    elif damage == "part-changed":
        data = part.read_bytes()
        part.write_bytes(data.replace(b"0.", b"1.", 1))
    elif damage == "stray-bak-and-truncated":
        shutil.copy(part, part.with_name(part.name + ".bak"))
        data = part.read_bytes()
        part.write_bytes(data[: len(data) - 20])
    elif damage in _LEDGER_EDITS:
        document = json.loads(manifest.read_text())
        _LEDGER_EDITS[damage](document)
        if damage.endswith("-forged"):  # edited by someone who knows the checksum
            document["sha256"] = orbits.survey.manifest_checksum(document)
        manifest.write_text(json.dumps(document))
    elif damage in _LINKS:
        # a symlink planted in the survey to a copy outside it (same bytes:
        # the ledger's SHA-256 alone would accept it)
        planted = directory / _LINKS[damage]
        outside = directory.parent / "outside" / planted.name
        outside.parent.mkdir(exist_ok=True)
        if planted.is_dir():
            shutil.copytree(planted, outside)
            shutil.rmtree(planted)
        else:
            shutil.copy(planted, outside)
            planted.unlink()
        os.symlink(outside, planted)
    elif damage == "no-bodies-folder":
        shutil.rmtree(directory / "bodies")
    elif damage == "stale-temporary":
        # a SIGKILLed run's temporary (pid 2**22 + 1 does not exist) next to a missing part
        (part.parent / f".{part.name}.{2**22 + 1}.abc.part").write_bytes(b"x" * 100)
        part.unlink()
    else:
        raise AssertionError(damage)


def prepare(directory, files, surveys_root):
    """Create the files of a case; returns objects to keep alive (sockets)."""
    keep = []
    for name, content in files.items():
        path = directory / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if content == FIFO:
            os.mkfifo(path)
        elif content == SOCKET:
            server = socket.socket(socket.AF_UNIX)
            server.bind(str(path))
            keep.append(server)
        elif content == DIRECTORY:
            path.mkdir()
        elif isinstance(content, tuple) and content[0] == "link":
            os.symlink(content[1].format(d=directory), path)
        elif isinstance(content, tuple) and content[0] == "survey":
            shutil.copytree(surveys_root / content[1], path, symlinks=True)
            _damage(path, content[2])
        elif isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content)
    return keep


def snapshot(directory):
    """Every entry under ``directory``: kind, mode, link target, SHA-256 of files."""
    state = {}
    for root, dirs, names in os.walk(directory):
        for name in dirs + names:
            path = os.path.join(root, name)
            info = os.lstat(path)
            key = os.path.relpath(path, directory)
            if stat.S_ISLNK(info.st_mode):
                state[key] = ("link", os.readlink(path))
            elif stat.S_ISREG(info.st_mode):
                with open(path, "rb") as handle:
                    state[key] = (
                        "file",
                        stat.S_IMODE(info.st_mode),
                        hashlib.sha256(handle.read()).hexdigest(),
                    )
            else:
                state[key] = (stat.S_IFMT(info.st_mode), stat.S_IMODE(info.st_mode))
    return state


def device_state():
    info = os.stat("/dev/null")
    return stat.S_ISCHR(info.st_mode), info.st_rdev


def _swap(document):
    document["parts"]["0"]["bodies"] = document["parts"]["1"]["bodies"]


def _extra(document):
    document["parts"]["99"] = document["parts"]["0"]


def _n_max_three(document):
    document["parameters"]["n_max"] = 3


_LEDGER_EDITS = {
    "ledger-swapped": _swap,
    "ledger-extra": _extra,
    "parameters-edited": _n_max_three,
    "ledger-swapped-forged": _swap,
    "ledger-extra-forged": _extra,
    "parameters-edited-forged": _n_max_three,
}
_LINKS = {
    "link-lock": ".lock",
    "link-part": "bodies/part-00001.csv",
    "link-bodies": "bodies",
    "link-orbits": "orbits",
    "link-manifest": "manifest.json",
    "link-report": "report.json",
}
_HAND_EDITS = ("ledger-swapped", "ledger-extra", "parameters-edited")

# ------------------------------------------------------------------ the table
P, C, V, F, S, A = "phase", "catalog", "verify", "figures", "survey", "animate"
FIG6 = ["--preset", "fig6"]
CAT = [C] + FIG6 + ["--n-max", "2", "--out"]
BODIES = [C, "--n-max", "2", "--out", "{d}/c.csv", "--bodies", "{d}/b.csv"]
SURVEY_B = [S, "--n-max", "2", "--format", "csv", "--out", "{d}/s", "--bodies", "{d}/b.csv"]
GRID = [S, "--resolution", "4", "--n-max", "2", "--format", "csv", "--chunk", "2"]


def bodies(text):
    return {"b.csv": text}


# (id, argv, files, fragment of the message)
CLI_CASES = [
    # ------------------------------------------------------- usage, numbers
    ("no-command", [], {}, "required"),
    ("unknown-command", ["nope"], {}, "invalid choice"),
    # argparse strips an attached "--" and hands the option [] past its checks:
    # a TypeError traceback (--out=--), an empty table with exit 0 (--theta=--)
    ("attached-separator-out", [C] + FIG6 + ["--n-max", "2", "--out=--"], {}, "'--' is not"),
    ("attached-separator-theta", [P] + FIG6 + ["--theta=--"], {}, "--theta: '--' is not"),
    ("attached-separator-phi", [P] + FIG6 + ["--theta", "0.5", "--phi=--"], {}, "--phi:"),
    ("attached-separator-flip", [A] + FIG6 + ["--flip=--", "--out", "a.gif"], {}, "--flip:"),
    ("attached-separator-bench", ["bench", "--only=--"], {}, "--only:"),
    ("attached-separator-survey", [S, "--resolution", "4", "--chunk=--"], {}, "--chunk:"),
    # '' was read as the current directory ("cannot write .: it is a directory")
    (
        "empty-out",
        [C] + FIG6 + ["--n-max", "2", "--out", ""],
        {},
        "--out must be a non-empty path",
    ),
    ("empty-check", [S, "--check", ""], {}, "--check must be a non-empty path"),
    ("empty-survey-out", [S, "--resolution", "4", "--out="], {}, "--out must be a non-empty path"),
    ("empty-table", [V, "--table", ""], {}, "--table must be a non-empty path"),
    ("animate-stdout", [A] + FIG6 + ["--theta", "0.5", "--out", "-"], {}, "never to standard"),
    # its remedies (--seconds 0.05, --periods 7.3e147) were both refused in turn
    (
        "animate-throw-too-fast",
        [A] + FIG6 + ["--omega", "1e150", "1e150", "1e150", "--dpi", "10", "--out", "a.gif"],
        {},
        "too fast to animate in real time; give a slower --omega",
    ),
    ("threads-zero", ["--threads", "0", P] + FIG6 + ["--theta", "1"], {}, ">= 1"),
    ("moments-nan", [P, "--moments", "1", "2", "nan", "--theta", "0.3"], {}, "finite"),
    ("moments-inf", [P, "--moments", "1", "2", "inf", "--theta", "0.3"], {}, "finite"),
    ("moments-minus-inf", [P, "--moments", "1", "2", "-inf", "--theta", "0.3"], {}, "finite"),
    ("moments-text", [P, "--moments", "a", "b", "c", "--theta", "0.3"], {}, "not a number"),
    ("moments-two", [P, "--moments", "1", "2", "--theta", "0.3"], {}, "--moments"),
    ("moments-negative", [P, "--moments", "-1", "2", "2.5", "--theta", "0.3"], {}, ""),
    ("moments-zero", [P, "--moments", "0", "1", "1.5", "--theta", "0.3"], {}, ""),
    ("moments-symmetric", [P, "--moments", "1", "1", "2", "--theta", "0.3"], {}, "symmetric"),
    ("moments-triangle", [P, "--moments", "1", "2", "4", "--theta", "0.3"], {}, "triangle"),
    (
        "moments-1e200-overflow",
        [P, "--moments", "1e200", "2e200", "1e308", "--theta", "0.3"],
        {},
        "",
    ),
    ("moments-1e-320", [P, "--moments", "1e-320", "2e-320", "2.5e-320", "--theta", "0.3"], {}, ""),
    ("t-handle-1e200", [P, "--t-handle", "1e200", "4", "1", "--theta", "0.3"], {}, ""),
    ("t-handle-zero", [P, "--t-handle", "0", "4", "1", "--theta", "0.3"], {}, ""),
    ("ellipsoid-negative", [P, "--ellipsoid", "-1", "2", "--theta", "0.3"], {}, ""),
    ("ellipsoid-symmetric", [P, "--ellipsoid", "0.5", "0.5", "--theta", "0.3"], {}, ""),
    ("box-cube", [P, "--box", "1", "1", "1", "--theta", "0.3"], {}, "symmetric"),
    ("box-negative-mass", [P, "--box", "1", "2", "3", "--mass", "-1", "--theta", "0.3"], {}, ""),
    ("box-1e200", [P, "--box", "1e200", "2e200", "3e200", "--theta", "0.3"], {}, ""),
    ("cylinder-one-value", [P, "--cylinder", "1", "--theta", "0.3"], {}, "--cylinder"),
    (
        "cylinder-four-values",
        [P, "--cylinder", "1", "2", "3", "4", "--theta", "0.3"],
        {},
        "--cylinder",
    ),
    (
        "point-masses-missing",
        [P, "--point-masses", "{d}/none.csv", "--theta", "0.3"],
        {},
        "none.csv",
    ),
    (
        "point-masses-columns",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y\n1,0,0\n"},
        "missing column(s) z",
    ),
    (
        "point-masses-text",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y,z\n1,0,0,abc\n"},
        "numbers",
    ),
    (
        "point-masses-underscore",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y,z\n1,1,0,0\n2,0,1_0,0\n3,0,0,1\n"},
        "'1_0'",
    ),
    (
        "point-masses-arabic-indic-digit",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y,z\n1,1,0,0\n2,0,\u0661,0\n3,0,0,1\n"},
        "must be numbers",
    ),
    (
        "point-masses-extra-column",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y,z,mass2\n1,1,0,0,1\n2,0,1,0,1\n"},
        "unknown column(s) 'mass2'",
    ),
    (
        "point-masses-index-column",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "0,mass,x,y,z\n0,1,1,0,0\n1,2,0,1,0\n"},
        "unknown column(s) '0'",
    ),
    (
        "point-masses-short-row",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y,z\n1,1,0,0\n2,0,1\n"},
        "3 fields where the header has 4",
    ),
    (
        "point-masses-overflow",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y,z\n1,1,0,1e999\n"},
        "'1e999'",
    ),
    (
        "point-masses-nan",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y,z\nnan,1,0,0\n"},
        "'nan'",
    ),
    (
        "point-masses-empty-cell",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y,z\n1,,0,0\n"},
        "x = ''",
    ),
    (
        "point-masses-header-only",
        [P, "--point-masses", "{d}/m.csv", "--theta", "0.3"],
        {"m.csv": "mass,x,y,z\n"},
        "no point masses",
    ),
    ("mesh-missing", [P, "--mesh", "{d}/none.stl", "--theta", "0.3"], {}, ""),
    (
        "rotational-constants-equal",
        [P, "--rotational-constants", "1", "1", "1", "--theta", "0.3"],
        {},
        "",
    ),
    (
        "rotational-constants-negative",
        [P, "--rotational-constants", "-1", "2", "3", "--theta", "0.3"],
        {},
        "",
    ),
    (
        "two-bodies",
        [P, "--preset", "fig6", "--moments", "1", "2", "2.5", "--theta", "1"],
        {},
        "not allowed",
    ),
    ("preset-unknown", [P, "--preset", "nope", "--theta", "1"], {}, "invalid choice"),
    ("no-angle", [P] + FIG6, {}, "required"),
    ("theta-nan", [P] + FIG6 + ["--theta", "nan"], {}, "finite"),
    ("theta-1e200", [P] + FIG6 + ["--theta", "1e200"], {}, "too large to fold"),
    ("phi-1e20", [P] + FIG6 + ["--theta", "1", "--phi", "1e20"], {}, "too large to fold"),
    ("dtheta-separatrix", [P] + FIG6 + ["--dtheta", "0"], {}, "separatrix"),
    ("dtheta-huge", [P] + FIG6 + ["--dtheta", "1e200"], {}, ""),
    ("phi-inf", [P] + FIG6 + ["--theta", "1", "--phi", "inf"], {}, "finite"),
    ("omega-zero", [P] + FIG6 + ["--omega", "0", "0", "0"], {}, ""),
    ("omega-1e200", [P] + FIG6 + ["--omega", "1e200", "1e200", "1e200"], {}, ""),
    (
        "omega-units",
        [P] + FIG6 + ["--omega", "1", "1", "1", "--units", "furlong"],
        {},
        "invalid choice",
    ),
    ("total-phase-negative", [P] + FIG6 + ["--total-phase", "-1"], {}, ""),
    ("period-ratio-zero", [P] + FIG6 + ["--period-ratio", "0"], {}, ""),
    ("name-empty", [P] + FIG6 + ["--theta", "1", "--name", " "], {}, "--name"),
    # ------------------------------------------------------- catalog: sizes
    ("n-max-zero", [C] + FIG6 + ["--n-max", "0", "--out", "{d}/c.csv"], {}, ">= 1"),
    (
        "n-max-1e23",
        [C] + FIG6 + ["--n-max", "99999999999999999999999", "--out", "{d}/c.csv"],
        {},
        "memory",
    ),
    ("n-max-float", [C] + FIG6 + ["--n-max", "1e3", "--out", "{d}/c.csv"], {}, "not an integer"),
    (
        "q-max-100000",
        [C] + FIG6 + ["--n-max", "30", "--q-max", "100000", "--out", "{d}/c.csv"],
        {},
        "",
    ),
    (
        "q-max-zero",
        [C] + FIG6 + ["--n-max", "3", "--q-max", "0", "--out", "{d}/c.csv"],
        {},
        ">= 1",
    ),
    ("catalog-no-out", [C] + FIG6 + ["--n-max", "3"], {}, "--out"),
    # ------------------------------------------------------- catalog: targets
    ("out-no-directory", CAT + ["{d}/none/c.csv"], {}, "does not exist"),
    ("out-parent-is-file", CAT + ["{d}/f/c.csv"], {"f": "x"}, "f is not a directory"),
    (
        "animate-out-directory",
        [A, *FIG6, "--theta", "0.5", "--out", "{d}/sub"],
        {"sub": DIRECTORY},
        "it names a directory",
    ),
    (
        "animate-out-trailing-slash",
        [A, *FIG6, "--theta", "0.5", "--out", "{d}/new/"],
        {},
        "it names a directory",
    ),
    (
        "figures-out-under-a-file",
        [F, *FIG6, "--n-max", "2", "--out", "{d}/f/sub"],
        {"f": "x"},
        "f is not a directory",
    ),
    ("figures-no-body", [F, "--n-max", "2", "--out", "{d}/x"], {}, "--rotational-constants"),
    ("out-trailing-slash", CAT + ["{d}/newname/"], {}, "directory"),
    ("out-existing-directory", CAT + ["{d}/sub"], {"sub": DIRECTORY}, "directory"),
    ("out-existing-directory-slash", CAT + ["{d}/sub/"], {"sub": DIRECTORY}, "directory"),
    ("out-fifo", CAT + ["{d}/fifo"], {"fifo": FIFO}, "FIFO"),
    ("out-socket", CAT + ["{d}/sock"], {"sock": SOCKET}, "socket"),
    ("out-dev-null", CAT + ["/dev/null"], {}, "character device"),
    ("out-link-to-dev-null", CAT + ["{d}/null"], {"null": link("/dev/null")}, "device"),
    ("out-link-to-stdout", CAT + ["{d}/fd1"], {"fd1": link("/proc/self/fd/1")}, ""),
    ("out-link-to-fifo", CAT + ["{d}/l"], {"fifo": FIFO, "l": link("{d}/fifo")}, "FIFO"),
    ("out-dangling-link", CAT + ["{d}/l"], {"l": link("{d}/nowhere/x")}, "dangling"),
    ("out-proc", CAT + ["/proc/orbits-bad-input.csv"], {}, "cannot write"),
    ("out-sys", CAT + ["/sys/orbits-bad-input.csv"], {}, "cannot write"),
    # ------------------------------------------------------- --bodies files
    ("bodies-missing", BODIES[:-1] + ["{d}/none.csv"], {}, "no bodies file"),
    ("bodies-directory", BODIES, {"b.csv": DIRECTORY}, "directory"),
    (
        "bodies-fifo-out",
        [C, "--n-max", "2", "--out", "{d}/fifo", "--bodies", "{d}/b.csv"],
        {"fifo": FIFO, **bodies(GOOD_BODIES)},
        "FIFO",
    ),
    ("bodies-empty-file", BODIES, bodies(""), "no header"),
    ("bodies-header-only", BODIES, bodies("I1,I2,I3\n"), "no bodies"),
    ("bodies-comments-only", BODIES, bodies("# a\n# b\n"), "no header"),
    ("bodies-implicit-index", BODIES, bodies("I1,I2,I3\n0.1,0.26,0.55,0.793662\n"), "row 1"),
    ("bodies-short-row", BODIES, bodies("I1,I2,I3\n0.26,0.55,0.793662\n0.26,0.55\n"), "row 2"),
    ("bodies-true", BODIES, bodies("I1,I2,I3\nTrue,0.55,0.793662\n"), "'True'"),
    ("bodies-underscore", BODIES, bodies("I1,I2,I3\n1_000,1200,1500\n"), "'1_000'"),
    ("bodies-hex", BODIES, bodies("I1,I2,I3\n0x10,20,25\n"), "'0x10'"),
    ("bodies-nan", BODIES, bodies("I1,I2,I3\nnan,0.55,0.793662\n"), "'nan'"),
    ("bodies-inf", BODIES, bodies("I1,I2,I3\n0.26,inf,0.793662\n"), "'inf'"),
    ("bodies-empty-cell", BODIES, bodies("I1,I2,I3\n0.26,,0.793662\n"), "row 1"),
    ("bodies-overflow", BODIES, bodies("I1,I2,I3\n1e400,2e400,2.5e400\n"), "row 1"),
    ("bodies-1e200", BODIES, bodies("I1,I2,I3\n1e200,2e200,1e308\n"), "row 1"),
    ("bodies-symmetric", BODIES, bodies("I1,I2,I3\n0.26,0.55,0.793662\n1,1,2\n"), "row 2"),
    ("bodies-negative", BODIES, bodies("I1,I2,I3\n-1,2,2.5\n"), "row 1"),
    ("bodies-triangle", BODIES, bodies("I1,I2,I3\n1,2,4\n"), "triangle"),
    ("bodies-missing-column", BODIES, bodies("I1,I2\n1,2\n"), "missing column"),
    ("bodies-unknown-column", BODIES, bodies("I1,I2,I3,mass\n1,2,2.5,1\n"), "unknown"),
    ("bodies-repeated-column", BODIES, bodies("I1,I2,I3,I3\n1,2,2.5,2.5\n"), "repeated"),
    ("bodies-not-utf8", BODIES, {"b.csv": b"I1,I2,I3,name\n1,2,2.5,\xff\xfe\n"}, "UTF-8"),
    ("bodies-bad-quote", BODIES, bodies('I1,I2,I3,name\n1,2,2.5,"a"b\n'), ""),
    (
        "bodies-hash-row-bad",
        BODIES,
        bodies('I1,I2,I3,name\n0.26,0.55,0.793662,"body#1"\n1,1,2,"body#2"\n'),
        "body#2",
    ),
    (
        "bodies-all-invalid-skip",
        BODIES + ["--skip-invalid"],
        bodies("I1,I2,I3\n1,1,2\nnan,1,2\n"),
        "all 2 rows",
    ),
    ("bodies-with-name", BODIES + ["--name", "x"], bodies(GOOD_BODIES), "--name"),
    ("skip-invalid-without-bodies", CAT + ["{d}/c.csv", "--skip-invalid"], {}, "--skip-invalid"),
    (
        "bodies-too-many-orbits",
        [C, "--n-max", "100000", "--q-max", "100", "--out", "{d}/c.csv", "--bodies", "{d}/b.csv"],
        bodies(GOOD_BODIES),
        "memory",
    ),
    # ------------------------------------------------------- verify
    ("verify-tolerance-negative", [V, "--tolerance", "-1"], {}, "--tolerance"),
    ("verify-tolerance-zero", [V, "--tolerance", "0"], {}, "--tolerance"),
    ("verify-tolerance-nan", [V, "--tolerance", "nan"], {}, "finite"),
    ("verify-bodies-1e8", [V, "--bodies", "100000000"], {}, "memory"),
    ("verify-angles-1e9", [V, "--angles", "1000000000"], {}, "memory"),
    ("verify-angles-zero", [V, "--angles", "0"], {}, ">= 1"),
    ("verify-symmetric-body", [V, "--moments", "1", "1", "2"], {}, "symmetric"),
    (
        "verify-table-fifo",
        [V, "--bodies", "2", "--angles", "2", "--table", "{d}/fifo"],
        {"fifo": FIFO},
        "FIFO",
    ),
    (
        "verify-table-trailing-slash",
        [V, "--bodies", "2", "--angles", "2", "--table", "{d}/t/"],
        {},
        "directory",
    ),
    (
        "verify-table-no-directory",
        [V, "--bodies", "2", "--angles", "2", "--table", "{d}/none/t.csv"],
        {},
        "does not exist",
    ),
    # ------------------------------------------------------- figures
    ("figures-nothing", [F, "--out", "{d}/o"], {}, "exactly one"),
    ("figures-paper-and-body", [F, "--paper", "--out", "{d}/o"] + FIG6, {}, "exactly one"),
    ("figures-body-no-n-max", [F, "--out", "{d}/o"] + FIG6, {}, "--n-max"),
    (
        "figures-huge-n-max",
        [F, "--out", "{d}/o", "--n-max", "99999999999999999999"] + FIG6,
        {},
        "memory",
    ),
    (
        "figures-out-is-file",
        [F, "--paper", "--out", "{d}/f"],
        {"f": "x"},
        "exists and is not a directory",
    ),
    (
        "figures-out-dev-null",
        [F, "--paper", "--out", "/dev/null"],
        {},
        "exists and is not a directory",
    ),
    ("figures-out-proc", [F, "--paper", "--out", "/proc/orbits-figures"], {}, ""),
    ("figures-format", [F, "--paper", "--out", "{d}/o", "--formats", "gif"], {}, "invalid choice"),
    ("figures-survey-missing", [F, "--survey", "{d}/none", "--out", "{d}/o"], {}, "none"),
    (
        "figures-survey-list",
        [F, "--survey", "{d}/s", "--out", "{d}/o"],
        {"s": survey("list")},
        "grid",
    ),
    *[
        (
            f"figures-survey-{damage}",
            [F, "--survey", "{d}/s", "--out", "{d}/o"],
            {"s": survey("grid", damage)},
            "",
        )
        for damage in (
            "no-manifest",
            "manifest-not-json",
            "manifest-empty",
            "manifest-incomplete",
            "manifest-old-format",
            "ledger-damaged",
            "part-missing",
            "part-truncated",
            "part-empty",
            "part-changed",
            "stray-bak-and-truncated",
            "stale-temporary",
        )
    ],
    # ------------------------------------------------------- survey
    (
        "survey-resolution-100000",
        [S, "--resolution", "100000", "--n-max", "2", "--out", "{d}/s"],
        {},
        "memory",
    ),
    (
        "survey-resolution-300-n-max-1000",
        [S, "--resolution", "300", "--n-max", "1000", "--out", "{d}/s"],
        {},
        "",
    ),
    (
        "survey-resolution-1",
        [S, "--resolution", "1", "--n-max", "2", "--out", "{d}/s"],
        {},
        ">= 2",
    ),
    ("survey-chunk-zero", GRID[:-1] + ["0", "--out", "{d}/s"], {}, ">= 1"),
    (
        "survey-huge-chunk-q",
        [
            S,
            "--resolution",
            "300",
            "--n-max",
            "50",
            "--q-max",
            "300",
            "--chunk",
            "100000",
            "--out",
            "{d}/s",
        ],
        {},
        "",
    ),
    (
        "survey-threads-scheduler",  # the workers' processes never see --threads
        ["--threads", "1"] + GRID + ["--out", "{d}/s", "--scheduler", "tcp://127.0.0.1:9"],
        {},
        "--threads sets this machine's threads",
    ),
    (
        "survey-cuda-scheduler",
        GRID + ["--out", "{d}/s", "--device", "cuda", "--scheduler", "tcp://127.0.0.1:9"],
        {},
        "give one or the other",
    ),
    ("survey-no-source", [S, "--n-max", "2", "--out", "{d}/s"], {}, "--resolution"),
    ("survey-no-n-max", [S, "--resolution", "4", "--out", "{d}/s"], {}, "--n-max"),
    ("survey-no-out", [S, "--resolution", "4", "--n-max", "2"], {}, "--out"),
    (
        "survey-two-sources",
        GRID + ["--out", "{d}/s", "--bodies", "{d}/b.csv"],
        bodies(GOOD_BODIES),
        "not allowed",
    ),
    (
        "survey-format",
        [S, "--resolution", "4", "--n-max", "2", "--format", "xlsx", "--out", "{d}/s"],
        {},
        "invalid choice",
    ),
    (
        "survey-skip-invalid-grid",
        GRID + ["--out", "{d}/s", "--skip-invalid"],
        {},
        "--skip-invalid",
    ),
    ("survey-bodies-bad", SURVEY_B, bodies("I1,I2,I3\nTrue,2,2.5\n"), "row 1"),
    ("survey-bodies-name", SURVEY_B + ["--name", "x"], bodies(GOOD_BODIES), "--name"),
    ("scheduler-garbage", GRID + ["--out", "{d}/s", "--scheduler", "garbage"], {}, "scheduler"),
    ("scheduler-empty", GRID + ["--out", "{d}/s", "--scheduler", ""], {}, "scheduler"),
    (
        "scheduler-http",
        GRID + ["--out", "{d}/s", "--scheduler", "http://localhost:8787"],
        {},
        "scheduler",
    ),
    (
        "scheduler-port-too-big",
        GRID + ["--out", "{d}/s", "--scheduler", "tcp://127.0.0.1:99999"],
        {},
        "scheduler",
    ),
    (
        "scheduler-unreachable",
        GRID + ["--out", "{d}/s", "--scheduler", "tcp://127.0.0.1:9"],
        {},
        "within",
    ),
    ("survey-out-file", GRID + ["--out", "{d}/f"], {"f": "x"}, "not a directory"),
    ("survey-out-dev-null", GRID + ["--out", "/dev/null"], {}, ""),
    ("survey-out-proc", GRID + ["--out", "/proc/orbits-survey"], {}, ""),
    (
        "survey-out-foreign",
        GRID + ["--out", "{d}/s"],
        {"s/notes.txt": "mine"},
        "not a survey directory",
    ),
    (
        "survey-other-parameters",
        [
            S,
            "--resolution",
            "4",
            "--n-max",
            "3",
            "--format",
            "csv",
            "--chunk",
            "2",
            "--out",
            "{d}/s",
        ],
        {"s": survey("grid")},
        "different parameters",
    ),
    (
        "survey-other-bodies",
        SURVEY_B + ["--chunk", "2"],
        {"s": survey("list"), **bodies(GOOD_BODIES)},
        "different parameters",
    ),
    (
        "survey-rerun-bad-manifest",
        GRID + ["--out", "{d}/s"],
        {"s": survey("grid", "manifest-not-json")},
        "not valid JSON",
    ),
    (
        "survey-rerun-incomplete-manifest",
        GRID + ["--out", "{d}/s"],
        {"s": survey("grid", "manifest-incomplete")},
        "damaged",
    ),
    (
        "survey-rerun-old-manifest",
        GRID + ["--out", "{d}/s"],
        {"s": survey("grid", "manifest-old-format")},
        "new directory",
    ),
    (
        "survey-rerun-no-manifest",
        GRID + ["--out", "{d}/s"],
        {"s": survey("grid", "no-manifest")},
        "no manifest.json",
    ),
    ("survey-check-missing", [S, "--check", "{d}/none"], {}, "not a directory"),
    ("survey-check-not-survey", [S, "--check", "{d}"], {}, "not a survey directory"),
    (
        "survey-check-bad-manifest",
        [S, "--check", "{d}/s"],
        {"s": survey("grid", "manifest-not-json")},
        "not valid JSON",
    ),
    (
        "survey-check-ledger",
        [S, "--check", "{d}/s"],
        {"s": survey("grid", "ledger-damaged")},
        "ledger",
    ),
    (
        "survey-check-extra-option",
        [S, "--check", "{d}/s", "--n-max", "3"],
        {"s": survey("grid")},
        "only the directory",
    ),
    # ------------------------------------------------------- animate
    ("animate-no-spin", [A] + FIG6 + ["--out", "{d}/a.gif"], {}, "exactly one spin"),
    (
        "animate-two-spins",
        [A] + FIG6 + ["--theta", "1", "--n", "2", "--out", "{d}/a.gif"],
        {},
        "exactly one spin",
    ),
    (
        "animate-q-without-p",
        [A] + FIG6 + ["--q", "2", "--theta", "1", "--out", "{d}/a.gif"],
        {},
        "",
    ),
    ("animate-flip-large", [A] + FIG6 + ["--flip", "1", "--out", "{d}/a.gif"], {}, "pi/4"),
    (
        "animate-frames-zero",
        [A] + FIG6 + ["--theta", "1", "--frames", "0", "--out", "{d}/a.gif"],
        {},
        "argument --frames: must be an integer >= 2",
    ),
    ("animate-suffix", [A] + FIG6 + ["--theta", "1", "--out", "{d}/a.txt"], {}, ""),
    (
        "animate-out-fifo",
        [A] + FIG6 + ["--theta", "1", "--frames", "2", "--out", "{d}/a.gif"],
        {"a.gif": FIFO},
        "FIFO",
    ),
    (
        "animate-out-no-directory",
        [A] + FIG6 + ["--theta", "1", "--frames", "2", "--out", "{d}/none/a.gif"],
        {},
        "does not exist",
    ),
    (
        "animate-periods-inf",
        [A] + FIG6 + ["--theta", "1", "--periods", "inf", "--out", "{d}/a.gif"],
        {},
        "finite",
    ),
    ("animate-no-orbit", [A] + FIG6 + ["--n", "1", "--out", "{d}/a.gif"], {}, ""),
    # --- issue 20: survey ledger and links ---
    *[
        (f"survey-{verb}-{damage}", argv, {"s": survey("grid", damage)}, "its own SHA-256")
        for damage in _HAND_EDITS
        for verb, argv in (
            ("rerun", GRID + ["--out", "{d}/s"]),
            ("check", [S, "--check", "{d}/s"]),
        )
    ],
    (
        "survey-rerun-parameters-edited-forged",
        GRID + ["--out", "{d}/s"],
        {"s": survey("grid", "parameters-edited-forged")},
        "different parameters (n_max)",
    ),
    *[
        (f"survey-{verb}-{damage}", argv, {"s": survey("grid", damage)}, "symbolic link")
        for damage in _LINKS
        for verb, argv in (
            ("rerun", GRID + ["--out", "{d}/s"]),
            ("check", [S, "--check", "{d}/s"]),
        )
    ],
    (
        "survey-rerun-no-manifest-with-report",
        GRID + ["--out", "{d}/s"],
        {"s": survey("grid", "no-manifest")},
        "(deleted?)",
    ),
    (
        "figures-survey-no-manifest",
        [F, "--survey", "{d}/s", "--out", "{d}/o"],
        {"s": survey("grid", "no-manifest")},
        "no manifest.json",
    ),
    # --- issue 20: arguments, files, names, streams ---
    (
        "mass-with-t-handle",
        [P, "--t-handle", "8", "4", "1", "--mass", "0.05", "--theta", "0.3"],
        {},
        "--mass applies to --box and --cylinder, not to --t-handle",
    ),
    (
        "mass-with-moments",
        [P, "--moments", "1", "2", "2.5", "--mass", "1", "--theta", "0.3"],
        {},
        "not to --moments",
    ),
    (
        "density-with-box",
        [P, "--box", "1", "2", "3", "--density", "2", "--theta", "0.3"],
        {},
        "--density applies to --mesh, not to --box",
    ),
    (
        "units-with-theta",
        [P] + FIG6 + ["--theta", "0.3", "--units", "Hz"],
        {},
        "--units applies to --omega, not to --theta",
    ),
    (
        "unit-with-preset",
        [P] + FIG6 + ["--theta", "0.3", "--unit", "MHz"],
        {},
        "not to --preset",
    ),
    ("phi-with-omega", [P] + FIG6 + ["--omega", "1", "2", "3", "--phi", "1"], {}, "--phi"),
    (
        "degrees-with-period-ratio",
        [P] + FIG6 + ["--period-ratio", "2", "--degrees"],
        {},
        "not to --period-ratio",
    ),
    ("theta-60", [P] + FIG6 + ["--theta", "60"], {}, "looks like degrees"),
    ("theta-400-degrees", [P] + FIG6 + ["--theta", "400", "--degrees"], {}, "[-360, 360]"),
    (
        "catalog-mass-with-preset",
        CAT + ["{d}/c.csv", "--mass", "2"],
        {},
        "--mass applies to --box and --cylinder, not to --preset",
    ),
    (
        "figures-q-max-with-paper",
        [F, "--paper", "--q-max", "3", "--out", "{d}/o"],
        {},
        "not to --paper",
    ),
    (
        "verify-count-with-body",
        [V] + FIG6 + ["--bodies", "4"],
        {},
        "--bodies applies to the region sample",
    ),
    ("verify-mass-without-body", [V, "--mass", "2"], {}, "not to the region sample"),
    (
        "survey-check-q-max",
        [S, "--check", "{d}/s", "--q-max", "3"],
        {"s": survey("grid")},
        "only the directory",
    ),
    (
        "animate-branch-with-theta",
        [A] + FIG6 + ["--theta", "1", "--branch", "SAM", "--out", "{d}/a.gif"],
        {},
        "--branch applies to --n and --p, not to --theta",
    ),
    ("animate-theta-45", [A] + FIG6 + ["--theta", "45", "--out", "{d}/a.gif"], {}, "degrees"),
    (
        "bodies-unclosed-quote",
        BODIES,
        bodies('I1,I2,I3,name\n0.26,0.55,0.793662,"a\n0.3,0.5,0.7,b\n0.2,0.6,0.75,c\n'),
        "line 2: a quote opened on this line is never closed",
    ),
    (
        "survey-bodies-unclosed-quote",
        SURVEY_B,
        bodies('I1,I2,I3,name\n0.26,0.55,0.793662,"a\n0.3,0.5,0.7,b\n0.2,0.6,0.75,c\n'),
        "line 2",
    ),
    (
        "bodies-quote-closed-rows-later",
        BODIES,
        bodies('I1,I2,I3,name\n0.26,0.55,0.793662,"a\n0.3,0.5,0.7,b\n0.2,0.6,0.75,c"\n'),
        "look like rows of bodies",
    ),
    (
        "animate-dpi-20000",
        [A] + FIG6 + ["--theta", "1", "--dpi", "20000", "--out", "{d}/a.gif"],
        {},
        "--dpi must be a number from 7 to 7281",
    ),
    (
        "animate-dpi-7000-memory",
        [A] + FIG6 + ["--theta", "1", "--dpi", "7000", "--out", "{d}/a.mp4"],
        {},
        "for one frame",
    ),
    (
        "animate-frames-1e8",
        [A] + FIG6 + ["--theta", "1", "--frames", "100000000", "--out", "{d}/a.gif"],
        {},
        "lower --frames or --dpi",
    ),
    (
        "bodies-subnormal",
        BODIES,
        bodies("I1,I2,I3\n0.3,0.5,0.7\n1e-320,2e-320,2.5e-320\n"),
        "row 2: I1 1e-320 is below the smallest normal double",
    ),
]


def _argv(argv, directory):
    return [word.format(d=directory) for word in argv]


def check_clean_failure(code, err, fragment):
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1, err
    assert lines[0].startswith("orbits: error: "), err
    assert "Traceback" not in err and "Error:" not in lines[0].replace("error:", ""), err
    assert fragment in lines[0], err


@pytest.mark.parametrize("case", CLI_CASES, ids=[c[0] for c in CLI_CASES])
def test_cli(case, tmp_path, capsys, monkeypatch, surveys):
    _, argv, files, fragment = case
    directory = tmp_path / "work"
    directory.mkdir()
    keep = prepare(directory, files, surveys)
    monkeypatch.chdir(directory)
    monkeypatch.setattr(orbits.survey.runner, "CONNECT_TIMEOUT", 2)
    before, device = snapshot(directory), device_state()
    capsys.readouterr()
    code = main(_argv(argv, directory))
    _, err = capsys.readouterr()
    check_clean_failure(code, err, fragment.format(d=directory))
    assert snapshot(directory) == before
    assert device_state() == device
    for server in keep:
        server.close()


SUBPROCESS_CASES = [
    "t-handle-1e200",
    "scheduler-garbage",
    "out-fifo",
    "out-dev-null",
    "out-trailing-slash",
    "n-max-1e23",
    "bodies-true",
    "verify-tolerance-negative",
    "figures-survey-manifest-incomplete",
    "survey-rerun-bad-manifest",
]


@pytest.mark.parametrize("name", SUBPROCESS_CASES)
def test_cli_subprocess(name, tmp_path, surveys):
    """The same, through a real process: ``python -m orbits``."""
    _, argv, files, fragment = next(c for c in CLI_CASES if c[0] == name)
    directory = tmp_path / "work"
    directory.mkdir()
    keep = prepare(directory, files, surveys)
    before = snapshot(directory)
    env = dict(os.environ, PYTHONPATH=str(Path(orbits.__file__).parent.parent))
    done = subprocess.run(
        [sys.executable, "-m", "orbits", *_argv(argv, directory)],
        cwd=directory,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    check_clean_failure(done.returncode, done.stderr, fragment)
    assert done.stdout == ""
    assert snapshot(directory) == before
    for server in keep:
        server.close()


# ------------------------------------------------------------------ API cases
def _body():
    return orbits.Body.preset("fig6")


def _frame():
    return orbits.closed_orbits(_body(), n_max=2)


def _catalog_file(directory, mutate):
    path = directory / "c.csv"
    orbits.write_catalog(_frame(), path)
    path.write_bytes(mutate(path.read_bytes()))
    return path


def _cut_at_line(raw):
    """A catalog cut at a line boundary: two whole rows fewer."""
    return b"".join(raw.splitlines(keepends=True)[:-2])


def _abc_in_period(raw):
    lines = raw.split(b"\n")
    first = next(k for k, line in enumerate(lines) if not line.startswith(b"#"))
    column = lines[first].split(b",").index(b"period")
    cells = lines[-2].split(b",")
    cells[column] = b"abc"
    lines[-2] = b",".join(cells)
    return b"\n".join(lines)


def _drop_checksum(raw):
    return b"".join(
        line for line in raw.splitlines(keepends=True) if not line.startswith(b"# sha256")
    )


def _flip_a_digit(raw):
    k = raw.rindex(b"e-")  # a digit of the last row's exponent
    return raw[: k - 1] + bytes([raw[k - 1] ^ 1]) + raw[k:]


def call(function, *args, **kwargs):
    """A case whose failing call needs no files."""
    return lambda directory, surveys: lambda: function(*args, **kwargs)


def on_file(make, function, **kwargs):
    """A case that first writes a file (``make(directory)`` returns its path)."""

    def setup(directory, surveys):
        path = make(directory)
        return lambda: function(path, **kwargs)

    return setup


def on_survey(kind, damage, function):
    def setup(directory, surveys):
        prepare(directory, {"s": survey(kind, damage)}, surveys)
        return lambda: function(directory / "s")

    return setup


def _fifo(directory):
    os.mkfifo(directory / "fifo")
    return directory / "fifo"


def _zero_link(directory):
    os.symlink("/dev/zero", directory / "z")
    return directory / "z"


def _bodies_file(text):
    return lambda directory: _write(directory / "b.csv", text)


def _read_bodies(path, **kwargs):
    from orbits.catalog import read_bodies_csv

    return read_bodies_csv(path, **kwargs)


def _grid(directory, resolution, n_max, **kwargs):
    return orbits.survey.Survey.grid(directory / "s", resolution, n_max, **kwargs)


API_CASES = [
    ("Body-nan", call(orbits.Body, [1, 2, np.nan])),
    ("Body-symmetric", call(orbits.Body, [1, 1, 2])),
    ("Body-triangle", call(orbits.Body, [1, 2, 4])),
    ("Body-negative", call(orbits.Body, [-1, 2, 2.5])),
    ("Body-two-moments", call(orbits.Body, [1, 2])),
    ("Body-1e200-overflow", call(orbits.Body, [1e200, 2e200, 1e308])),
    ("total_phase-nan", lambda d, s: lambda: orbits.total_phase(_body(), np.nan)),
    ("total_phase-unfoldable", lambda d, s: lambda: orbits.total_phase(_body(), 1e20)),
    ("closed_orbits-n-max-zero", lambda d, s: lambda: orbits.closed_orbits(_body(), n_max=0)),
    # orbits.closed_orbits itself has no bound yet (see the note at the end)
    ("catalog-n-max-1e22", lambda d, s: lambda: orbits.catalog(_body(), n_max=10**22)),
    ("catalog-q-max-100000", lambda d, s: lambda: orbits.catalog(_body(), n_max=30, q_max=100000)),
    ("catalog-no-bodies", call(orbits.catalog, [], n_max=2)),
    ("catalog-n-max-float", lambda d, s: lambda: orbits.catalog(_body(), n_max=1.5)),
    # a flag that is not a bool ("no" is a true string) and a progress that
    # is not callable (raised after the first body's search)
    ("catalog-verify-no", lambda d, s: lambda: orbits.catalog(_body(), n_max=2, verify="no")),
    (
        "catalog-verify-array",
        lambda d, s: lambda: orbits.catalog(_body(), n_max=2, verify=np.array([1, 2])),
    ),
    ("catalog-progress-text", lambda d, s: lambda: orbits.catalog(_body(), progress="bar")),
    ("write_catalog-dev-null", lambda d, s: lambda: orbits.write_catalog(_frame(), "/dev/null")),
    ("write_catalog-fifo", on_file(_fifo, lambda p: orbits.write_catalog(_frame(), p))),
    (
        "write_catalog-link-to-device",
        on_file(_zero_link, lambda p: orbits.write_catalog(_frame(), p)),
    ),
    (
        "write_catalog-trailing-slash",
        lambda d, s: lambda: orbits.write_catalog(_frame(), f"{d}/new/"),
    ),
    ("read_catalog-missing", lambda d, s: lambda: orbits.read_catalog(d / "none.csv")),
    ("read_catalog-directory", lambda d, s: lambda: orbits.read_catalog(d)),
    (
        "read_catalog-cut-at-line",
        on_file(lambda d: _catalog_file(d, _cut_at_line), orbits.read_catalog),
    ),
    ("read_catalog-abc", on_file(lambda d: _catalog_file(d, _abc_in_period), orbits.read_catalog)),
    (
        "read_catalog-abc-unchecked",
        on_file(lambda d: _catalog_file(d, _abc_in_period), orbits.read_catalog, check=False),
    ),
    (
        "read_catalog-no-checksum",
        on_file(lambda d: _catalog_file(d, _drop_checksum), orbits.read_catalog),
    ),
    (
        "read_catalog-changed-digit",
        on_file(lambda d: _catalog_file(d, _flip_a_digit), orbits.read_catalog),
    ),
    (
        "read_bodies_csv-index",
        on_file(_bodies_file("I1,I2,I3\n0.1,0.26,0.55,0.793662\n"), _read_bodies),
    ),
    ("read_bodies_csv-true", on_file(_bodies_file("I1,I2,I3\nTrue,2,2.5\n"), _read_bodies)),
    (
        "read_bodies_csv-underscore",
        on_file(_bodies_file("I1,I2,I3\n1_000,1200,1500\n"), _read_bodies),
    ),
    *[
        (f"read_survey-{damage}", on_survey("grid", damage, orbits.survey.read_survey))
        for damage in (
            "no-manifest",
            "manifest-not-json",
            "manifest-incomplete",
            "ledger-damaged",
            "ledger-outside",
            "part-missing",
            "part-truncated",
            "part-empty",
            "part-changed",
            "stray-bak-and-truncated",
            # --- issue 20: survey ledger and links ---
            # (parameters-edited-forged reads: a forger who recomputes the
            # checksum is beyond a checksum; a rerun still refuses it)
            *(damage for damage in _LEDGER_EDITS if damage != "parameters-edited-forged"),
            *_LINKS,
            "no-bodies-folder",
        )
    ],
    *[
        (f"check_survey-{damage}", on_survey("grid", damage, orbits.survey.check_survey))
        for damage in (*_HAND_EDITS, *_LINKS)
    ],
    (
        "Survey-rerun-link-lock",
        on_survey(
            "grid",
            "link-lock",
            lambda p: orbits.survey.Survey.grid(p, 4, 2, fmt="csv", chunk=2).run(),
        ),
    ),
    ("survey_grid-list", on_survey("list", None, orbits.survey.survey_grid)),
    ("check_survey-ledger", on_survey("grid", "ledger-damaged", orbits.survey.check_survey)),
    ("check_survey-not-json", on_survey("grid", "manifest-not-json", orbits.survey.check_survey)),
    ("Survey-resolution-100000", lambda d, s: lambda: _grid(d, 100000, 2)),
    ("Survey-n-max-1000-resolution-300", lambda d, s: lambda: _grid(d, 300, 1000)),
    ("Survey-chunk-zero", lambda d, s: lambda: _grid(d, 4, 2, chunk=0)),
    ("Survey-format", lambda d, s: lambda: _grid(d, 4, 2, fmt="xlsx")),
    ("Survey-scheduler-garbage", lambda d, s: lambda: _grid(d, 4, 2).run(scheduler="garbage")),
    (
        "Survey-other-parameters",
        on_survey(
            "grid", None, lambda p: orbits.survey.Survey.grid(p, 4, 3, fmt="csv", chunk=2).run()
        ),
    ),
    # --- issue 20: arguments, files, names, streams ---
    (
        "read_bodies_csv-unclosed-quote",
        on_file(
            _bodies_file('I1,I2,I3,name\n0.26,0.55,0.793662,"a\n0.3,0.5,0.7,b\n'), _read_bodies
        ),
    ),
    (
        "read_bodies_csv-subnormal",
        on_file(_bodies_file("I1,I2,I3\n1e-310,0.5,0.7\n"), _read_bodies),
    ),
    ("set_num_threads-text", call(orbits.set_num_threads, "2")),
    ("write_catalog-list", lambda d, s: lambda: orbits.write_catalog([1, 2], d / "c.csv")),
    (
        "poinsot_animation-dpi-negative",
        lambda d, s: lambda: _animation(d, dpi=-80),
    ),
    ("poinsot_animation-frames-1e8", lambda d, s: lambda: _animation(d, frames=10**8)),
    # --- issue 20: symmetric bodies from geometry ---
    (
        "Body.from_point_masses-equilateral-turned",
        call(
            orbits.Body.from_point_masses,
            [1.0, 1.0, 1.0],
            np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 3**0.5 / 2, 0.0]])
            @ np.array([[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]]).T
            + [3.0, -1.0, 2.0],
        ),
    ),
    (
        "Body.from_inertia_tensor-rotated-symmetric",
        call(
            orbits.Body.from_inertia_tensor,
            (lambda r: r @ np.diag([1.0, 1.0, 1.5]) @ r.T)(
                np.array([[0.36, 0.48, -0.8], [-0.8, 0.6, 0.0], [0.48, 0.64, 0.6]])
            ),
        ),
    ),
    (
        "Body.from_inertia_tensor-past-flat",
        call(orbits.Body.from_inertia_tensor, np.diag([1.0, 2.0, 3.01])),
    ),
    (
        "Body.from_inertia_tensor-defect-unknown",
        call(orbits.Body.from_inertia_tensor, np.diag([1.0, 2.0, 2.5]), defect="ignore"),
    ),
]


def _animation(directory, **kwargs):
    from orbits.animate import poinsot_animation

    return poinsot_animation(_body(), 1.0, out=directory / "a.gif", **kwargs)


@pytest.mark.parametrize("case", API_CASES, ids=[c[0] for c in API_CASES])
def test_api(case, tmp_path, surveys, monkeypatch):
    """Each API case raises an OrbitsError and leaves its directory untouched."""
    _, setup = case
    directory = tmp_path / "work"
    directory.mkdir()
    monkeypatch.chdir(directory)
    failing = setup(directory, surveys)
    before, device = snapshot(directory), device_state()
    with pytest.raises(OrbitsError):
        failing()
    assert snapshot(directory) == before
    assert device_state() == device


def _silent_listener():
    """A local port that accepts connections and never sends a byte."""
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    held = []

    def accept():
        while True:
            try:
                held.append(server.accept()[0])
            except OSError:  # closed
                return

    threading.Thread(target=accept, daemon=True).start()
    return server, held


def _http_server():
    """A local HTTP server (what a dashboard port, 8787, answers with)."""
    import http.server
    import threading

    # handlers on daemon threads: one stuck reading the client's bytes as a
    # request line must not hold up shutdown()
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):  # not on the test's stderr
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Quiet)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


@pytest.mark.parametrize("kind", ["silent", "http"])
def test_scheduler_port_that_is_no_scheduler(kind, tmp_path, capsys, monkeypatch):
    """A port that accepts and never answers (or answers HTTP, as the
    dashboard's 8787 does) hung --scheduler for good (an audit: still
    waiting after 623 s); now one line within 1.5 timeouts, nothing written."""
    pytest.importorskip("distributed")
    import time

    monkeypatch.setattr(orbits.survey.runner, "CONNECT_TIMEOUT", 1)
    if kind == "silent":
        server, held = _silent_listener()
        port, stop = server.getsockname()[1], server.close
    else:
        server = _http_server()
        port = server.server_address[1]

        def stop():
            server.shutdown()
            server.server_close()

    try:
        capsys.readouterr()
        start = time.monotonic()
        code = main(
            GRID + ["--out", str(tmp_path / "s"), "--scheduler", f"tcp://127.0.0.1:{port}"]
        )
        took = time.monotonic() - start
        _, err = capsys.readouterr()
    finally:
        stop()
    check_clean_failure(code, err, "is it a dask scheduler's address")
    assert took < 30  # 1.5 s and the start-up, on a loaded machine
    assert not (tmp_path / "s").exists()


def test_scheduler_without_workers(tmp_path, capsys, monkeypatch):
    """A scheduler with no worker: one line stating the timeout, nothing written."""
    distributed = pytest.importorskip("distributed")
    monkeypatch.setattr(orbits.survey.runner, "CONNECT_TIMEOUT", 1)
    with distributed.LocalCluster(
        n_workers=0, processes=False, dashboard_address=None, protocol="tcp", scheduler_port=0
    ) as cluster:
        capsys.readouterr()
        code = main(
            GRID + ["--out", str(tmp_path / "s"), "--scheduler", cluster.scheduler_address]
        )
        _, err = capsys.readouterr()
    check_clean_failure(code, err, "has no workers (waited 1 s)")
    assert not (tmp_path / "s").exists()


CASE_COUNT = len(CLI_CASES) + len(API_CASES)
# Not in the table, because they would exhaust the machine rather than fail:
# orbits.closed_orbits(body, n_max=10**22) and (n_max=30, q_max=100000) build
# every fraction first (search.phase_levels has no bound), and
# orbits.checks.verify(10**8, 22) raises MemoryError; the command line bounds
# all three before any work (cases n-max-1e23, figures-huge-n-max,
# verify-bodies-1e8).


def test_the_table_has_enough_cases():
    assert len(CLI_CASES) >= 80 and CASE_COUNT >= 110
