"""Bodies: constructors, ordering, frames and validation."""

import math

import numpy as np
import pytest

import orbits
from orbits import Body, InputError, NonPhysicalBodyError, SymmetricTopError

EPS = np.finfo(float).eps


def box_inertia(mass, sides, centre):
    """Inertia tensor about the origin of a uniform box (parallel-axis theorem)."""
    a, b, c = sides
    local = mass / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    r = np.asarray(centre, float)
    return local + mass * (r @ r * np.eye(3) - np.outer(r, r))


def t_handle_by_parts(l1, l2, w):
    """Independent derivation: cross piece along x, shaft along y, unit mass."""
    total = l1 + l2
    bar = (l1 / total, (l1, w, w), (0.0, 0.0, 0.0))
    shaft = (l2 / total, (w, l2, w), (0.0, 0.5 * w + 0.5 * l2, 0.0))
    com = sum(m * np.array(c) for m, _, c in (bar, shaft))
    tensor = sum(box_inertia(m, s, np.array(c) - com) for m, s, c in (bar, shaft))
    return tensor


class TestTHandle:
    def test_paper_normalised_moments(self):
        # Fig. 3 caption: I = (0.286827, 0.533256, 0.795844)
        body = Body.t_handle(8, 4, 1)
        np.testing.assert_allclose(
            body.normalized_moments, [0.286827, 0.533256, 0.795844], atol=5e-7
        )

    @pytest.mark.parametrize("dims", [(8, 4, 1), (3, 5, 0.5), (1, 1, 0.2), (2, 9, 1.5)])
    def test_eqn_isfort_matches_parallel_axis_theorem(self, dims):
        tensor = t_handle_by_parts(*dims)
        # the T is symmetric about the y axis: the tensor is diagonal
        assert np.max(np.abs(tensor - np.diag(np.diag(tensor)))) < 1e-13 * np.max(tensor)
        body = Body.t_handle(*dims)
        np.testing.assert_allclose(body.moments, np.sort(np.diag(tensor)), rtol=1e-14)

    def test_short_cross_piece_is_relabelled(self):
        # l1 short: the moment about x is no longer the smallest
        body = Body.t_handle(1.0, 6.0, 0.5)
        assert body.moments[0] < body.moments[1] < body.moments[2]
        assert body.permutation != (0, 1, 2)
        assert np.linalg.det(body.frame) == pytest.approx(1.0)

    def test_equivalent_ellipsoid_fig1(self):
        a, b, c = Body.t_handle(8, 4, 1).equivalent_ellipsoid()
        # Fig. 1 caption, and eqn:ellipsoid evaluated at 8, 4, 1
        assert (a, b, c) == pytest.approx((4.23281, 3.07318, 0.645497), abs=5e-6)
        l1, l2, w = 8.0, 4.0, 1.0
        k = math.sqrt(5.0 / 3.0)
        assert a == pytest.approx(
            k * math.sqrt(l2 * w * w + l1**3) / (2 * math.sqrt(l1 + l2)), rel=1e-14
        )
        assert b == pytest.approx(
            k
            * math.sqrt(2 * l1 * l2 * (3 * l2 * w + 2 * l2**2 + 2 * w**2) + l1**2 * w**2 + l2**4)
            / (2 * (l1 + l2)),
            rel=1e-14,
        )
        assert c == pytest.approx(0.5 * k * w, rel=1e-14)

    @pytest.mark.parametrize("bad", [(0, 4, 1), (8, -1, 1), (8, 4, math.nan)])
    def test_rejects_bad_lengths(self, bad):
        with pytest.raises(NonPhysicalBodyError, match="must be a finite positive number"):
            Body.t_handle(*bad)


