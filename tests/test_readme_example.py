"""The README's real-object quick start runs as written and says what is true."""

import contextlib
import io
import re
import shlex
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from orbits.cli import main

README = Path(__file__).resolve().parent.parent / "README.md"


def example_blocks():
    text = README.read_text(encoding="utf-8")
    section = re.search(
        r"<!-- example:phone:start -->(.*?)<!-- example:phone:end -->", text, re.DOTALL
    ).group(1)
    python = re.search(r"```python\n(.*?)```", section, re.DOTALL).group(1)
    bash = re.search(r"```bash\n(.*?)```", section, re.DOTALL).group(1).strip()
    return python, bash


@pytest.fixture(scope="module")
def ran():
    python, _ = example_blocks()
    namespace = {}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(python, str(README), "exec"), namespace)  # noqa: S102 (as written)
    return namespace, out.getvalue().splitlines()


def test_python_example_prints_what_the_comments_say(ran):
    namespace, lines = ran
    assert lines[0].startswith("LAM 2.337")
    assert lines[1].startswith("0.02424") and " 0.003857" in lines[1]
    motion, phone = namespace["motion"], namespace["phone"]
    assert motion.D < phone.moments[1]  # LAM: D < I2
    assert "precession=0.5165" in lines[3] and "ratio=4.525" in lines[3]


def test_example_period_against_integration(ran):
    """Euler's equations integrated (DOP853, rtol 1e-13) return to omega0 after
    the closed-form period T, and not after T/2 (where omega is mirrored)."""
    motion = ran[0]["motion"]
    i1, i2, i3 = motion.body.moments

    def euler(_, w):
        return [
            (i2 - i3) * w[1] * w[2] / i1,
            (i3 - i1) * w[2] * w[0] / i2,
            (i1 - i2) * w[0] * w[1] / i3,
        ]

    sol = solve_ivp(
        euler,
        (0.0, motion.period),
        motion.omega0,
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
        dense_output=True,
    )
    scale = np.linalg.norm(motion.omega0)
    assert np.abs(sol.y[:, -1] - motion.omega0).max() < 1e-8 * scale
    assert np.abs(sol.sol(0.5 * motion.period) - motion.omega0).max() > 1e-2 * scale
    # energy in J from its definition
    assert motion.energy == pytest.approx(
        0.5 * np.dot(motion.body.moments, motion.omega0**2), rel=1e-14
    )


def test_command_line_example(ran, capsys):
    _, bash = example_blocks()
    words = shlex.split(bash)
    assert words[0] == "orbits"
    assert main(words[1:]) == 0
    # rows: name, [unit], value (issue #21: every printed quantity has its unit)
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()}
    assert "[s]" in lines["period"] and "[kg m^2]" in lines["D"]
    rows = {name: line.split()[-1] for name, line in lines.items()}
    motion = ran[0]["motion"]
    assert float(rows["D"]) == pytest.approx(motion.D, rel=1e-14)
    assert float(rows["period"]) == pytest.approx(motion.period, rel=1e-14)
    assert rows["branch"].strip() == "LAM"
