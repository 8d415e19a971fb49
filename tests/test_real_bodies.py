"""Real bodies: box, cylinder, point masses, meshes, rotational constants.

Each constructor is checked against a textbook formula or an independent
computation (numerical volume integration, a second unit system, a mesh).
"""

import math
import warnings

import numpy as np
import pytest
from scipy import constants as codata
from scipy import integrate

import orbits
from orbits import Body
from orbits.bodies import InertialDefectWarning, cylinder_moments
from orbits.errors import InputError, NonPhysicalBodyError, SymmetricTopError


# ---------------------------------------------------------------- box
def test_box_matches_the_textbook_formula():
    # a phone: 146 x 71 x 8 mm, 170 g; I = m (b^2 + c^2)/12 and cyclically
    body = Body.box(0.146, 0.071, 0.008, 0.170)
    m = 0.170
    expected = sorted(
        [
            m * (0.071**2 + 0.008**2) / 12,
            m * (0.146**2 + 0.008**2) / 12,
            m * (0.146**2 + 0.071**2) / 12,
        ]
    )
    np.testing.assert_allclose(body.moments, expected, rtol=1e-15)


def test_box_against_numerical_volume_integral():
    a, b, c, m = 3.0, 2.0, 0.5, 7.0
    density = m / (a * b * c)
    # I_z = rho * int (x^2 + y^2) dV: an independent tplquad
    i_z, _ = integrate.tplquad(
        lambda z, y, x: density * (x * x + y * y),
        -a / 2,
        a / 2,
        -b / 2,
        b / 2,
        -c / 2,
        c / 2,
        epsabs=1e-13,
        epsrel=1e-13,
    )
    assert Body.box(a, b, c, m).moments[2] == pytest.approx(i_z, rel=1e-11)


@pytest.mark.parametrize("args", [(1, 1, 2, 1.0)])
def test_box_with_a_square_section_is_a_symmetric_top(args):
    with pytest.raises(SymmetricTopError):
        Body.box(*args)


@pytest.mark.parametrize(
    "args", [(0, 1, 2, 1), (1, 2, 3, -1), (1, np.nan, 2, 1), (1, 2, math.inf, 1)]
)
def test_box_rejects_bad_lengths_and_masses(args):
    with pytest.raises(NonPhysicalBodyError):
        Body.box(*args)


# ---------------------------------------------------------------- cylinder
def test_circular_cylinder_moments_are_the_textbook_ones():
    r, length, m = 0.02, 0.3, 1.5
    i_x, i_y, i_z = cylinder_moments(r, length, m)
    assert i_x == i_y == pytest.approx(m * (3 * r * r + length**2) / 12, rel=1e-15)
    assert i_z == pytest.approx(m * r * r / 2, rel=1e-15)
    with pytest.raises(SymmetricTopError, match="radius_y"):
        Body.cylinder(r, length, m)


def test_elliptic_cylinder_moments_belong_to_their_axes():
    """radius along x, radius_y along y: I_x = m (b^2/4 + L^2/12) is the
    largest here, so the principal order (I1, I2, I3) is (z, y, x).  The
    sorted moments alone do not tell the axes apart (a cylinder with a and b
    swapped has the same ones); a spin about x must have E = I_x w^2 / 2."""
    a, b, length, m = 0.03, 0.05, 0.2, 1.0
    body = Body.cylinder(a, length, m, radius_y=b)
    i_x = m * (b * b / 4 + length**2 / 12)
    i_y = m * (a * a / 4 + length**2 / 12)
    i_z = m * (a * a + b * b) / 4
    assert body.moments == pytest.approx([i_z, i_y, i_x], rel=1e-15)
    assert body.permutation == (2, 1, 0)
    for axis, moment in enumerate((i_x, i_y, i_z)):
        spin = np.zeros(3)
        spin[axis] = 2.0
        if axis == 1:
            spin[0] = 1e-3  # not exactly along I2 (the separatrix)
            moment_energy = 0.5 * (i_x * 1e-6 + moment * 4.0)
        else:
            moment_energy = 0.5 * moment * 4.0
        motion = orbits.Motion.from_omega(body, spin, axes="body")
        assert motion.energy == pytest.approx(moment_energy, rel=1e-14)