class TestEllipsoids:
    def test_semi_axes_round_trip(self):
        body = Body.from_semi_axes(3.0, 2.0, 0.5)
        np.testing.assert_allclose(body.equivalent_ellipsoid(), (3.0, 2.0, 0.5), rtol=1e-14)

    @pytest.mark.parametrize(
        "moments",
        [
            (1e308, 1.5e308, 1.7e308),  # the sums overflowed: (inf, inf, inf)
            (1e-310, 1.5e-310, 1.7e-310),  # subnormal moments
            (0.1, 0.2, 0.2999999999),  # I1 + I2 - I3 cancels
            (3e-5, 1.0, 1.00001),  # I1 + I3 - I2 cancels
        ],
    )
    def test_equivalent_ellipsoid_at_any_scale_against_mpmath(self, moments):
        """eqn:ellipsoid on the double moments, in mpmath at 50 digits: each
        semi-axis within 4 ulp, also where the sums overflow or cancel."""
        import mpmath

        body = Body(moments)
        with mpmath.workdps(50):
            i1, i2, i3 = (mpmath.mpf(float(v)) for v in body.moments)
            exact = [mpmath.sqrt(2.5 * s) for s in (i2 + i3 - i1, i1 + i3 - i2, i1 + i2 - i3)]
        for got, want in zip(body.equivalent_ellipsoid(), exact):
            assert math.isfinite(got)
            assert abs(got - float(want)) <= 4 * math.ulp(float(want)), (got, float(want))

    def test_a_flat_body_has_a_zero_thin_axis(self):
        """c is +0.0 exactly on the flat edge (it came out -0.0)."""
        for moments in ((1, 2, 3), (0.3, 0.6, 0.9), (2, 3, 5)):
            c = Body(moments).equivalent_ellipsoid()[2]
            assert c == 0.0 and math.copysign(1.0, c) == 1.0, moments

    def test_equivalent_ellipsoid_scales_exactly(self):
        """Moments 4**k times as large give semi-axes 2**k times as large, bit for bit."""
        base = Body((0.26, 0.55, 0.793662)).equivalent_ellipsoid()
        for k in (-500, -3, 1, 480):
            scaled = Body([math.ldexp(v, 2 * k) for v in (0.26, 0.55, 0.793662)])
            assert scaled.equivalent_ellipsoid() == tuple(math.ldexp(v, k) for v in base)

    def test_semi_axes_in_caller_order(self):
        body = Body.from_semi_axes(0.5, 3.0, 2.0)
        # largest semi-axis (caller's y) carries the smallest moment
        assert body.permutation[0] == 1

    def test_paper_parametrisation_has_unit_norm(self):
        for b, c in [(0.3, 0.1), (0.5, 0.45), (0.2, 0.0), (0.6, 0.05)]:
            body = Body.ellipsoid(b, c)
            assert np.linalg.norm(body.moments) == pytest.approx(1.0, abs=4 * EPS)
            i1, i2, i3 = body.moments
            assert i1 == pytest.approx(b * b + c * c, rel=4 * EPS)
            assert i3 - i2 == pytest.approx(b * b - c * c, abs=8 * EPS)

    def test_paper_parametrisation_third_semi_axis(self):
        b, c = 0.4, 0.25
        body = Body.ellipsoid(b, c)
        root = math.sqrt(2 - 3 * b**4 - 2 * b**2 * c**2 - 3 * c**4)
        a = math.sqrt(root - b * b - c * c) / math.sqrt(2)
        # moments are those of a solid ellipsoid (mass 5) with semi-axes a, b, c
        np.testing.assert_allclose(
            body.moments, sorted([b * b + c * c, a * a + c * c, a * a + b * b]), rtol=1e-14
        )

    def test_flat_ellipsoid_is_a_valid_body(self):
        body = Body.ellipsoid(0.4, 0.0)
        assert body.is_flat
        assert body.equivalent_ellipsoid()[2] < 1e-7

    @pytest.mark.parametrize("b, c", [(0.9, 0.8), (1.0, 0.1)])
    def test_rejects_too_large(self, b, c):
        with pytest.raises(NonPhysicalBodyError):
            Body.ellipsoid(b, c)


