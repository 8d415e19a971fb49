"""The console examples of docs/cli.md are what the command prints.

Every ``$ orbits phase ...`` example, and every example whose output is a
refusal (``orbits: error: ...``, which the command prints before any work),
is run in this process and its output compared with the page line by line:
words exactly, numbers to 1e-13 relative (the last digit of a 17-digit
number may differ with the CPU, e.g. under ``NUMBA_CPU_NAME=generic``).  A
line the page elides with ``...`` is compared up to the ellipsis.
"""

import re
import shlex
import warnings
from pathlib import Path

import pytest

from orbits.cli import main

PAGE = Path(__file__).resolve().parents[1] / "docs" / "cli.md"
NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def console_examples(text):
    """(command, expected output lines) of each ``$ orbits`` line of the page."""
    examples = []
    for block in re.findall(r"```console\n(.*?)```", text, flags=re.S):
        command = None
        for line in block.splitlines():
            if line.startswith("$ "):
                command = (line[2:], [])
                examples.append(command)
            elif command is not None:
                command[1].append(line)
    return examples


def checked(example):
    command, lines = example
    argv = shlex.split(command)
    refused = len(lines) == 1 and lines[0].startswith("orbits: error:")
    return argv[0] == "orbits" and (argv[1] == "phase" or refused)


EXAMPLES = [e for e in console_examples(PAGE.read_text(encoding="utf-8")) if checked(e)]


def test_the_page_has_the_examples():
    commands = [command for command, _ in EXAMPLES]
    assert sum(c.startswith("orbits phase") for c in commands) >= 5
    assert any("--periods 263 27.38" in c for c in commands)
    assert any("--rotational-constants" in c for c in commands)


def tokens(line):
    return [t for t in re.split(r"[\s,]+", line) if t]


def same_line(expected, got):
    want, have = tokens(expected), tokens(got)
    if "..." in expected:
        want = tokens(expected.split("...")[0])  # whole fields before it
        have = have[: len(want)]
    if len(want) != len(have):
        return False
    for a, b in zip(want, have):
        if a == b:
            continue
        if not (NUMBER.match(a) and NUMBER.match(b)):
            return False
        if float(b) != pytest.approx(float(a), rel=1e-13, abs=1e-300):
            return False
    return True


@pytest.mark.parametrize("example", EXAMPLES, ids=[c for c, _ in EXAMPLES])
def test_console_example(example, capsys, tmp_path, monkeypatch):
    command, expected = example
    monkeypatch.chdir(tmp_path)  # a refused --out names a file here, never written
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        code = main(shlex.split(command)[1:])
    out, err = capsys.readouterr()
    refused = expected[0].startswith("orbits: error:")
    assert code == (2 if refused else 0), err
    got = out.splitlines() + err.splitlines()
    assert len(got) == len(expected), "\n".join(got)
    for want, have in zip(expected, got):
        assert same_line(want, have), f"\npage: {want}\ngot:  {have}"
    assert list(tmp_path.iterdir()) == []