def test_elliptic_cylinder_against_numerical_integration():
    a, b, length, m = 0.5, 0.2, 1.3, 2.0
    density = m / (math.pi * a * b * length)

    def integral(f):
        # over the elliptic section (x = a s cos t, y = b s sin t, jacobian a b s)
        # and the length
        value, _ = integrate.tplquad(
            lambda z, s, t: density * f(a * s * math.cos(t), b * s * math.sin(t), z) * a * b * s,
            0.0,
            2 * math.pi,
            0.0,
            1.0,
            -length / 2,
            length / 2,
            epsabs=1e-13,
            epsrel=1e-12,
        )
        return value

    expected = sorted(
        [
            integral(lambda x, y, z: y * y + z * z),
            integral(lambda x, y, z: x * x + z * z),
            integral(lambda x, y, z: x * x + y * y),
        ]
    )
    np.testing.assert_allclose(
        Body.cylinder(a, length, m, radius_y=b).moments, expected, rtol=1e-10
    )


# ---------------------------------------------------------------- point masses
def test_point_masses_on_a_rectangle():
    # four masses m at (+-a/2, +-b/2, 0): I_x = m b^2, I_y = m a^2, I_z = m (a^2+b^2)
    a, b, m = 3.0, 1.0, 0.25
    corners = np.array([[sx * a / 2, sy * b / 2, 0.0] for sx in (-1, 1) for sy in (-1, 1)])
    body = Body.from_point_masses([m] * 4, corners + [10.0, -4.0, 2.0])
    np.testing.assert_allclose(
        body.moments, [m * b * b, m * a * a, m * (a * a + b * b)], rtol=1e-13
    )
    assert body.is_flat


def test_point_masses_are_taken_about_the_centre_of_mass_in_any_frame():
    rng = np.random.default_rng(11)
    masses = rng.uniform(0.5, 2.0, 7)
    points = rng.normal(size=(7, 3))
    body = Body.from_point_masses(masses, points)
    # an independent route: parallel-axis theorem from the origin
    tensor_origin = sum(m * (p @ p * np.eye(3) - np.outer(p, p)) for m, p in zip(masses, points))
    centre = masses @ points / masses.sum()
    tensor_cm = tensor_origin - masses.sum() * (
        centre @ centre * np.eye(3) - np.outer(centre, centre)
    )
    np.testing.assert_allclose(body.moments, np.linalg.eigvalsh(tensor_cm), rtol=1e-12)
    # moved and turned rigidly: same moments
    turn, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    moved = Body.from_point_masses(masses, points @ turn.T + [5.0, 6.0, -7.0])
    np.testing.assert_allclose(moved.moments, body.moments, rtol=1e-12)
    # the frame maps the caller's axes to the principal axes
    rotated = body.frame @ tensor_cm @ body.frame.T
    np.testing.assert_allclose(rotated, np.diag(body.moments), atol=1e-12 * body.moments[2])


@pytest.mark.parametrize("offset", [1e3, 1e7, 1e10])
def test_point_masses_far_from_the_origin(offset):
    """Far from the coordinates' origin (a spacecraft in Earth-centred
    metres, 7e6): the centre of mass is off by ~n eps |x|, one shift of every
    relative position, so the rounding grows like the offset, not its square.
    1e7 was refused as a symmetric top (bound 2.4 I3) with moments good to 4e-10.
    """
    masses = [1.0, 2.0, 3.0, 1.0]
    points = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.3, -1.0, 0.5], [0.0, 0.0, 1.0]])
    body = Body.from_point_masses(masses, points + offset)
    np.testing.assert_allclose(
        body.moments, Body.from_point_masses(masses, points).moments, rtol=40 * offset * 2.2e-16
    )
    # an equilateral triangle there is still a symmetric top
    triangle = np.array([[1.0, 0.0, 0.0], [-0.5, 0.75**0.5, 0.0], [-0.5, -(0.75**0.5), 0.0]])
    with pytest.raises(SymmetricTopError):
        Body.from_point_masses([1.0, 1.0, 1.0], triangle + offset)


@pytest.mark.parametrize(
    "masses, points",
    [
        ([1.0, 1.0], [[0, 0, 0], [1, 0, 0]]),  # collinear
        ([1.0, -1.0, 1.0], [[0, 0, 0], [1, 0, 0], [0, 1, 0]]),  # negative mass
        ([1.0, 1.0], [[0, 0, 0]]),  # shapes
        ([1.0, np.nan, 1.0], [[0, 0, 0], [1, 0, 0], [0, 1, 0]]),
    ],
)
def test_point_masses_rejected(masses, points):
    with pytest.raises(NonPhysicalBodyError):
        Body.from_point_masses(masses, points)


# ---------------------------------------------------------------- scale
# The constructors scale lengths and masses by exact powers of two before
# forming products: a body does not depend on its units, and moments that no
# normal double holds (below 2.2e-308 or above 1.8e308) are refused, naming
# underflow or overflow (issue: --box 1e-160 ... gave I1 = 0.231862 for 0.231963).
BOX = (1.0, 2.0, 3.5)