class TestInertiaTensor:
    def test_rotated_tensor(self):
        rng = np.random.default_rng(3)
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        moments = np.array([2.0, 3.0, 4.5])
        tensor = q @ np.diag(moments) @ q.T
        body = Body.from_inertia_tensor(tensor)
        np.testing.assert_allclose(body.moments, moments, rtol=1e-13)
        # frame rows are the principal axes: frame T frame^T is diagonal
        np.testing.assert_allclose(
            body.frame @ tensor @ body.frame.T, np.diag(moments), atol=1e-12
        )
        assert np.linalg.det(body.frame) == pytest.approx(1.0)

    def test_frame_is_a_proper_rotation_whatever_eigh_returns(self):
        """eigh's eigenvectors may form a left-handed basis (det -1); the
        frame is made proper (its last row flipped), so that a spin in the
        body's axes is turned, never mirrored.  diag(1, 3, 2): the principal
        axes are x, z and x cross z = -y, so the body spin (0.1, 0.2, 0.3)
        is (0.1, 0.3, -0.2) along them."""
        rng = np.random.default_rng(11)
        tensors = [
            np.diag([1.0, 3.0, 2.0]),
            np.array([[3, 0.3, 0.1], [0.3, 2, 0.2], [0.1, 0.2, 4]]),
        ]
        for _ in range(20):
            q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
            tensors.append(q @ np.diag(rng.uniform(1.0, 2.0, 3)) @ q.T)
        improper = 0
        for tensor in tensors:
            improper += np.linalg.det(np.linalg.eigh(tensor)[1]) < 0
            body = Body.from_inertia_tensor(tensor)
            assert np.linalg.det(body.frame) == pytest.approx(1.0, abs=1e-12)
            np.testing.assert_allclose(
                body.frame @ tensor @ body.frame.T, np.diag(body.moments), atol=1e-12
            )
        assert improper >= 3  # the check has cases to decide
        motion = orbits.Motion.from_omega(
            Body.from_inertia_tensor(np.diag([1.0, 3.0, 2.0])), [0.1, 0.2, 0.3], axes="body"
        )
        np.testing.assert_array_equal(motion.omega0, [0.1, 0.3, -0.2])

    def test_rejects_asymmetric(self):
        with pytest.raises(NonPhysicalBodyError, match="symmetric"):
            Body.from_inertia_tensor([[1, 0.5, 0], [0, 2, 0], [0, 0, 2.5]])

    def test_rejects_non_finite(self):
        with pytest.raises(NonPhysicalBodyError, match="finite"):
            Body.from_inertia_tensor(np.full((3, 3), np.nan))


class TestOrderingAndFrame:
    @pytest.mark.parametrize(
        "given", [(3.0, 1.0, 2.5), (1.0, 2.5, 3.0), (2.5, 3.0, 1.0), (3.0, 2.5, 1.0)]
    )
    def test_sorted_with_permutation(self, given):
        body = Body(given)
        assert list(body.moments) == sorted(given)
        assert [given[i] for i in body.permutation] == list(body.moments)
        frame = body.frame
        assert np.linalg.det(frame) == pytest.approx(1.0)
        # the frame maps the caller's inertia tensor to the sorted one
        np.testing.assert_array_equal(frame @ np.diag(given) @ frame.T, np.diag(body.moments))

    def test_moments_are_read_only(self):
        body = Body((1.0, 2.0, 2.5))
        with pytest.raises(ValueError):
            body.moments[0] = 5.0

    def test_presets(self):
        assert Body.preset("fig6").moments.tolist() == [0.26, 0.55, 0.793662]
        assert Body.preset("t-handle") == Body.t_handle(8, 4, 1)
        with pytest.raises(InputError, match="unknown preset 'nope'"):
            Body.preset("nope")


