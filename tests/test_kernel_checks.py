"""The checks, fold and clamp inside the kernels (issue #18, item 3) raise the
errors of the reference path: same type, same message, same precedence
when several inputs are bad at once (the kernels flag points; the host then
names the error the serial checks named before)."""

import importlib
import re

import numpy as np
import pytest

import orbits
from orbits.errors import AngleError, InputError, SeparatrixError

BODY = (1.0, 2.0, 2.5)
MANY = [BODY, (0.3, 0.9, 1.1)]
TOO_LARGE = "angle 1e+09 rad is too large to fold"


@pytest.mark.parametrize("function", [orbits.total_phase, orbits.phases])
@pytest.mark.parametrize("moments", [BODY, MANY], ids=["one body", "two bodies"])
@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        # a too-large theta anywhere wins over a NaN before it (the fold ran first)
        (dict(theta=[0.2, np.nan, 1e9]), AngleError, TOO_LARGE),
        (dict(theta=[np.nan, 1e9]), AngleError, TOO_LARGE),
        (dict(theta=[0.2, np.nan]), AngleError, "theta must be finite, got nan"),
        # phi: not finite is checked before theta is folded; too large after
        (dict(theta=1e9, phi=np.inf), AngleError, "phi must be finite, got inf"),
        (dict(theta=np.nan, phi=1e9), AngleError, TOO_LARGE),
        (dict(theta=1e9, phi=[0.1, 0.2]), AngleError, TOO_LARGE),
        # the fold's error comes before a shape mismatch
        (dict(theta=[0.1, 1e9, 0.3], phi=[0.1, 0.2]), AngleError, TOO_LARGE),
        (dict(dtheta=[0.1, 2.0]), AngleError, "theta_c + dtheta = "),
        (dict(dtheta=[0.0, np.nan]), SeparatrixError, "dtheta = 0 puts the spin"),
        (dict(dtheta=[np.inf]), AngleError, "dtheta must be finite, got inf"),
    ],
)
def test_errors_and_their_order(function, moments, kwargs, error, message):
    with pytest.raises(error) as caught:
        function(moments, **kwargs)
    assert str(caught.value).startswith(message)


def test_shape_mismatch_named():
    with pytest.raises(InputError, match=r"shapes do not broadcast together: moments \(\), "):
        orbits.total_phase(BODY, [0.1, 0.2, 0.3], phi=[0.1, 0.2])


def test_separatrix_theta_named():
    theta_c = orbits.critical_angle(BODY)
    for function in (orbits.total_phase, orbits.phases):
        with pytest.raises(SeparatrixError, match="is within the rounding error") as info:
            function(BODY, [0.1, theta_c])
        # the angle is printed so that it reads back to the same double, shortest form
        shown = re.search(r"theta = (\S+) is within", str(info.value)).group(1)
        assert float(shown) == theta_c and shown == repr(float(theta_c))
        with pytest.raises(SeparatrixError, match="dtheta = 0 puts the spin"):
            function(BODY, dtheta=[0.1, 0.0])


def test_folded_in_kernel_equals_folded_first():
    """theta folded inside the kernel gives the values of theta folded first
    (fold_angle), bit for bit, for total_phase and every column of phases."""
    theta = np.random.default_rng(11).uniform(-40.0, 40.0, 3001)
    folded = importlib.import_module("orbits.phases").fold_angle(theta)
    assert not np.array_equal(theta, folded)
    np.testing.assert_array_equal(
        orbits.total_phase(BODY, theta, phi=-2.5), orbits.total_phase(BODY, folded, phi=2.5)
    )
    a = orbits.phases(MANY[1], theta, 7.0)
    b = orbits.phases(MANY[1], folded, 7.0)
    for column in a.columns:
        np.testing.assert_array_equal(a[column].to_numpy(), b[column].to_numpy())