@pytest.mark.parametrize("k, mass_k", [(-530, 60), (-500, 0), (500, 0), (-200, -300)])
def test_box_is_scale_free(k, mass_k):
    """Edges 2**k, mass 2**mass_k: moments exactly 2**(2k + mass_k) times, same unit moments."""
    base = Body.box(*BOX)
    scaled = Body.box(*(math.ldexp(v, k) for v in BOX), math.ldexp(1.0, mass_k))
    assert np.array_equal(scaled.unit_moments, base.unit_moments)
    assert np.array_equal(scaled.moments, np.ldexp(base.moments, 2 * k + mass_k))
    assert scaled.critical_angle() == base.critical_angle()


def test_box_at_a_decimal_small_scale():
    """1e-160 edges (moments 1e-320 would be subnormal) with mass 1e30: moments 1e-290."""
    base = Body.box(*BOX)
    small = Body.box(*(1e-160 * v for v in BOX), 1e30)
    np.testing.assert_allclose(small.normalized_moments, base.normalized_moments, rtol=1e-15)
    np.testing.assert_allclose(small.moments, base.moments * 1e-290, rtol=1e-14)
    assert small.critical_angle() == pytest.approx(base.critical_angle(), rel=1e-14)


def test_box_moments_beyond_the_doubles_are_refused():
    with pytest.raises(NonPhysicalBodyError, match=r"I_z = 4\.17e-321: it underflows") as e:
        Body.box(*(1e-160 * v for v in BOX))
    assert "overflow" not in str(e.value)
    with pytest.raises(NonPhysicalBodyError, match=r"I_x = 1\.08e\+400: it overflows") as e:
        Body.box(1e200, 2e200, 3e200)
    assert "underflow" not in str(e.value)
    with pytest.raises(NonPhysicalBodyError, match="it overflows"):
        Body.box(2.0, 4.0, 6.0, 1e308)  # I_x = 4.33e308


def test_subnormal_mass_is_refused():
    """A mass below 2.2e-308 keeps fewer than 53 bits: every moment would be off."""
    with pytest.raises(NonPhysicalBodyError, match="mass 1e-320 is below the smallest normal"):
        Body.cylinder(1.0, 2.0, 1e-320, radius_y=1.5)
    with pytest.raises(NonPhysicalBodyError, match="mass 1e-310 is below the smallest normal"):
        Body.box(1.0, 2.0, 3.0, 1e-310)


def test_cylinder_is_scale_free():
    base = Body.cylinder(1.0, 2.0, radius_y=1.5)
    scaled = Body.cylinder(2.0**-520, 2.0**-519, 2.0**100, radius_y=1.5 * 2.0**-520)
    assert np.array_equal(scaled.unit_moments, base.unit_moments)
    assert np.array_equal(scaled.moments, np.ldexp(base.moments, -940))
    # 1e-300 kg: moments 1e-300 times, same phases (I1 0.434435 before and after)
    light = Body.cylinder(1.0, 2.0, 1e-300, radius_y=1.5)
    np.testing.assert_allclose(light.moments, base.moments * 1e-300, rtol=1e-15)
    assert light.normalized_moments[0] == pytest.approx(0.434435, abs=5e-7)
    with pytest.raises(NonPhysicalBodyError, match="it underflows"):
        Body.cylinder(1e-10, 2e-10, 1e-300, radius_y=1.5e-10)
    with pytest.raises(NonPhysicalBodyError, match=r"I_z = 2\.5e\+399: it overflows"):
        cylinder_moments(1e200, 1.0, radius_y=1.0)


POINT_MASSES = ([1.0, 2.0, 3.0], np.array([[0.0, 0.0, 0.0], [1.0, 0.2, 0.0], [0.3, 1.4, 0.5]]))


@pytest.mark.parametrize("k, mass_k", [(-500, 0), (500, 0), (-530, 100), (200, -300)])
def test_point_masses_are_scale_free(k, mass_k):
    masses, points = POINT_MASSES
    base = Body.from_point_masses(masses, points)
    scaled = Body.from_point_masses(np.ldexp(masses, mass_k), np.ldexp(points, k))
    assert np.array_equal(scaled.unit_moments, base.unit_moments)
    assert np.array_equal(scaled.moments, np.ldexp(base.moments, 2 * k + mass_k))
    assert np.array_equal(scaled.frame, base.frame)