class TestValidation:
    @pytest.mark.parametrize(
        "moments, message",
        [
            ((1.0, 2.0, math.nan), "not all finite"),
            ((1.0, math.inf, 2.0), "not all finite"),
            ((0.0, 1.0, 1.0), "positive"),
            ((-1.0, 2.0, 2.5), "positive"),
            ((1.0, 1.5, 3.0), "triangle inequality"),
        ],
    )
    def test_non_physical(self, moments, message):
        with pytest.raises(NonPhysicalBodyError, match=message):
            Body(moments)

    @pytest.mark.parametrize("moments", [(1.0, 1.0, 1.5), (1.0, 1.5, 1.5), (2.0, 2.0, 2.0)])
    def test_symmetric_top_explains_why(self, moments):
        with pytest.raises(SymmetricTopError, match="symmetric top.*I1 < I2 < I3"):
            Body(moments)

    @pytest.mark.parametrize(
        "moments",
        [
            (1.0, 2.9999999999999996, 3.0),
            (1.0, 1.9999999999999998, 2.0),
            (0.5129825523965297, 0.7650661643592273, 0.7650661643592274),
        ],
    )
    def test_moments_an_ulp_apart_that_normalise_to_one_value(self, moments):
        # distinct doubles, but I / |I| (the catalog's columns) rounds two of
        # them to one value: a catalog of the body was refused by its own
        # writer check, a survey listed I2 == I3
        assert len(set(moments)) == 3
        with pytest.raises(SymmetricTopError, match=r"symmetric top within rounding.*\|I\| = 1"):
            Body(moments)

    def test_moments_an_ulp_apart_that_stay_distinct(self):
        # the same kind of body whose normalised moments stay sorted is kept,
        # and its catalog columns are strictly increasing
        body = Body((1.0, 2.0, 2.0000000000000004))
        unit = body.normalized_moments
        assert unit[0] < unit[1] < unit[2]

    def test_flat_equality_allowed(self):
        i1, i2 = 0.3, 0.55
        body = Body((i1, i2, i1 + i2))
        assert body.is_flat

    def test_wrong_shape(self):
        with pytest.raises(NonPhysicalBodyError, match="exactly 3"):
            Body((1.0, 2.0))


class TestArgumentTypes:
    """Every constructor refuses what is not a real number with an OrbitsError
    naming the argument (these raised bare ValueError, TypeError,
    OverflowError or IndexError, or took True for 1, or dropped the
    imaginary part of a complex array)."""

    P = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.3, -1.0, 0.5], [0.0, 0.0, 1.0]]

    @pytest.mark.parametrize(
        "make, named",
        [
            (lambda: Body.from_point_masses("abc", [[0, 0, 1]]), "point masses"),
            (lambda: Body.from_point_masses([1, 1], [[0, 0, 1], [1, 2]]), "positions"),
            (lambda: Body.from_point_masses([1 + 1j, 1, 1], np.eye(3)), "point masses"),
            (lambda: Body.from_point_masses(np.ones(3, complex), np.eye(3)), "point masses"),
            (lambda: Body.from_inertia_tensor("abc"), "inertia tensor"),
            (lambda: Body.from_inertia_tensor([[1, 0], [0, 1, 2]]), "inertia tensor"),
            (
                lambda: Body.from_inertia_tensor(
                    np.array([[1, 0.5j, 0], [-0.5j, 2, 0], [0, 0, 2.5]])
                ),
                "inertia tensor",
            ),
            (lambda: Body.t_handle("8", 4, 1), "l1"),
            (lambda: Body.t_handle(None, 4, 1), "l1"),
            (lambda: Body.t_handle(np.array([8.0, 9.0]), 4, 1), "l1"),
            (lambda: Body.t_handle(True, 4, 1), "l1"),
            (lambda: Body.box(10**400, 2, 3), "box edge a"),
            (lambda: Body.box(True, 2, 3), "box edge a"),
            (lambda: Body.box(1, 2, 3, mass=False), "mass"),
            (lambda: Body.ellipsoid("0.5", 0.1), "semi-axis b"),
            (lambda: Body.from_semi_axes(10**400, 1, 2), "semi-axis a"),
            (lambda: Body.cylinder(1, 2, radius_y="x"), "radius_y"),
            (lambda: Body.from_rotational_constants(True, 2, 1.5), "rotational constant A"),
            (lambda: Body.from_rotational_constants(3, 2, 1.5, unit=["MHz"]), "unknown unit"),
            (lambda: Body.preset(["fig6"]), "unknown preset"),
            (lambda: Body.from_inertia_tensor(np.eye(3), defect=np.array(["x"])), "defect"),
        ],
    )
    def test_refused_with_an_orbits_error(self, make, named):
        with pytest.raises(orbits.OrbitsError, match=named):
            make()

    def test_numpy_scalars_and_integers_are_numbers(self):
        assert Body.t_handle(np.float32(8), np.int64(4), 1) == Body.t_handle(8.0, 4.0, 1.0)
        assert Body.box(np.array(3.0), 1, 2) == Body.box(3, 1, 2)


class TestFrameArgument:
    """``frame`` must hold orthonormal rows: a non-rotation used to be stored
    and every vector passed through it (``Motion.from_omega(axes="body")``)
    came out wrong with no error."""

    @pytest.mark.parametrize(
        "frame, message",
        [
            ("abc", "frame must be real numbers"),
            (np.eye(2), r"finite 3x3 matrix .* got shape \(2, 2\)"),
            (np.full((3, 3), np.nan), "non-finite entries"),
            (np.ones((3, 3)), r"not orthonormal .* = 3 >"),
            (np.diag([1.0, 1.0, 1.0 + 1e-6]), "not orthonormal"),
        ],
    )
    def test_refused(self, frame, message):
        with pytest.raises(orbits.OrbitsError, match=message):
            Body((1.0, 2.0, 2.5), frame=frame)

    def test_a_rotation_is_kept_to_rounding(self):
        turn, _ = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))
        body = Body((2.5, 1.0, 2.0), frame=turn)
        # rows reordered with the moments (a proper rotation, det +1)
        assert np.linalg.det(body.frame) == pytest.approx(1.0, abs=1e-14)
        np.testing.assert_allclose(np.abs(body.frame), np.abs(turn[[1, 2, 0]]), atol=0)


# ---------------------------------------------------------------------------
# Symmetric bodies built with rounding noise (issue 20, item 3) and the flat
# limit for computed bodies (issue 21, item 4)
# ---------------------------------------------------------------------------
TURN = np.array(
    [
        [0.36, 0.48, -0.8],
        [-0.8, 0.6, 0.0],
        [0.48, 0.64, 0.6],
    ]
)  # an exact rotation in decimals (rounded in binary)


HALF_ROOT3 = math.sqrt(3.0) / 2.0


def equilateral(shift=(10.0, -4.0, 2.0), height=HALF_ROOT3):
    corners = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, height, 0.0]])
    return corners @ TURN.T + shift


def test_equilateral_point_masses_are_a_symmetric_top():
    """Turned and moved, the triangle's two in-plane moments differ by rounding only."""
    with pytest.raises(SymmetricTopError, match=r"within the rounding of their construction"):
        Body.from_point_masses([2.0, 2.0, 2.0], equilateral())


def test_nearly_equilateral_point_masses_are_accepted():
    """One corner moved by 1e-6: I2 - I1 ~ 1e-6 I3, far above the rounding (~1e-13)."""
    body = Body.from_point_masses([2.0, 2.0, 2.0], equilateral(height=HALF_ROOT3 + 1e-6))
    gap = (body.moments[1] - body.moments[0]) / body.moments[2]
    assert 1e-7 < gap < 1e-5


def rotated(diagonal):
    rotation = TURN @ np.array([[0.6, 0.0, 0.8], [0.0, 1.0, 0.0], [-0.8, 0.0, 0.6]])
    return rotation @ np.diag(diagonal) @ rotation.T