def test_point_masses_at_1e200_overflow_clearly():
    """Positions ~1e200: the tensor ~1e400 (LinAlgError from eigvalsh before)."""
    masses, points = POINT_MASSES
    with pytest.raises(NonPhysicalBodyError, match=r"I3 = 3\.68e\+400: it overflows"):
        Body.from_point_masses(masses, points * 1e200)
    with pytest.raises(NonPhysicalBodyError, match=r"I1 = 6\.88e-321: it underflows"):
        Body.from_point_masses(masses, points * 1e-160)
    # the same positions with heavy masses: moments ~1e-170, the same body
    base = Body.from_point_masses(masses, points)
    heavy = Body.from_point_masses(np.array(masses) * 1e150, points * 1e-160)
    np.testing.assert_allclose(heavy.moments, base.moments * 1e-170, rtol=1e-14)
    np.testing.assert_allclose(heavy.normalized_moments, base.normalized_moments, rtol=1e-14)


def test_point_masses_degenerate_scales_are_refused():
    masses, points = POINT_MASSES
    with pytest.raises(NonPhysicalBodyError, match="point mass #1 .* below the smallest normal"):
        Body.from_point_masses([1.0, 1e-320, 1.0], points)
    with pytest.raises(NonPhysicalBodyError, match="all lie at one point"):
        Body.from_point_masses(masses, np.zeros((3, 3)))
    with pytest.raises(NonPhysicalBodyError, match="coordinate .* below the smallest normal"):
        Body.from_point_masses(masses, points * 1e-310)
    # masses 1e300 apart: the moment underflows at the scale of the heaviest
    with pytest.raises(NonPhysicalBodyError, match="intermediate products"):
        Body.from_point_masses([1.0, 1e-300, 1e-300], points)