@pytest.mark.parametrize("diagonal", [(1.0, 1.0, 1.5), (1.0, 2.0, 2.0), (3.0, 3.0, 3.0)])
def test_rotated_symmetric_tensor_is_a_symmetric_top(diagonal):
    with pytest.raises(SymmetricTopError, match=r"bound [0-9.e-]+ I3"):
        Body.from_inertia_tensor(rotated(diagonal))


def test_rotated_nearly_symmetric_tensor_is_accepted():
    """I2 - I1 = 1e-10 I3 (rounding bound ~1.4e-14): a genuine asymmetric top."""
    body = Body.from_inertia_tensor(rotated((1.0, 1.0 + 1.5e-10, 1.5)))
    assert body.moments[1] - body.moments[0] == pytest.approx(1.5e-10, rel=1e-3)


def test_moments_given_directly_keep_exact_comparisons():
    body = Body((1.0, 1.0 + 2 * EPS, 1.5))  # 2 ulps apart: accepted as before
    assert body.moments[0] < body.moments[1]
    with pytest.raises(SymmetricTopError):
        Body((1.0, 1.0, 1.5))


def test_tensor_past_the_flat_limit_error_and_flatten():
    """A measured plate 0.1 % past I3 = I1 + I2: refused, or flattened with the excess."""
    tensor = rotated((1.0, 2.0, 3.003))
    with pytest.raises(NonPhysicalBodyError, match=r"defect='flatten'.*--defect flatten"):
        Body.from_inertia_tensor(tensor)
    from orbits import InertialDefectWarning

    with pytest.warns(
        InertialDefectWarning, match=r"excess I3 - I1 - I2 = 0\.003\d* \(0\.1\d*% of I3\)"
    ):
        body = Body.from_inertia_tensor(tensor, defect="flatten")
    assert body.is_flat
    np.testing.assert_allclose(body.moments, (1.0, 2.0, 3.0), rtol=1e-13)
    # the principal axes are kept
    np.testing.assert_allclose(
        body.frame @ tensor @ body.frame.T, np.diag((1.0, 2.0, 3.003)), atol=1e-12
    )


def test_point_masses_take_the_defect_choice():
    masses, points = [1.0, 2.0, 3.0], [[0.0, 0.0, 0.0], [1.0, 0.2, 0.0], [0.3, 1.4, 0.0]]
    body = Body.from_point_masses(masses, points, defect="flatten")  # planar: on the edge already
    assert body == Body.from_point_masses(masses, points)
    with pytest.raises(InputError, match="defect must be"):
        Body.from_point_masses(masses, points, defect="ignore")
    with pytest.raises(InputError, match="defect must be"):
        Body.from_inertia_tensor(np.diag([1.0, 2.0, 2.5]), defect="ignore")


# ---------------------------------------------------------------------------
# Scale: constructors from lengths work at exact powers of two of the
# lengths (no underflow or overflow in the intermediate products), and refuse
# moments that no normal double holds, naming underflow or overflow.
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("k", [-500, -300, 300, 500])
def test_t_handle_is_scale_free(k):
    """Lengths 2**k times: moments exactly 4**k times, unit moments bit-identical."""
    base = Body.t_handle(8.0, 4.0, 1.0)
    scaled = Body.t_handle(*(math.ldexp(v, k) for v in (8.0, 4.0, 1.0)))
    assert np.array_equal(scaled.unit_moments, base.unit_moments)
    assert np.array_equal(scaled.moments, np.ldexp(base.moments, 2 * k))
    assert scaled.critical_angle() == base.critical_angle()


def test_t_handle_at_a_decimal_small_scale_keeps_its_unit_moments():
    """1e-150 (not a power of two): the same unit-norm body to a few ulps."""
    base = Body.t_handle(8.0, 4.0, 1.0)
    small = Body.t_handle(8e-150, 4e-150, 1e-150)
    np.testing.assert_allclose(small.normalized_moments, base.normalized_moments, rtol=4 * EPS)
    np.testing.assert_allclose(small.moments, base.moments * 1e-300, rtol=1e-14)


def _t_handle_exact(l1, l2, w):
    """eqn:IsforT as the paper prints it (expanded), in exact rationals:
    independent of the code's mass-fraction form."""
    from fractions import Fraction

    l1, l2, w = (Fraction(v) for v in (l1, l2, w))
    total = l1 + l2
    ix = (
        6 * l1 * l2 * w**2 + 2 * l1**2 * w**2 + l2**2 * w * (6 * l1 + w) + l2**4 + 4 * l1 * l2**3
    ) / (12 * total**2)
    iy = ((l1 + 2 * l2) * w**2 + l1**3) / (12 * total)
    iz = (
        l1 * l2 * (l1**2 + 5 * w**2 + 4 * l2**2)
        + l1**2 * (l1**2 + w**2)
        + l2**2 * w * (6 * l1 + w)
        + l2**4
    ) / (12 * total**2)
    return sorted((ix, iy, iz))


@pytest.mark.parametrize(
    "dims",
    [(1e-150, 1e-150, 1.0), (1e-160, 1e-160, 1.0), (1e-161, 1e-161, 1.0), (1e-300, 1e-300, 1.0),
     (1e-200, 1e-200, 3.0), (1.0, 2.0, 1e-120), (8.0, 4.0, 1.0), (2.0, 9.0, 1.5)],
)  # fmt: skip
def test_t_handle_of_very_unequal_lengths(dims):
    """Bars 1e-160 of the width: the expanded eqn:IsforT over (l1 + l2)**2
    was 8.6% off at 1e-161 (no error), then divided by zero."""
    exact = _t_handle_exact(*dims)
    moments = Body.t_handle(*dims).moments
    assert all(abs(got / float(want) - 1) < 4 * EPS for got, want in zip(moments, exact))


@pytest.mark.filterwarnings("ignore::orbits.InertialDefectWarning")
def test_constructors_take_fractions_and_one_element_arrays():
    """Numbers as box takes them: the labels and the shape were formatted
    from the raw arguments (TypeError: a Fraction has no :g format, a
    1-element array none either)."""
    from fractions import Fraction

    plain = Body.from_rotational_constants(27.877, 14.512, 9.285, defect="flatten")
    given = Body.from_rotational_constants(
        Fraction(27877, 1000), np.array([14.512]), [9.285], defect="flatten"
    )
    assert np.array_equal(given.moments, plain.moments)
    cylinder = Body.cylinder(np.array([0.1]), [0.3], 1.0, radius_y=Fraction(1, 20))
    assert cylinder.shape == ("cylinder", 0.1, 0.3, 0.05)
    assert np.array_equal(cylinder.moments, Body.cylinder(0.1, 0.3, 1.0, radius_y=0.05).moments)


def test_t_handle_underflow_and_overflow_are_named():
    # moments ~5e-401: underflow (it used to be reported as an overflow)
    with pytest.raises(NonPhysicalBodyError, match="underflows below the smallest normal") as e:
        Body.t_handle(1e-200, 2e-200, 3e-201)
    assert "overflow" not in str(e.value)
    with pytest.raises(NonPhysicalBodyError, match=r"I_z = 8\.33e\+398: it overflows") as e:
        Body.t_handle(1e200, 4.0, 1.0)
    assert "underflow" not in str(e.value)
    # normal moments, but the smallest underflows at the scale of the largest
    with pytest.raises(NonPhysicalBodyError, match="intermediate products"):
        Body.t_handle(1e150, 1e-20, 1e-20)


@pytest.mark.parametrize("k", [-500, 500])
def test_semi_axes_are_scale_free(k):
    base = Body.from_semi_axes(3.0, 2.0, 0.5)
    scaled = Body.from_semi_axes(*(math.ldexp(v, k) for v in (3.0, 2.0, 0.5)))
    assert np.array_equal(scaled.unit_moments, base.unit_moments)
    assert np.array_equal(scaled.moments, np.ldexp(base.moments, 2 * k))