@pytest.mark.parametrize("k", [-800, 800])
def test_rotational_constants_are_scale_free(k):
    """Constants 2**k times give moments exactly 2**-k times (I = h / (8 pi^2 B))."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InertialDefectWarning)
        base = Body.from_rotational_constants(*FORMALDEHYDE_MHZ, unit="MHz", defect="flatten")
        scaled = Body.from_rotational_constants(
            *(math.ldexp(v, k) for v in FORMALDEHYDE_MHZ), unit="MHz", defect="flatten"
        )
    assert np.array_equal(scaled.moments, np.ldexp(base.moments, -k))


def test_rotational_constants_beyond_the_doubles_are_refused():
    with pytest.raises(NonPhysicalBodyError, match=r"I_A = 9\.33e-312 kg m\^2: it underflows"):
        Body.from_rotational_constants(1e265, 2e265, 3e265)
    with pytest.raises(NonPhysicalBodyError, match="constant C 1e-320 is below the smallest"):
        Body.from_rotational_constants(3.0, 2.0, 1e-320)


# ---------------------------------------------------------------- mesh
trimesh = pytest.importorskip("trimesh", reason="the optional extra orbits[mesh]")


def test_box_mesh_matches_body_box(tmp_path):
    a, b, c, density = 0.4, 0.25, 0.1, 2700.0
    mesh = trimesh.creation.box(extents=(a, b, c))
    # turned and moved: the constructor works about the centre of mass
    mesh.apply_transform(
        trimesh.transformations.random_rotation_matrix(np.random.default_rng(3).uniform(size=3))
    )
    mesh.apply_translation([1.0, 2.0, 3.0])
    path = tmp_path / "box.stl"
    mesh.export(path)
    body = Body.from_mesh(path, density=density)
    # STL stores float32 vertices: the reference is good to ~1e-7
    np.testing.assert_allclose(
        body.moments, Body.box(a, b, c, density * a * b * c).moments, rtol=2e-6
    )


def test_ellipsoid_mesh_converges_to_body_from_semi_axes(tmp_path):
    a, b, c, density = 3.0, 2.0, 1.0, 1.0
    errors = []
    for subdivisions in (3, 5):
        mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
        mesh.apply_scale((a, b, c))
        path = tmp_path / f"ellipsoid{subdivisions}.obj"
        mesh.export(path)
        body = Body.from_mesh(path, density=density)
        exact = Body.from_semi_axes(a, b, c).moments * (4.0 / 3.0 * math.pi * a * b * c)
        errors.append(np.max(np.abs(body.moments / exact - 1.0)))
    # the inscribed polyhedron converges like h^2: 4^2 = 16 fold per 2 subdivisions
    assert errors[1] < 2e-3
    assert errors[0] / errors[1] > 10.0


def test_open_mesh_is_refused(tmp_path):
    mesh = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    mesh.update_faces(np.arange(len(mesh.faces) - 1))
    path = tmp_path / "open.stl"
    mesh.export(path)
    with pytest.raises(InputError, match="not closed"):
        Body.from_mesh(path, density=1.0)


def test_missing_mesh_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError):
        Body.from_mesh(tmp_path / "nothing.stl")


# ---------------------------------------------------------------- molecules
# Ground-state rotational constants, MHz.
# H2O: De Lucia, Helminger, Cook & Gordy, Phys. Rev. A 6, 1324 (1972):
#   A0 = 835840.3, B0 = 435351.7, C0 = 278138.7
WATER_MHZ = (835840.3, 435351.7, 278138.7)
# H2CO: Johns & McKellar, J. Mol. Spectrosc. 48, 354 (1973) / CDMS entry 030501:
#   A0 = 281970.5, B0 = 38833.99, C0 = 34004.24
FORMALDEHYDE_MHZ = (281970.5, 38833.99, 34004.24)
# Gordy & Cook, Microwave Molecular Spectra (1984), eq. 2.8:
#   I [u A^2] = 505379.0 / B [MHz]
GORDY_COOK = 505379.0
AMU_A2 = codata.physical_constants["atomic mass constant"][0] * 1e-20


@pytest.mark.parametrize("constants", [WATER_MHZ, FORMALDEHYDE_MHZ])
def test_rotational_constants_textbook_conversion(constants):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InertialDefectWarning)
        body = Body.from_rotational_constants(*constants, unit="MHz", defect="flatten")
    i_a, i_b = body.moments[:2] / AMU_A2
    # the textbook factor is given to 7 digits
    assert i_a == pytest.approx(GORDY_COOK / constants[0], rel=2e-7)
    assert i_b == pytest.approx(GORDY_COOK / constants[1], rel=2e-7)
    assert body.is_flat


def test_units_agree():
    ghz = [v / 1e3 for v in FORMALDEHYDE_MHZ]
    cm = [v * 1e6 / (100.0 * codata.c) for v in FORMALDEHYDE_MHZ]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InertialDefectWarning)
        bodies = [
            Body.from_rotational_constants(*values, unit=unit, defect="flatten")
            for values, unit in ((FORMALDEHYDE_MHZ, "MHz"), (ghz, "GHz"), (cm, "cm-1"))
        ]
    for body in bodies[1:]:
        np.testing.assert_allclose(body.moments, bodies[0].moments, rtol=1e-14)


def test_rotational_constants_axes_are_a_b_c_whatever_the_order():
    """The body's own axes are a, b, c of A >= B >= C however the constants
    are typed (documented for --omega): the frame is the identity, and a
    spin along the first axis is one about a (the smallest moment)."""
    typed = Body.from_rotational_constants(0.5, 1.5, 0.4)
    sorted_ = Body.from_rotational_constants(1.5, 0.5, 0.4)
    np.testing.assert_array_equal(typed.moments, sorted_.moments)
    np.testing.assert_array_equal(typed.frame, np.eye(3))
    h_over = codata.h / (8.0 * np.pi**2 * 100.0 * codata.c)
    assert typed.moments[0] == pytest.approx(h_over / 1.5, rel=1e-15)


def test_water_defect_is_an_error_that_names_the_option():
    with pytest.raises(NonPhysicalBodyError) as caught:
        Body.from_rotational_constants(*WATER_MHZ, unit="MHz")
    message = str(caught.value)
    i_a, i_b, i_c = (GORDY_COOK / v for v in WATER_MHZ)
    defect = i_c - i_a - i_b  # 0.0515 u A^2, 2.8 % of I_C
    import re

    stated = float(re.search(r"Delta = I_C - I_A - I_B = ([0-9.]+) u A\^2", message).group(1))
    assert stated == pytest.approx(defect, rel=1e-5)
    assert "defect='flatten'" in message and "2.83" in message


def test_water_flatten_warns_with_the_defect():
    with pytest.warns(InertialDefectWarning, match=r"0\.0515"):
        body = Body.from_rotational_constants(*WATER_MHZ, unit="MHz", defect="flatten")
    assert body.is_flat
    assert body.moments[2] == body.moments[0] + body.moments[1]


def test_rotational_constants_bad_input():
    with pytest.raises(InputError, match="unknown unit"):
        Body.from_rotational_constants(1.0, 2.0, 3.0, unit="Hz")
    with pytest.raises(NonPhysicalBodyError):
        Body.from_rotational_constants(1.0, -2.0, 3.0)
    with pytest.raises(InputError, match="defect must be"):
        Body.from_rotational_constants(3.0, 2.0, 1.5, defect="ignore")


def test_non_planar_molecule_needs_no_flattening():
    # an asymmetric box-shaped "molecule": constants of Body.box moments
    body = Body.box(3.0, 2.0, 1.0, 1e-25)
    hertz = codata.h / (8 * math.pi**2 * body.moments)
    again = Body.from_rotational_constants(*hertz / 1e9, unit="GHz")
    np.testing.assert_allclose(again.moments, body.moments, rtol=1e-14)


@pytest.mark.parametrize("suffix", ["stl", "obj", "ply", "off"])
def test_sphere_mesh_is_a_symmetric_top(tmp_path, suffix):
    """An icosphere has an isotropic inertia tensor; each file format rounds it.

    (Before, the STL sphere was accepted with moments equal to 2e-16 and a
    total phase of 3.8e16.)  The rounding bound takes the vertex precision
    the file keeps (float32 in STL and this PLY, 8 decimals in OBJ).
    """
    mesh = trimesh.creation.icosphere(subdivisions=3)
    mesh.apply_translation([0.3, -0.2, 0.1])
    path = tmp_path / f"sphere.{suffix}"
    mesh.export(path)
    with pytest.raises(SymmetricTopError, match="within the rounding of their construction"):
        Body.from_mesh(path)


def test_cube_mesh_is_a_symmetric_top(tmp_path):
    mesh = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    mesh.apply_transform(
        trimesh.transformations.random_rotation_matrix(np.random.default_rng(4).uniform(size=3))
    )
    path = tmp_path / "cube.stl"
    mesh.export(path)
    with pytest.raises(SymmetricTopError):
        Body.from_mesh(path)


def test_nearly_cubic_mesh_is_accepted(tmp_path):
    """Edges 1 : 1.001 : 0.999 -- moments 1e-3 apart, far above the float32 bound (~2e-6)."""
    mesh = trimesh.creation.box(extents=(1.0, 1.001, 0.999))
    path = tmp_path / "brick.stl"
    mesh.export(path)
    body = Body.from_mesh(path)
    np.testing.assert_allclose(
        body.moments, Body.box(1.0, 1.001, 0.999, 1.0 * 1.001 * 0.999).moments, rtol=1e-6
    )


def test_text_mesh_keeps_the_decimals_it_writes(tmp_path):
    """A box 0.3 x 0.1 x 0.2 m exported by trimesh (OBJ, ``%.8f``: 0.15000000)
    was refused as a symmetric top: the vertex rounding was guessed from the
    values (2 decimals, 0.005 m), not from the 8 decimals in the file.  The
    same file with the coordinates shortened to 0.15 is ambiguous (a writer
    of 2 digits, or of shortest forms as trimesh's STL export) and stays
    refused, with a note that the file's digits set the bound and how to
    write more (a 6-digit floor let a cube written with 2 decimals through
    as an asymmetric top; a review).
    """
    mesh = trimesh.creation.box(extents=(0.3, 0.1, 0.2))
    path = tmp_path / "box.obj"
    mesh.export(path)
    assert "0.15000000" in path.read_text()
    body = Body.from_mesh(path)
    np.testing.assert_allclose(
        body.moments, Body.box(0.3, 0.1, 0.2, 0.3 * 0.1 * 0.2).moments, rtol=1e-12
    )
    short = tmp_path / "short.obj"
    text = path.read_text()
    for long, brief in (("0.15000000", "0.15"), ("0.05000000", "0.05"), ("0.10000000", "0.1")):
        text = text.replace(long, brief)
    short.write_text(text)
    with pytest.raises(SymmetricTopError, match="set by the digits the file writes"):
        Body.from_mesh(short)


def test_vertex_rounding_reads_the_written_decimals():
    from orbits.bodies import vertex_rounding

    values = np.array([0.15, -0.05, 0.1])
    # a padded writer: fixed decimals, trailing zeros included
    assert vertex_rounding(values, b"v 0.15000000 -0.05000000 0.10000000\n") == 5e-9
    assert vertex_rounding(values, b"v 1.500e-01 -5.000e-02 1.000e-01\n") == 0.5e-4
    # a stripping writer (%g, repr): at least the most significant digits seen
    assert vertex_rounding(values, b"v 0.15 -0.05 0.1\n") == pytest.approx(0.5e-1 * 0.15)
    long = np.array([0.0980171403295606, 0.15])
    assert vertex_rounding(long, b"v 0.0980171403295606 0.15 0\n") == pytest.approx(0.5e-15 * 0.15)
    # %.17g writes 0 and 1 bare: they count (they were skipped, and the
    # rounding fell back to the fewest decimals reproducing the values, 0.05)
    tet = np.array([0.0, 1.0, 0.10000000000000001, 0.7, 0.05, 0.2])
    text = b"v 0 1 0.10000000000000001\nv 0.69999999999999996 0.050000000000000003 0.2\n"
    assert vertex_rounding(tet, text) == pytest.approx(0.5e-16 * 1.0)
    # a value not written in the text: the values alone decide
    assert vertex_rounding(values, b"v 0.15 -0.05 1\n") == vertex_rounding(values)
    # a binary file
    assert vertex_rounding(values, b"\x00\x01binary") == vertex_rounding(values)


def test_thin_plate_mesh_rounding_bound_covers_vertex_moves():
    """The vertex-rounding bound is 2 rho delta (surface integral of r^2): a
    thin plate's moments move far more than the M R delta once assumed.
    Measured: random +-delta vertex moves of a 1 x 0.8 x 0.01 plate move a
    moment by up to 16 delta (M = 1), above the old bound 8 M R delta = 5.1
    delta; the surface bound is 57 delta."""
    from orbits.bodies import _surface_r2

    plate = trimesh.creation.box(extents=(1.0, 0.8, 0.01))
    plate.density = 1.0 / plate.volume
    bound = plate.density * _surface_r2(plate.triangles - plate.center_mass, plate.area_faces)
    # exact for a box: 2 [bc (a^2/4 + (b^2 + c^2)/12) + cyclic]
    a, b, c = 1.0, 0.8, 0.01
    exact = 2 * (
        b * c * (a * a / 4 + (b * b + c * c) / 12)
        + a * c * (b * b / 4 + (a * a + c * c) / 12)
        + a * b * (c * c / 4 + (a * a + b * b) / 12)
    )
    assert bound == pytest.approx(plate.density * exact, rel=1e-12)
    rng = np.random.default_rng(0)
    delta, worst = 1e-6, 0.0
    base = np.linalg.eigvalsh(plate.moment_inertia)
    for _ in range(20):
        moved = trimesh.Trimesh(
            plate.vertices + rng.choice([-delta, delta], size=plate.vertices.shape),
            plate.faces,
            process=False,
        )
        moved.density = plate.density
        worst = max(worst, np.max(np.abs(np.linalg.eigvalsh(moved.moment_inertia) - base)))
    assert 8.0 * 0.64 * delta < worst <= bound * delta


def write_obj(path, vertices, faces):
    """An OBJ file with every coordinate to 17 significant digits (``%.16e``:
    the double itself, written with fixed decimals, so the file says so)."""
    lines = [f"v {x:.16e} {y:.16e} {z:.16e}" for x, y, z in vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces.tolist()]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("k", [-200, 200])
def test_mesh_is_scale_free(tmp_path, k):
    """Vertices 2**k times, density 2**-3k: moments 4**k times, the same unit moments.

    At 2**-200 the file's vertices used to be merged by trimesh's absolute
    tolerance (1e-8) into one point; beyond that the integrals (degree 5 in
    the lengths) under- or overflowed.
    """
    mesh = trimesh.creation.box(extents=(0.4, 0.25, 0.1))
    mesh.apply_translation([1.0, 2.0, 3.0])
    write_obj(tmp_path / "box.obj", mesh.vertices, mesh.faces)
    write_obj(tmp_path / "scaled.obj", np.ldexp(mesh.vertices, k), mesh.faces)
    base = Body.from_mesh(tmp_path / "box.obj", density=2700.0)
    body = Body.from_mesh(tmp_path / "scaled.obj", density=2700.0 * 2.0 ** (-3 * k))
    assert np.array_equal(body.unit_moments, base.unit_moments)
    assert np.array_equal(body.moments, np.ldexp(base.moments, 2 * k))
    expected = Body.box(0.4, 0.25, 0.1, 2700.0 * 0.4 * 0.25 * 0.1).moments
    # trimesh integrates about the origin and moves to the centre of mass
    # (3.7 away for a 0.4 box): 1.5e-12 measured
    np.testing.assert_allclose(base.moments, expected, rtol=1e-11)


def _write_obj(path, vertices, faces):
    lines = [f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("shift", [0.0, 1.0, 1e2, 1e4])
def test_mesh_far_from_the_origin(shift, tmp_path):
    """trimesh integrates about the origin and shifts to the centre of mass,
    which cancels far from it: a 0.3 x 0.2 x 0.1 box 10^4 m out came 5 %
    off (2.6e-7 at 100 m) and an off-centre cube passed as an asymmetric top
    (an audit).  The mesh is now moved to its bounding box's centre first."""
    box = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    path = tmp_path / "box.obj"
    _write_obj(path, box.vertices + shift, box.faces)
    body = Body.from_mesh(path, density=1000.0)
    # the box's moments from the stored (rounded) vertices: an ulp of the shift
    tolerance = max(1e-14, 8 * np.spacing(shift) / 0.1)
    np.testing.assert_allclose(body.moments, Body.box(0.3, 0.2, 0.1, 6.0).moments, rtol=tolerance)
    from scipy.spatial.transform import Rotation

    rotation = Rotation.random(random_state=1).as_matrix()
    cube = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    _write_obj(tmp_path / "cube.obj", cube.vertices @ rotation.T + shift, cube.faces)
    with pytest.raises(SymmetricTopError):
        Body.from_mesh(tmp_path / "cube.obj")


def test_mesh_with_overlapping_shells_warns(tmp_path):
    """Two overlapping closed shells: trimesh counts the common volume twice
    (the body had the mass of both; an audit).  A warning says so; separate
    shells and a cavity (an inner shell wound inside out) do not warn."""
    a = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    overlapping = trimesh.util.concatenate([a, a.copy().apply_translation([0.05, 0.05, 0.05])])
    overlapping.export(tmp_path / "overlap.obj")
    with pytest.warns(UserWarning, match="overlapping bounding boxes"):
        Body.from_mesh(tmp_path / "overlap.obj")
    apart = trimesh.util.concatenate([a, a.copy().apply_translation([1.0, 0.4, 0.2])])
    apart.export(tmp_path / "apart.obj")
    inner = trimesh.creation.box(extents=(0.1, 0.05, 0.02))
    inner.invert()
    hollow = trimesh.util.concatenate([a, inner.apply_translation([0.02, 0.01, 0.0])])
    hollow.export(tmp_path / "hollow.obj")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Body.from_mesh(tmp_path / "apart.obj")
        Body.from_mesh(tmp_path / "hollow.obj")


def test_mesh_with_a_part_wound_inside_out_is_refused(tmp_path):
    """A small part beside a box with its faces wound inside out: trimesh
    integrated it as negative mass (I2 9.2 % and I3 7.2 % low, no message;
    an audit), since the mesh's total volume stayed positive.  A shell of
    negative volume outside every solid shell's bounding box is no cavity:
    refused.  The same part wound outward gives the two boxes' moments."""
    big = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    small = trimesh.creation.box(extents=(0.05, 0.04, 0.03))
    small.apply_translation((0.2, 0.0, 0.0))
    vertices = np.vstack([big.vertices, small.vertices])
    offset = len(big.vertices)
    _write_obj(
        tmp_path / "flipped.obj", vertices, np.vstack([big.faces, small.faces[:, ::-1] + offset])
    )
    with pytest.raises(InputError, match="wound inside out .* outside every solid shell"):
        Body.from_mesh(tmp_path / "flipped.obj")
    _write_obj(tmp_path / "parts.obj", vertices, np.vstack([big.faces, small.faces + offset]))
    body = Body.from_mesh(tmp_path / "parts.obj", density=1.0)
    # parallel-axis sum of the two boxes about their common centre of mass
    m_big, m_small = 0.3 * 0.2 * 0.1, 0.05 * 0.04 * 0.03
    x = 0.2 * m_small / (m_big + m_small)  # centre of mass on the x axis
    own = Body.box(0.3, 0.2, 0.1, m_big).moments + Body.box(0.05, 0.04, 0.03, m_small).moments
    shift = np.array([0.0, 1.0, 1.0]) * (m_big * x**2 + m_small * (0.2 - x) ** 2)
    np.testing.assert_allclose(np.sort(body.moments), np.sort(own + shift), rtol=1e-13)


def test_low_precision_cube_is_refused(tmp_path):
    """A rotated cube written with 2 decimals is a symmetric top whose
    moments differ by rounding alone: refused (a 6-digit floor for writers
    that strip zeros let 17 of 20 through as asymmetric; a review)."""
    from scipy.spatial.transform import Rotation

    cube = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    for seed in range(5):
        rotation = Rotation.random(random_state=seed).as_matrix()
        vertices = 7.3 * cube.vertices @ rotation.T
        lines = [" ".join(["v"] + [str(round(float(x), 2)) for x in v]) for v in vertices]
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in cube.faces]
        path = tmp_path / f"cube{seed}.obj"
        path.write_text("\n".join(lines) + "\n")
        with pytest.raises(SymmetricTopError, match="set by the digits the file writes"):
            Body.from_mesh(path)


def test_many_disjoint_shells_are_swept(tmp_path):
    """The overlap check sorts the shells' boxes (it compared every pair:
    5.6 s for 2,000 shells; a review): 2,000 disjoint boxes do not warn,
    and one overlapping pair among them does."""
    box = trimesh.creation.box(extents=(0.5, 0.4, 0.3))
    parts = [
        box.copy().apply_translation([2.0 * (k % 50), 2.0 * (k // 50), 0.0]) for k in range(2000)
    ]
    trimesh.util.concatenate(parts).export(tmp_path / "pile.obj")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Body.from_mesh(tmp_path / "pile.obj")
    parts.append(box.copy().apply_translation([2.0 * 49 + 0.1, 2.0 * 39 + 0.1, 0.1]))
    trimesh.util.concatenate(parts).export(tmp_path / "pile2.obj")
    with pytest.warns(UserWarning, match="2001 closed shells of positive volume"):
        Body.from_mesh(tmp_path / "pile2.obj")