def test_semi_axes_beyond_the_doubles_are_refused():
    with pytest.raises(NonPhysicalBodyError, match=r"I_a = 1e-322: it underflows"):
        Body.from_semi_axes(3e-160, 2e-161, 1e-161)
    with pytest.raises(NonPhysicalBodyError, match=r"I_c = 2\.6e\+400: it overflows"):
        Body.from_semi_axes(3e200, 2e200, 1e200)


class TestEllipsoidDomain:
    """``Body.ellipsoid(b, c)`` needs 0 <= c < b < a (docstring and eqn:isforellipsoid)."""

    @pytest.mark.parametrize("b, c", [(0.0, 0.3), (0.3, 0.4)])
    def test_c_larger_than_b_is_refused(self, b, c):
        with pytest.raises(NonPhysicalBodyError, match=r"needs 0 <= c < b < a.*swap b and c"):
            Body.ellipsoid(b, c)

    def test_equal_b_and_c_is_a_symmetric_top(self):
        with pytest.raises(SymmetricTopError, match="b = c = 0.5"):
            Body.ellipsoid(0.5, 0.5)

    def test_a_shorter_than_b_is_refused(self):
        # b = 0.7, c = 0.1: S = 1.1268 < 3 b^2 + c^2 = 1.48, so a = 0.5598 < b
        with pytest.raises(NonPhysicalBodyError, match=r"a = 0\.5598\d* shorter than b"):
            Body.ellipsoid(0.7, 0.1)

    def test_just_inside_is_accepted_with_the_formula(self):
        b, c = 0.6, 0.05  # a = 0.673 > b
        body = Body.ellipsoid(b, c)
        assert body.moments[0] == b * b + c * c
        assert body.equivalent_ellipsoid()[0] > body.equivalent_ellipsoid()[1]

    def test_huge_is_too_large_not_an_overflow(self):
        with pytest.raises(NonPhysicalBodyError, match="too large for a unit-norm"):
            Body.ellipsoid(1e100, 0.0)

    def test_tiny_b_underflows(self):
        with pytest.raises(
            NonPhysicalBodyError, match=r"I1 = b\^2 \+ c\^2 = 1e-340: it underflows"
        ):
            Body.ellipsoid(1e-170, 0.0)


@pytest.mark.parametrize("k", [-1000, 1000])
def test_inertia_tensor_is_scale_free(k):
    tensor = rotated((1.0, 2.0, 2.5))
    base = Body.from_inertia_tensor(tensor)
    scaled = Body.from_inertia_tensor(np.ldexp(tensor, k))
    assert np.array_equal(scaled.unit_moments, base.unit_moments)
    assert np.array_equal(scaled.moments, np.ldexp(base.moments, k))
    assert np.array_equal(scaled.frame, base.frame)


def test_inertia_tensor_with_subnormal_moments_is_refused():
    with pytest.raises(NonPhysicalBodyError, match="underflows below the smallest normal"):
        Body.from_inertia_tensor(np.diag([1.0, 2.0, 2.5]) * 1e-310)


def test_one_or_two_point_masses_are_refused_for_what_they_are():
    with pytest.raises(NonPhysicalBodyError, match="a single point mass: every moment"):
        Body.from_point_masses([1.0], [[1.0, 2.0, 3.0]])
    with pytest.raises(NonPhysicalBodyError, match="2 point masses lie on a line"):
        Body.from_point_masses([1.0, 2.0], [[0.0, 0.0, 0.0], [1.0, 0.5, 0.0]])


def test_name_is_text_or_none():
    """An array as the name was taken, then broke repr() and every catalog."""
    with pytest.raises(orbits.ArgumentTypeError, match="name must be a str or None"):
        Body([1.0, 2.0, 3.0], name=np.array([1, 2]))
    body = Body([1.0, 2.0, 3.0], name=np.str_("x"))
    assert type(body.name) is str and repr(body) == "Body((1, 2, 3), name='x')"
    with pytest.raises(orbits.ArgumentTypeError):
        body.name = 5
