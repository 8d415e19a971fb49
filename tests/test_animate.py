"""Poinsot animations: the drawn data are the exact motion (no pixels compared)."""

import matplotlib

matplotlib.use("Agg")

import math  # noqa: E402
import os  # noqa: E402
import re  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
from PIL import Image, ImageSequence  # noqa: E402
from scipy.special import ellipk  # noqa: E402

import orbits  # noqa: E402
from orbits import Body, Motion, animate  # noqa: E402
from orbits.cli import main  # noqa: E402
from orbits.errors import ArgumentTypeError, InputError  # noqa: E402

FIG6 = Body.preset("fig6")
T_HANDLE = Body.preset("t-handle")
# rounding in the exact motion ~1e-15; the bounds below leave 100x and more
TIGHT = 1e-12


@pytest.fixture(scope="module")
def orbit_anim():
    row = animate.orbit_row(FIG6, p=7, q=2, branch="SAM")
    return row, animate.poinsot_animation(row, frames=11, dpi=30)


def invariants(motion):
    """E and M from omega0 and the moments directly (not from the Motion's slots)."""
    w, moments = motion.omega0, motion.body.moments
    return 0.5 * w @ (moments * w), np.linalg.norm(moments * w)


def drawn_rotation(anim):
    """The orientation as drawn: the body-axis segments' directions."""
    columns = []
    for line in anim.artists["axes"]:
        x, y, z = (np.asarray(v) for v in line.get_data_3d())
        segment = np.array([x[1] - x[0], y[1] - y[0], z[1] - z[0]])
        columns.append(segment / np.linalg.norm(segment))
    return np.stack(columns, axis=1)


def test_orientation_drawn_is_motion_rotation(orbit_anim):
    row, anim = orbit_anim
    motion = Motion.from_spin(Body((row["I1"], row["I2"], row["I3"])), dtheta=row["dtheta"])
    assert anim.times[-1] == pytest.approx(2 * motion.period, rel=1e-15)
    expected = motion.rotation(anim.times)
    moments = motion.body.moments
    for k in range(len(anim.times)):
        data = anim.frame(k)
        np.testing.assert_allclose(drawn_rotation(anim), expected[k], rtol=0, atol=TIGHT)
        np.testing.assert_array_equal(data.rotation, expected[k])
        # every wire-frame point of the drawn ellipsoid satisfies x.(R I R^T).x = 1
        inertia = expected[k] @ np.diag(moments) @ expected[k].T
        for line in anim.artists["ellipsoid"]:
            points = np.stack([np.asarray(v) for v in line.get_data_3d()], axis=-1)
            np.testing.assert_allclose(
                np.einsum("ni,ij,nj->n", points, inertia, points), 1.0, rtol=TIGHT
            )


def test_closed_orbit_returns_to_its_start(orbit_anim):
    _, anim = orbit_anim
    first, last = anim.frame(0), anim.frame(len(anim.times) - 1)
    # p/q = 7/2 drawn over q = 2 periods: the body is back where it started
    np.testing.assert_allclose(last.rotation, first.rotation, atol=1e-10)
    np.testing.assert_allclose(last.contact, first.contact, atol=1e-10)
    # ... while halfway it is not (the orbit is not 2 pi n)
    middle = anim.frame(len(anim.times) // 2)
    assert np.abs(middle.rotation - first.rotation).max() > 0.1


@pytest.mark.parametrize("scale, speed", [(1.0, 1.0), (1000.0, 3.0)])
def test_ellipsoid_touches_the_plane_at_omega_over_sqrt_2e(scale, speed):
    """Units: I in J s^2, omega in rad/s, x in (J s^2)^(-1/2); the contact point is omega/sqrt(2E)."""
    body = Body(scale * FIG6.moments)
    motion = Motion.from_spin(body, 0.7, phi=0.3, speed=speed)
    anim = animate.poinsot_animation(motion, frames=7, periods=0.8, dpi=30)
    energy, momentum = invariants(motion)
    height = np.sqrt(2 * energy) / momentum
    # the drawn plane is z = sqrt(2E)/M
    np.testing.assert_allclose(anim.artists["plane_edge"].get_data_3d()[2], height, rtol=TIGHT)
    assert anim.plane_height == pytest.approx(height, rel=TIGHT)
    omega_space = motion.omega_space(anim.times)
    moments = body.moments
    for k in range(len(anim.times)):
        data = anim.frame(k)
        x, y, z = (np.asarray(v)[0] for v in anim.artists["contact"].get_data_3d())
        contact = np.array([x, y, z])
        np.testing.assert_allclose(
            contact,
            omega_space[k] / np.sqrt(2 * energy),
            rtol=0,
            atol=TIGHT * np.abs(contact).max(),
        )
        # on the plane, and on the drawn ellipsoid
        assert contact[2] == pytest.approx(height, rel=TIGHT)
        rotation = drawn_rotation(anim)
        inertia = rotation @ np.diag(moments) @ rotation.T
        assert contact @ inertia @ contact == pytest.approx(1.0, rel=1e-11)
        # the ellipsoid's normal there is along L (z): it touches, not cuts
        normal = inertia @ contact
        assert np.hypot(normal[0], normal[1]) <= 1e-11 * abs(normal[2])
        # and its highest point is the plane: support height sqrt(z.I^-1.z)
        inverse = rotation @ np.diag(1.0 / moments) @ rotation.T
        assert np.sqrt(inverse[2, 2]) == pytest.approx(height, rel=1e-11)
        for line in anim.artists["ellipsoid"]:
            assert np.max(line.get_data_3d()[2]) <= height * (1 + 1e-12)
        # the body-frame contact point is on x.I.x = 1 (the polhode)
        assert data.contact_body @ (moments * data.contact_body) == pytest.approx(1.0, rel=TIGHT)


def test_contact_point_lies_on_the_herpolhode(orbit_anim):
    row, anim = orbit_anim
    motion = anim.motion
    energy, _ = invariants(motion)
    for k in (1, 4, 10):
        data = anim.frame(k)
        traced = np.stack(
            [np.asarray(v) for v in anim.artists["herpolhode"].get_data_3d()], axis=-1
        )
        np.testing.assert_array_equal(traced[-1], data.contact)
        np.testing.assert_allclose(traced[:, 2], anim.plane_height, rtol=TIGHT)
        # the traced points are the herpolhode omega_space(t)/sqrt(2E) on [0, t_k]
        times = np.linspace(0.0, anim.times[k], len(traced))
        np.testing.assert_allclose(
            traced, motion.omega_space(times) / np.sqrt(2 * energy), rtol=0, atol=1e-12
        )
        polhode = np.stack([np.asarray(v) for v in anim.artists["polhode"].get_data_3d()], axis=-1)
        np.testing.assert_allclose(
            np.einsum("ni,i,ni->n", polhode, motion.body.moments, polhode), 1.0, rtol=TIGHT
        )


def test_t_handle_solid_has_the_body_moments():
    kind, faces = animate.solid_faces(T_HANDLE)
    assert kind == "t-handle" and len(faces) == 12
    tensor = np.zeros((3, 3))
    mass = 0.0
    for box in range(2):
        corners = np.concatenate(faces[6 * box : 6 * box + 6])
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        volume = np.prod(hi - lo)
        centre = 0.5 * (lo + hi)
        a, b, c = hi - lo
        tensor += volume / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
        tensor += volume * (centre @ centre * np.eye(3) - np.outer(centre, centre))
        mass += volume
    # principal frame: the drawn solid's tensor is diag(I1, I2, I3) of the body
    np.testing.assert_allclose(tensor / mass, np.diag(T_HANDLE.moments), atol=1e-12)
    assert animate.solid_faces(FIG6)[0] == "ellipsoid"
    assert animate.solid_faces(T_HANDLE, "ellipsoid")[0] == "ellipsoid"
    kind, faces = animate.solid_faces(FIG6, ("box", 3.0, 2.0, 1.0))
    extent = np.ptp(np.concatenate(faces), axis=0)
    # the longest side lies along I1 (smallest moment)
    np.testing.assert_allclose(extent, [3.0, 2.0, 1.0], rtol=1e-15)


def _principal_extent(faces):
    return np.ptp(np.concatenate(faces), axis=0)


def test_real_bodies_are_drawn_as_their_solids(tmp_path):
    # a phone-like box: the drawn box has the body's moments (about its centre)
    phone = Body.box(0.071, 0.147, 0.0078, 0.17, name="phone")
    kind, faces = animate.solid_faces(phone)
    assert kind == "box"
    a, b, c = _principal_extent(faces)
    np.testing.assert_allclose(
        0.17 / 12 * np.array([b * b + c * c, a * a + c * c, a * a + b * b]),
        phone.moments,
        rtol=1e-13,
    )
    # an elliptic cylinder (a = 0.3 along x, b = 0.2 along y, length 1 along z):
    # I_z < I_x < I_y, so the length lies along I1, 2a along I2, 2b along I3
    rod = Body.cylinder(0.3, 1.0, 2.0, radius_y=0.2)
    kind, faces = animate.solid_faces(rod)
    assert kind == "cylinder"
    np.testing.assert_allclose(_principal_extent(faces), [1.0, 0.6, 0.4], rtol=1e-13)
    # a closed mesh (a box 3 x 1 x 2): drawn from its own vertices, principal axes
    trimesh = pytest.importorskip("trimesh")
    path = tmp_path / "brick.stl"
    trimesh.creation.box(extents=(3.0, 1.0, 2.0)).export(path)
    brick = Body.from_mesh(path)
    kind, faces = animate.solid_faces(brick)
    assert kind == "mesh"
    np.testing.assert_allclose(_principal_extent(faces), [3.0, 2.0, 1.0], rtol=1e-12)
    # the animation scales every solid to lie inside the inertia ellipsoid x.I.x = 1
    for body in (phone, rod, brick, T_HANDLE):
        anim = animate.poinsot_animation(animate.flip_motion(body), frames=2, dpi=20)
        vertices = np.concatenate(anim.scene.faces)
        assert anim.solid_kind == body.shape[0]
        form = np.einsum("ni,i,ni->n", vertices, body.moments, vertices)
        assert form.max() == pytest.approx(0.95**2, rel=1e-12)


def test_catalog_row_of_a_real_body_keeps_its_solid_and_units(tmp_path, monkeypatch):
    phone = Body.box(0.071, 0.147, 0.0078, 0.17, name="phone")
    row = animate.orbit_row(phone, n=3, branch="SAM")
    anim = animate.poinsot_animation(row, frames=3, dpi=20, body=phone)
    assert anim.solid_kind == "box" and anim.motion.body is phone
    # the same orbit in the body's own units: the phase and closure are scale-free
    np.testing.assert_allclose(anim.motion.total_phase(), 2 * np.pi * 3, rtol=1e-12)
    assert "closed after 1/2 T" in anim._title.get_text()
    with pytest.raises(InputError, match="not of the given body"):
        animate.poinsot_animation(row, frames=3, body=FIG6)
    out = tmp_path / "phone_n3.gif"
    drawn = spy_on_animations(monkeypatch)
    assert (
        main(
            [
                "animate",
                "--box",
                "0.071",
                "0.147",
                "0.0078",
                "--mass",
                "0.17",
                "--n",
                "3",
                "--branch",
                "SAM",
                "--frames",
                "3",
                "--dpi",
                "20",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert out.stat().st_size > 0
    # the command line draws the row with the box's solid and moments (a
    # mutant that dropped the body drew an ellipsoid; an audit)
    (anim,) = drawn
    assert anim.solid_kind == "box"
    np.testing.assert_allclose(anim.motion.body.moments, phone.moments, rtol=1e-12)


def test_flip_turns_the_intermediate_axis_over():
    motion = animate.flip_motion()
    assert motion.body == T_HANDLE
    t = np.linspace(0.0, motion.period, 801)
    axis_along_l = motion.rotation(t)[:, 2, 1]  # z component of the I2 axis
    assert axis_along_l.min() < -0.95 and axis_along_l.max() > 0.95
    with pytest.raises(InputError):
        animate.flip_motion(offset=1.0)


@pytest.mark.parametrize("offset", [0.05, 1e-8, 1e-12, 1e-16, 1e-20, 1e-100, 1e-300])
def test_flip_keeps_the_offset_down_to_1e_300(offset):
    """The period of the flip against mpmath (Eq. 16a with K at enough digits
    for 1 - m ~ offset**2), from the spin the docstring defines: every offset
    its own spin (pi/2 - offset rounded made every offset below 6e-17 the
    same spin, T 18 % short at 1e-20)."""
    import mpmath as mp

    motion = animate.flip_motion(offset=offset)
    with mp.workdps(60 + 2 * int(-math.log10(offset))):
        o = mp.mpf(offset)
        i1, i2, i3 = (mp.mpf(float(v)) for v in motion.body.moments)
        w = (mp.sin(o) * mp.cos(o), mp.cos(o) ** 2, mp.sin(o))
        two_e = i1 * w[0] ** 2 + i2 * w[1] ** 2 + i3 * w[2] ** 2
        m_sq = (i1 * w[0]) ** 2 + (i2 * w[1]) ** 2 + (i3 * w[2]) ** 2
        assert m_sq > two_e * i2  # SAM for the T-handle
        k2 = (i2 - i1) * (two_e * i3 - m_sq) / ((i3 - i2) * (m_sq - two_e * i1))
        rate = mp.sqrt((i3 - i2) * (m_sq - two_e * i1) / (i1 * i2 * i3))
        period = 4 * mp.ellipk(k2) / rate
    assert motion.period == pytest.approx(float(period), rel=1e-14)
    assert np.array_equal(
        motion.omega0,
        [math.sin(offset) * math.cos(offset), math.cos(offset) ** 2, math.sin(offset)],
    )


def test_output_is_deterministic_and_atomic(tmp_path, monkeypatch):
    row = animate.orbit_row(FIG6, n=3, branch="LAM")
    first = animate.poinsot_animation(row, frames=5, dpi=30, out=tmp_path / "a.gif")
    animate.poinsot_animation(row, frames=5, dpi=30, out=tmp_path / "b.gif")
    assert (tmp_path / "a.gif").read_bytes() == (tmp_path / "b.gif").read_bytes()
    with Image.open(tmp_path / "a.gif") as image:
        assert image.n_frames == 5
    # a failure while rendering leaves neither the target nor a temporary file
    calls = []

    def broken(k):
        calls.append(k)
        if k == 3:
            raise RuntimeError("disk full")
        return animate.PoinsotAnimation.render(first, k)

    monkeypatch.setattr(first, "render", broken)
    with pytest.raises(RuntimeError):
        first.save(tmp_path / "c.gif")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif", "b.gif"]


@pytest.mark.skipif(not animate.mp4_available(), reason="imageio-ffmpeg not installed")
def test_mp4(tmp_path):
    motion = Motion.from_spin(FIG6, 0.5)
    for name in ("a.mp4", "b.mp4"):
        animate.poinsot_animation(motion, frames=4, dpi=30, out=tmp_path / name)
    data = (tmp_path / "a.mp4").read_bytes()
    assert data[4:8] == b"ftyp" and data == (tmp_path / "b.mp4").read_bytes()


def test_orbit_row_selection():
    row = animate.orbit_row(FIG6, n=5, branch="SAM")
    assert (row["n"], row["q"], row["branch"], row["closes_after"]) == (5, 1, "SAM", "1/2")
    with pytest.raises(InputError, match="choose one"):
        animate.orbit_row(FIG6, n=5)
    with pytest.raises(InputError, match="lowest terms"):
        animate.orbit_row(FIG6, p=4, q=2, branch="SAM")
    with pytest.raises(InputError, match="exactly one"):
        animate.orbit_row(FIG6)
    with pytest.raises(InputError, match="no closed orbit"):
        animate.orbit_row(FIG6, n=1, branch="SAM")
    table = orbits.closed_orbits(FIG6, n_max=3)
    assert animate.orbit_row(FIG6, n=2, branch="LAM", orbits=table)["dtheta"] > 0


class TestCli:
    @pytest.mark.parametrize(
        "argv",
        [
            ["--preset", "fig6", "--n", "5", "--branch", "SAM"],
            ["--preset", "fig6", "--p", "7", "--q", "2", "--branch", "LAM"],
            ["--preset", "t-handle", "--flip"],
            ["--t-handle", "8", "4", "1", "--theta", "0.3"],
            ["--moments", "2", "3", "4", "--dtheta", "-0.01", "--phi", "0.2"],
        ],
    )
    def test_writes(self, tmp_path, capsys, argv):
        out = tmp_path / "x.gif"
        assert main(["animate", *argv, "--frames", "3", "--dpi", "20", "--out", str(out)]) == 0
        with Image.open(out) as image:
            assert image.n_frames == 3
        assert "written to" in capsys.readouterr().err

    @pytest.mark.parametrize(
        "argv, fragment",
        [
            (["--preset", "fig6", "--out", "a.gif"], "exactly one spin"),
            (["--preset", "fig6", "--n", "2", "--theta", "1", "--out", "a.gif"], "exactly one"),
            (["--preset", "fig6", "--n", "5", "--out", "a.gif"], "--branch"),
            (
                ["--preset", "fig6", "--q", "2", "--theta", "1", "--out", "a.gif"],
                "--q applies to --p",
            ),
            (["--preset", "fig6", "--theta", "0.5", "--out", "a.png"], "use .gif or .mp4"),
            (["--preset", "fig6", "--flip", "2", "--out", "a.gif"], "(0, pi/4)"),
            (
                ["--preset", "fig6", "--theta", "0.5", "--frames", "1", "--out", "a.gif"],
                "--frames: must be an integer >= 2, got 1",
            ),
            (
                # a directory that does not exist (relative: tmp_path is the cwd)
                ["--preset", "fig6", "--theta", "0.5", "--out", "missing/a.gif"],
                "does not exist",
            ),
        ],
    )
    def test_bad_input(self, tmp_path, capsys, monkeypatch, argv, fragment):
        monkeypatch.chdir(tmp_path)
        code = main(["animate", *argv])
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and len(err) == 1 and fragment in err[0], err
        assert list(tmp_path.iterdir()) == []


def test_solids_reach_matplotlib_with_one_vertex_count():
    """A cylinder's 24-gon caps and quadrilateral walls are padded by repeating
    each face's last vertex: matplotlib 3.11 would otherwise pad them with
    uninitialised memory and autoscale on it (matplotlib#32272; a CI run got
    axis limits of 1.8e308).  The padded faces are the same polygons."""
    rod = Body.cylinder(0.3, 1.0, 2.0, radius_y=0.2)
    anim = animate.poinsot_animation(animate.flip_motion(rod), frames=2, dpi=20)
    _, faces = animate.solid_faces(rod)
    assert len({len(face) for face in faces}) > 1  # the input is ragged
    assert {len(face) for face in anim.scene.faces} == {max(len(face) for face in faces)}
    for original, drawn in zip(faces, anim.scene.faces):
        np.testing.assert_array_equal(drawn[: len(original)], original * anim.solid_scale)
        assert (drawn[len(original) :] == drawn[len(original) - 1]).all()


def test_the_drawing_shows_the_scene_geometry(orbit_anim):
    """PoinsotAnimation draws what animation_scene computes: a scene built alone
    (no figure) gives the same frame data bit for bit, and the artists hold it."""
    from orbits.animation_scene import PoinsotScene

    _, anim = orbit_anim
    scene = PoinsotScene(anim.motion, anim.times)
    assert scene.solid_scale == anim.solid_scale and scene.solid_kind == anim.solid_kind
    for k in (0, 3, len(anim.times) - 1):
        drawn, alone = anim.frame(k), scene.frame(k)
        for name in ("rotation", "contact", "contact_body", "herpolhode", "polhode"):
            np.testing.assert_array_equal(getattr(drawn, name), getattr(alone, name))
        assert drawn.t == alone.t == anim.times[k]
        line = np.stack([np.asarray(v) for v in anim.artists["herpolhode"].get_data_3d()], -1)
        np.testing.assert_array_equal(line, alone.herpolhode)
    with pytest.raises(InputError, match="out of range"):
        scene.frame(len(anim.times))


# ----------------------------------------------------------------- checked inputs
def _one_line_refusal(capsys, directory, argv):
    """Run ``orbits animate argv`` in ``directory``: exit 2, one stderr line, nothing written."""
    before = sorted(os.listdir(directory))
    code = main(["animate", *argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err  # no "estimated ... working..." line before it
    assert err[0].startswith("orbits: error: ") and "Traceback" not in err[0]
    assert sorted(os.listdir(directory)) == before
    return err[0]


def test_dpi_below_the_smallest_text_is_refused(tmp_path, capsys, monkeypatch):
    """FreeType cannot set the captions' subscripts ($I_1$, small) at 6 dpi: the
    smallest dpi is 7 at matplotlib's default font size, and 6 is refused up front."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    with matplotlib.rc_context({"font.size": 10.0}):
        assert animate.min_dpi() == 7
        # the bound is FreeType's own: the subscript fails at 6 and draws at 7
        for dpi, draws in ((6, False), (7, True)):
            figure = Figure(figsize=(1, 1), dpi=dpi)
            FigureCanvasAgg(figure)
            figure.text(0.5, 0.5, "$I_1$", fontsize="small")
            if draws:
                figure.canvas.draw()
            else:
                with pytest.raises(RuntimeError, match="FT_Set_Char_Size"):
                    figure.canvas.draw()
        assert animate.poinsot_animation(FIG6, 0.5, frames=2, dpi=7).render(1).shape == (
            28,
            63,
            3,
        )
        for dpi in (6.99, 6, 1, 0.25):
            with pytest.raises(InputError, match=r"^dpi must be a number from 7 to 7281 \("):
                animate.poinsot_animation(FIG6, 0.5, frames=2, dpi=dpi)
        motion = Motion.from_spin(FIG6, 0.5)
        with pytest.raises(InputError, match="dpi must be a number from 7 "):
            animate.PoinsotAnimation(motion, [0.0, 1.0], dpi=5)
        # a title's nested subscripts are smaller still: refused when drawn, not a crash
        anim = animate.PoinsotAnimation(motion, [0.0, 1.0], dpi=7, title="$x_{a_{b}}$")
        with pytest.raises(InputError, match="dpi 7 is too small for a text"):
            anim.render(0)
    # larger fonts draw at a lower dpi
    with matplotlib.rc_context({"font.size": 20.0}):
        assert animate.min_dpi() == 4
    monkeypatch.chdir(tmp_path)
    argv = ["--preset", "fig6", "--theta", "0.5", "--frames", "2", "--out", "a.gif"]
    message = _one_line_refusal(capsys, tmp_path, [*argv, "--dpi", "5"])
    assert "--dpi must be a number from 7 to 7281" in message and message.endswith("got 5")


@pytest.mark.parametrize("fps", [4, 25, 50])
def test_gif_plays_at_its_fps(tmp_path, fps):
    """Every frame's stored delay is 1000/fps ms exactly (whole hundredths)."""
    out = tmp_path / "a.gif"
    animate.poinsot_animation(FIG6, 0.5, frames=3, fps=fps, dpi=10, out=out)
    with Image.open(out) as image:
        durations = [frame.info["duration"] for frame in ImageSequence.Iterator(image)]
    assert durations == [1000 / fps] * 3


def test_gif_refuses_rates_it_cannot_play(tmp_path, capsys, monkeypatch):
    # delays 100/fps cs: whole and >= 2 only for these (1 cs plays as 10 cs)
    assert animate.GIF_FPS == tuple(f for f in range(1, 101) if 100 % f == 0 and 100 // f >= 2)
    # the defaults (library and command line) are one of them
    assert animate.DEFAULT_FPS in animate.GIF_FPS
    from orbits.cli import build_parser

    parsed = build_parser().parse_args(
        ["animate", "--preset", "fig6", "--theta", "1"] + ["--out", "a.gif"]
    )
    assert parsed.fps == animate.DEFAULT_FPS
    motion = Motion.from_spin(FIG6, 0.5)
    for fps in (3, 30, 40, 60, 100):
        with pytest.raises(InputError, match=rf"^fps {fps} cannot play at its speed in a GIF"):
            animate.poinsot_animation(motion, frames=2, dpi=10, fps=fps, out=tmp_path / "a.gif")
        with pytest.raises(InputError, match="or write an .mp4"):
            animate.PoinsotAnimation(motion, [0.0, 1.0], dpi=10, fps=fps).save(tmp_path / "a.gif")
    assert list(tmp_path.iterdir()) == []
    monkeypatch.chdir(tmp_path)
    argv = [
        "--preset",
        "fig6",
        "--theta",
        "0.5",
        "--seconds",
        "3",
        "--fps",
        "40",
        "--out",
        "a.gif",
    ]
    message = _one_line_refusal(capsys, tmp_path, argv)
    assert "--fps 40 cannot play at its speed in a GIF" in message
    assert "1, 2, 4, 5, 10, 20, 25 or 50, or write an .mp4" in message
    if animate.mp4_available():  # an MP4 takes any rate
        out = tmp_path / "a.mp4"
        animate.poinsot_animation(motion, frames=2, dpi=10, fps=40, out=out)
        assert out.read_bytes()[4:8] == b"ftyp"


THROW = ["--preset", "fig6", "--omega"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--theta", "0.5", "--fps", "101"], "--fps must be an integer from 1 to 100, got 101"),
        (["--theta", "0.5", "--periods", "0"], "--periods must be positive, got 0"),
        (["--theta", "0.5", "--periods", "-1"], "--periods must be positive, got -1"),
        (
            ["--theta", "0.5", "--seconds", "200"],
            "--seconds 200 at --fps 20 is 4001 frames (round(seconds x fps) + 1), more than "
            "2000: lower --seconds (at most 99.95) or --fps",
        ),
        (
            # the count beyond 2**62 frames and beyond a double (it said ~4.6e+18)
            ["--theta", "0.5", "--seconds", "1e308"],
            "--seconds 1e+308 at --fps 20 is ~2.0e+309 frames (round(seconds x fps) + 1), "
            "more than 2000: lower --seconds (at most 99.95)",
        ),
        (
            # a mantissa that rounds up to 10 moves to the next power
            ["--theta", "0.5", "--seconds", "4.99e17"],
            "--seconds 4.99e+17 at --fps 20 is ~1.0e+19 frames (round(seconds x fps) + 1), "
            "more than 2000: lower --seconds (at most 99.95)",
        ),
        (
            ["--theta", "0.5", "--seconds", "0.01"],
            "--seconds 0.01 at --fps 20 is 1 frame (round(seconds x fps) + 1), and an "
            "animation needs at least 2: give --seconds of at least 0.05 (one frame at --fps 20)",
        ),
        (
            ["--omega", "1e-3", "0", "1e-3"],
            "--omega plays one period T = 7427.04 s in real time: at --fps 20 that is 148542 "
            "frames, more than 2000: give --seconds of at most 99.95 or --periods of at most "
            "0.01345",
        ),
        (
            ["--omega", "1e4", "1", "1e4"],
            "--omega plays one period T = 0.000742704 s in real time: at --fps 20 that is 1 "
            "frame, and an animation needs at least 2: give --seconds of at least 0.05 or "
            "--periods of at least 67.32",
        ),
        (
            ["--omega", "1", "0", "1", "--periods", "0.005", "--fps", "10"],
            "--omega plays --periods 0.005 of T = 7.42704 s (0.0371352 s) in real time: at "
            "--fps 10 that is 1 frame, and an animation needs at least 2: give --seconds of "
            "at least 0.1 or --periods of at least 0.01346, or a higher --fps",
        ),
        (["--theta", "0.5", "--frames", "0"], "argument --frames: must be an integer >= 2, got 0"),
        (["--theta", "0.5", "--periods", "1e308"], "--periods 1e+308 of T = 7.742 s is beyond"),
        # Motion's range of times (2^50 periods), before the estimate line
        (
            ["--theta", "0.5", "--periods", "1e300"],
            "|t| = 1e+300 periods is beyond the 1.13e+15 periods (2^50)",
        ),
        (
            ["--theta", "0.5", "--periods", "1.2e15"],
            "|t| = 1.2e+15 periods is beyond the 1.13e+15 periods (2^50)",
        ),
        (
            ["--theta", "0.5", "--speed", "1e100", "--seconds", "10"],
            "|t| = 1.29e+100 periods is beyond the 1.13e+15 periods (2^50)",
        ),
        (
            ["--n", "2", "--branch", "SAM", "--periods", "1e300"],
            "|t| = 1e+300 periods is beyond the 1.13e+15 periods (2^50)",
        ),
        # an orbit too near the separatrix for a double: one line, no warning
        (
            ["--n", "1000", "--branch", "SAM", "--frames", "2", "--dpi", "20"],
            "orbits: error: the closed orbit Delta alpha = 2 pi 1000 on SAM lies closer than "
            "|dtheta| = 2.2e-308 to the separatrix and cannot be held in double precision; "
            "the largest n drawable on SAM is 385",
        ),
        (
            ["--p", "775", "--q", "2", "--branch", "LAM", "--frames", "2", "--dpi", "20"],
            "the closed orbit Delta alpha = 2 pi 775/2 on LAM lies closer than "
            "|dtheta| = 2.2e-308 to the separatrix and cannot be held in double precision; "
            "the largest n drawable on LAM is 386",
        ),
        (
            ["--n", "1000", "--frames", "2", "--dpi", "20"],
            "2 pi 1000 on SAM and LAM lies closer than |dtheta| = 2.2e-308 to the separatrix",
        ),
        # none at all (below the branch's smallest phase): the message as before
        (
            ["--n", "1", "--branch", "SAM", "--frames", "2", "--dpi", "20"],
            "orbits: error: the body has no closed orbit Delta alpha = 2 pi 1 on SAM",
        ),
        # a subnormal --dtheta, as orbits phase refuses it
        (
            ["--dtheta", "1e-320", "--frames", "2", "--dpi", "20"],
            "--dtheta 1e-320 is a subnormal double with about 3 significant digits",
        ),
    ],
)
def test_refused_before_the_estimate(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    full = ["--preset", "fig6", *argv, "--out", "a.gif"]
    assert message in _one_line_refusal(capsys, tmp_path, full)


@pytest.mark.parametrize("dtheta", ["1e-320", "-4e-312", "5e-324"])
def test_subnormal_dtheta_refused_as_phase_refuses_it(tmp_path, capsys, monkeypatch, dtheta):
    """The same value, the same one line as ``orbits phase --dtheta``."""
    monkeypatch.chdir(tmp_path)
    assert main(["phase", "--preset", "fig6", "--dtheta", dtheta]) == 2
    phase_error = capsys.readouterr().err.strip()
    argv = [
        "--preset",
        "fig6",
        "--dtheta",
        dtheta,
        "--frames",
        "2",
        "--dpi",
        "20",
        "--out",
        "a.gif",
    ]
    assert _one_line_refusal(capsys, tmp_path, argv) == phase_error
    assert "subnormal" in phase_error


def test_smallest_normal_dtheta_offsets_are_drawn(tmp_path, capsys):
    """Offsets from 4.941e-312 up keep 12 digits: drawn, as phase computes them."""
    out = tmp_path / "a.gif"
    argv = ["animate", "--preset", "fig6", "--dtheta", "1e-311", "--frames", "2", "--dpi", "20"]
    assert main([*argv, "--out", str(out)]) == 0
    with Image.open(out) as image:
        assert image.n_frames == 2


def test_unresolved_orbit_is_one_error_without_the_search_warning():
    """An orbit beyond the phase at |dtheta| = 2.2e-308: refused with the largest
    n drawable, which is itself drawn; the search's warning is not added."""
    import warnings

    from orbits.search import UnresolvedOrbitsWarning

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError) as refused:
            animate.orbit_row(FIG6, n=1000, branch="SAM")
        with pytest.raises(InputError, match="largest n drawable on SAM is 385$"):
            animate.orbit_row(FIG6, n=386, branch="SAM")
        row = animate.orbit_row(FIG6, n=385, branch="SAM")
        # the chosen branch's row found: the orbit left out (SAM's n = 386) is another
        assert animate.orbit_row(FIG6, n=386, branch="LAM")["branch"] == "LAM"
    assert "cannot be held in double precision" in str(refused.value)
    assert str(refused.value).endswith("the largest n drawable on SAM is 385")
    assert (row["n"], row["branch"]) == (385, "SAM") and -1e-300 < row["dtheta"] < 0
    # no branch chosen: the one row found is told with the other branch's left out
    with pytest.warns(UnresolvedOrbitsWarning, match=r"1 closed orbit \(on SAM\) .* 2.2e-308"):
        assert animate.orbit_row(FIG6, n=386)["branch"] == "LAM"


def test_throw_plays_its_periods_in_real_time(tmp_path, capsys):
    """--omega with --periods X: X periods in real time (docs: no --frames with --omega)."""
    usage = next(
        line
        for line in (Path(__file__).resolve().parents[1] / "docs" / "cli.md")
        .read_text()
        .splitlines()
        if line.startswith("orbits animate BODY --omega")
    )
    assert "--periods X]" in usage and "--frames" not in usage
    out = tmp_path / "a.gif"
    argv = ["animate", *THROW, "1", "0", "1", "--periods", "0.5", "--fps", "4", "--dpi", "10"]
    assert main([*argv, "--out", str(out)]) == 0
    period = Motion.from_omega(FIG6, np.array([1.0, 0.0, 1.0]), axes="body").period
    frames = round(0.5 * period * 4) + 1
    with Image.open(out) as image:
        assert image.n_frames == frames and image.info["duration"] == 250
    err = capsys.readouterr().err
    assert (
        f"{frames} frames over {0.5 * period:.4g} s = 0.5 periods at 4 frames/s (real time)" in err
    )
    message = _one_line_refusal(
        capsys, tmp_path, [*THROW, "1", "0", "1", "--frames", "5", "--out", "b.gif"]
    )
    assert "not --frames" in message


def test_mp4_without_ffmpeg_is_refused_first(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # as if not installed
    assert not animate.mp4_available()
    monkeypatch.chdir(tmp_path)
    message = _one_line_refusal(
        capsys, tmp_path, ["--preset", "fig6", "--theta", "0.5", "--out", "a.mp4"]
    )
    assert "MP4 needs an ffmpeg writer" in message
    with pytest.raises(InputError, match="MP4 needs an ffmpeg writer"):
        animate.poinsot_animation(FIG6, 0.5, frames=2, dpi=10, out="a.mp4")


def test_output_path_messages(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("afile").write_text("x")
    os.mkfifo("ff.gif")
    argv = ["--preset", "fig6", "--theta", "0.5", "--frames", "2", "--out"]
    for out in ("afile/a.gif", "afile/deeper/a.gif"):
        message = _one_line_refusal(capsys, tmp_path, [*argv, out])
        assert message.endswith(f"cannot write {out}: afile is not a directory")
    message = _one_line_refusal(capsys, tmp_path, [*argv, "ff.gif"])
    assert "it is a FIFO" in message and "--out -" not in message  # animate has no '-'
    for out in ("a\nb.gif", tmp_path / "a\tb.gif"):
        with pytest.raises(InputError, match="contains the control character"):
            animate.poinsot_animation(FIG6, 0.5, frames=2, dpi=10, out=out)
        with pytest.raises(InputError, match="^path .* contains the control character"):
            animate.PoinsotAnimation(Motion.from_spin(FIG6, 0.5), [0.0, 1.0], dpi=10).save(out)
    assert sorted(os.listdir(tmp_path)) == ["afile", "ff.gif"]


MOTION = Motion.from_spin(FIG6, 0.5)
SQUARE = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]


@pytest.mark.parametrize(
    "call, error, message",
    [
        (lambda: animate.poinsot_animation(FIG6, 0.5, fps=float("nan")), InputError, "^fps must"),
        (lambda: animate.poinsot_animation(FIG6, 0.5, fps=float("inf")), InputError, "^fps must"),
        (lambda: animate.poinsot_animation(FIG6, 0.5, fps=None), InputError, "^fps must"),
        (lambda: animate.poinsot_animation(FIG6, 0.5, frames=float("nan")), InputError, "^frames"),
        (lambda: animate.poinsot_animation(FIG6, 0.5, frames=float("inf")), InputError, "^frames"),
        (lambda: animate.poinsot_animation(FIG6, 0.5, frames="3"), ArgumentTypeError, "^frames"),
        (lambda: animate.poinsot_animation(FIG6, 0.5, periods="1"), ArgumentTypeError, "^periods"),
        (lambda: animate.poinsot_animation(FIG6, 0.5, seconds="1"), ArgumentTypeError, "^seconds"),
        (
            lambda: animate.poinsot_animation(FIG6, 0.5, seconds=0.01),
            InputError,
            "^seconds 0.01 at fps 20 is 1 frame",
        ),
        (
            lambda: animate.orbit_row(FIG6, n=float("nan")),
            InputError,
            "^n must be an integer >= 1",
        ),
        (lambda: animate.orbit_row(FIG6, p=2, q="1"), ArgumentTypeError, "^q must be an integer"),
        (
            lambda: animate.solid_faces(FIG6, ("box", 1)),
            InputError,
            r"^solid \('box', a, b, c\) takes three lengths, got 1",
        ),
        (
            lambda: animate.solid_faces(FIG6, ("box", -1, 2, 3)),
            InputError,
            r"^solid \('box', a, b, c\) needs positive lengths",
        ),
        (
            lambda: animate.solid_faces(FIG6, ("t-handle", 0, 0, 0)),
            InputError,
            "^solid .'t-handle', l1, l2, w. needs positive",
        ),
        (
            lambda: animate.solid_faces(FIG6, ("cylinder", 1, np.nan, 1)),
            InputError,
            "must be finite",
        ),
        (
            lambda: animate.solid_faces(FIG6, ("mesh", SQUARE, [[0, 1, 5]])),
            InputError,
            "face 0 must list at least 3 vertex indices 0..2",
        ),
        (
            lambda: animate.solid_faces(FIG6, ("mesh", SQUARE, [[0, 1]])),
            InputError,
            "face 0 must list",
        ),
        (
            lambda: animate.solid_faces(FIG6, ("mesh", SQUARE[:2], [[0, 1, 1]])),
            InputError,
            r"vertices must be an array \(k, 3\)",
        ),
        (
            lambda: animate.solid_faces(FIG6, ("mesh", SQUARE)),
            InputError,
            "takes vertices and faces",
        ),
        (lambda: animate.solid_faces(FIG6, 5), InputError, "^unknown solid 5"),
        (
            lambda: animate.PoinsotAnimation(MOTION, []),
            InputError,
            r"^times must be a 1-D array of at least 2 frame times, got shape \(0,\)",
        ),
        (
            lambda: animate.PoinsotAnimation(MOTION, [1.0, 0.5], dpi=10),
            InputError,
            r"^times must increase from frame to frame, got times\[0\] = 1 then times\[1\] = 0.5",
        ),
        (
            lambda: animate.PoinsotAnimation(MOTION, [0.0, np.inf], dpi=10),
            InputError,
            "^times must be finite",
        ),
        (
            lambda: animate.PoinsotAnimation(MOTION, [0.0, 1.0], fps=0, dpi=10),
            InputError,
            "^fps must be an integer from 1 to 100, got 0",
        ),
        (
            lambda: animate.PoinsotAnimation(FIG6, [0.0, 1.0], dpi=10),
            ArgumentTypeError,
            "^motion must be an orbits.Motion",
        ),
    ],
)
def test_api_refusals_name_the_argument(call, error, message):
    with pytest.raises(error, match=message):
        call()


def test_few_frames_still_trace_smooth_curves():
    """Two or three frames over a period: the traced polhode and herpolhode
    keep at least 256 steps per period (8 a frame drew a polygon), and the
    frames still sit exactly on the dense grid."""
    from orbits.animation_scene import TRACE_SAMPLES_PER_PERIOD, PoinsotScene

    motion = Motion.from_spin(FIG6, dtheta=-8.332e-3)
    for frames in (2, 3, 48):
        times = np.linspace(0.0, motion.period, frames)
        scene = PoinsotScene(motion, times)
        steps = len(scene.dense_times) - 1
        assert steps >= TRACE_SAMPLES_PER_PERIOD and scene.subsamples >= 8
        assert np.array_equal(scene.dense_times[:: scene.subsamples], scene.times)
        last = scene.frame(frames - 1)
        assert len(last.herpolhode) == steps + 1
        # consecutive traced points at most 1/16 of the herpolhode's size
        # apart (1/18 at 256 steps a period for this 3-lobed SAM curve; 16
        # steps, 3 frames at 8 a frame, were about the size itself)
        gaps = np.linalg.norm(np.diff(last.herpolhode, axis=0), axis=1)
        size = np.ptp(last.herpolhode[:, :2], axis=0).max()
        assert gaps.max() < size / 16


def test_orbit_row_and_animation_take_no_argument_they_would_ignore():
    """orbit_row dropped q with n, took another body's row from a catalog
    (and any body at all), and raised TypeError for a catalog not a frame;
    poinsot_animation ignored theta, dtheta, phi, speed and body with a Motion
    or a catalog row."""
    other = Body((1.0, 2.0, 3.0))
    table = orbits.closed_orbits(FIG6, n_max=4)
    with pytest.raises(InputError, match="for 2 pi p/2 give p and q"):
        animate.orbit_row(FIG6, n=3, q=2, branch="SAM")
    with pytest.raises(InputError, match="no rows of this body"):
        animate.orbit_row(other, n=3, branch="SAM", orbits=table)
    with pytest.raises(InputError, match="orbits must be a catalog DataFrame"):
        animate.orbit_row(FIG6, n=3, orbits="x")
    with pytest.raises(orbits.OrbitsError):
        animate.orbit_row("not a body", n=3, orbits=table)
    both = pd.concat([table, orbits.closed_orbits(other, n_max=4)], ignore_index=True)
    row = animate.orbit_row(FIG6, n=3, branch="SAM", orbits=both)
    assert row.equals(animate.orbit_row(FIG6, n=3, branch="SAM"))
    motion = Motion.from_spin(FIG6, 0.5)
    for extra in ({"theta": 0.3}, {"dtheta": 0.1}, {"phi": 0.2}, {"speed": 2.0}):
        for source in (motion, row):
            with pytest.raises(InputError, match=f"{next(iter(extra))} given with a"):
                animate.animation_motion(source, **extra)
    with pytest.raises(InputError, match="body given with a Motion, whose own body is drawn"):
        animate.animation_motion(motion, body=other)
    assert animate.animation_motion(motion, body=FIG6, phi=0.0, speed=1)[0] is motion


@pytest.mark.parametrize(
    "options, message",
    [
        ({"title": 5}, "title must be a str or None"),
        ({"size": "big"}, r"size must be \(width, height\) in inches"),
        ({"size": (1e9, 1e9)}, "each at most 9362"),
        ({"subsamples": 10**9}, "beyond half of this machine.s memory"),
        ({"pyplot": np.array([1, 2])}, "pyplot must be True or False"),
    ],
)
def test_animation_options_refused_by_name(options, message):
    """Were AttributeError, TypeError, MemoryError (67 GiB), ValueError, and
    'dpi must be a number from 7 to 0'."""
    motion = Motion.from_spin(FIG6, 0.5)
    with pytest.raises(orbits.OrbitsError, match=message):
        orbits.PoinsotAnimation(motion, np.linspace(0.0, 1.0, 3), **options)


def test_scene_of_many_frames_and_rows_with_numeric_names(tmp_path):
    """200,000 frames at the default subsamples were built (1.6e6 traced
    points) before a cap of 1e6 points refused them; a catalog row whose
    name pandas reads as a number (7) or NaN ("NA") animates as before."""
    from orbits.animation_scene import PoinsotScene

    motion = Motion.from_spin(FIG6, 0.5)
    scene = PoinsotScene(motion, np.linspace(0.0, 10.0, 130_001))
    assert scene.subsamples == 8 and len(scene.dense_times) == 8 * 130_000 + 1
    for name in ("7", "NA"):
        out = tmp_path / f"{name}.csv"
        orbits.write_catalog(orbits.closed_orbits(Body(FIG6.moments, name=name), n_max=3), out)
        row = pd.read_csv(out, comment="#").iloc[0]
        motion, _, title = animate.animation_motion(row)
        assert motion.body.name == (None if name == "NA" else name) and title
    with pytest.raises(InputError, match="body given with a body as the source"):
        animate.animation_motion(FIG6, 0.5, body=Body((1.0, 2.0, 3.0)))


def test_the_traced_curves_stay_on_the_ellipsoid_next_to_the_separatrix():
    """At dtheta = 1e-300 the polhode was traced as chords through the
    ellipsoid (x.I.x down to 0.72 at chord midpoints, 0.50 with 5 frames):
    256 steps a period left ~1 for the turn-over past the I2 axis."""
    from orbits.animation_scene import PoinsotScene

    for dtheta, frames in ((1e-300, 120), (1e-300, 5), (-1e-100, 120)):
        motion = Motion.from_spin(FIG6, dtheta=dtheta)
        scene = PoinsotScene(motion, np.linspace(0.0, motion.period, frames))
        middle = 0.5 * (scene.rho_body[1:] + scene.rho_body[:-1])
        on_ellipsoid = np.einsum("ij,j,ij->i", middle, motion.body.moments, middle)
        assert on_ellipsoid.min() > 0.999  # the curve itself: 1
        space = 0.5 * (scene.rho_space[1:] + scene.rho_space[:-1])
        radius = np.hypot(scene.rho_space[:, 0], scene.rho_space[:, 1]).max()
        # a chord's midpoint within 1e-3 of the radius inside the curve's ring
        inner = np.hypot(scene.rho_space[:, 0], scene.rho_space[:, 1]).min()
        assert np.hypot(space[:, 0], space[:, 1]).min() > inner - 1e-3 * radius


def test_uneven_frame_times_trace_to_each_frame_only():
    """With frame times 0, 0.1 T, T the dense grid was one linspace: frame 1
    traced the herpolhode on to 0.496 T, then jumped back to its contact point."""
    from orbits.animation_scene import PoinsotScene

    motion = Motion.from_spin(FIG6, 0.5)
    times = np.array([0.0, 0.1, 1.0]) * motion.period
    scene = PoinsotScene(motion, times)
    assert np.array_equal(scene.dense_times[:: scene.subsamples], times)
    data = scene.frame(1)
    traced = scene.dense_times[: len(data.herpolhode)]
    assert traced[-1] == times[1]
    expected = motion.omega_space(traced) / np.sqrt(2.0 * motion.energy)
    assert np.allclose(data.herpolhode, expected, rtol=0.0, atol=1e-12)


def test_the_clock_tells_fast_frames_apart():
    """A period of 7.7e-4 s showed 0.000, 0.000, 0.001, 0.001 s."""
    anim = animate.poinsot_animation(FIG6, 0.5, speed=1e4, frames=4)
    shown = []
    for k in range(4):
        anim.frame(k)
        (clock,) = [t.get_text() for t in anim.figure.texts if t.get_text().startswith("t = ")]
        shown.append(clock.split(" s =")[0])
    assert len(set(shown)) == 4, shown
    assert animate.clock_text(1.5, np.linspace(0.0, 3.0, 10)) == "1.500"


def test_the_clock_reads_the_time_and_the_fraction_of_a_period():
    """Three frames over one period of Fig. 6 at theta = 0.5 (T = 7.742 in
    1/|w0|, seconds at |w0| = 1 rad/s), and the player's frame interval at
    the frame rate (a clock labelled in ms, a fraction of 2 T, or an interval
    a tenth of the frame's passed every test)."""
    with pytest.warns(UserWarning, match="aliasing"):  # 3 frames a period, on purpose
        anim = animate.poinsot_animation(FIG6, 0.5, frames=3)
    shown = []
    for k in range(3):
        anim.frame(k)
        shown += [t.get_text() for t in anim.figure.texts if t.get_text().startswith("t = ")]
    assert shown == ["t = 0.000 s = 0.000 T", "t = 3.871 s = 0.500 T", "t = 7.742 s = 1.000 T"]
    player = anim.animation
    assert player.event_source.interval == pytest.approx(1000.0 / anim.fps)
    player._draw_was_started = True  # not drawn here: no warning at its deletion


def test_a_solid_given_as_a_mapping_names_its_parts():
    """A dict solid took its values in the mapping's order and ignored the
    keys: {"kind": "box", "c": .., "a": .., "b": ..} drew a box of sides c, a, b."""
    phone = Body.box(0.071, 0.147, 0.0078)
    kind, faces = animate.solid_faces(phone, {"kind": "box", "c": 0.0078, "a": 0.071, "b": 0.147})
    _, expected = animate.solid_faces(phone, ("box", 0.071, 0.147, 0.0078))
    assert kind == "box" and len(faces) == len(expected)
    for got, want in zip(faces, expected):
        np.testing.assert_array_equal(got, want)
    for bad, says in [
        ({"kind": "box", "a": 1.0, "b": 2.0}, "missing: c"),
        ({"kind": "box", "a": 1.0, "b": 2.0, "c": 3.0, "d": 4.0}, "unknown: d"),
        ({"kind": "ellipsoid", "a": 1.0}, "unknown: a"),
        ({"kind": "sphere"}, "needs 'kind'"),
        ({"a": 1.0}, "needs 'kind'"),
    ]:
        with pytest.raises(InputError, match=says):
            animate.solid_faces(phone, bad)


def test_an_empty_title_draws_no_heading():
    """title="" was replaced by the default heading; None keeps the default."""
    blank = animate.poinsot_animation(FIG6, 0.5, frames=3, title="", dpi=40)
    default = animate.poinsot_animation(FIG6, 0.5, frames=3, dpi=40)
    assert blank.figure._suptitle.get_text() == ""
    assert default.figure._suptitle.get_text().startswith("fig6: Poinsot construction")
    row = animate.orbit_row(FIG6, n=3, branch="SAM")
    assert (
        animate.poinsot_animation(row, frames=3, title="", dpi=40).figure._suptitle.get_text()
        == ""
    )


def test_frames_too_far_apart_warn_of_aliasing():
    """A catalog row of n = 30 over the default 120 frames turned the body
    105 degrees a frame, with no word; the warning's frame count keeps
    each turn under 45 degrees, and the turns are the integral of |omega|."""
    from scipy.integrate import quad

    row = animate.orbit_row(FIG6, n=30, branch="SAM")
    with pytest.warns(animate.AliasingWarning, match=r"up to 105 degrees") as caught:
        drawn = animate.poinsot_animation(row, dpi=40)
    assert len(drawn.times) == 120
    enough = int(str(caught[0].message).split("about ")[1].split(" frames")[0])
    with warnings.catch_warnings():
        warnings.simplefilter("error", animate.AliasingWarning)
        smooth = animate.poinsot_animation(row, frames=enough, dpi=40)
    assert smooth.scene.frame_turns.max() <= animate.SMOOTH_TURN
    # each interval's turn against quadrature of |omega| (the trapezoid
    # rule on the 33 steps an interval here: at most 1.3e-5 off, measured)
    motion, times = drawn.motion, drawn.times

    def speed(t):
        return float(np.linalg.norm(motion.state(np.array([t])).omega[0]))

    for k in (0, 37, 118):
        want = quad(speed, times[k], times[k + 1], epsabs=0.0, epsrel=1e-12)[0]
        assert drawn.scene.frame_turns[k] == pytest.approx(want, rel=2e-4)
    # a few frames of a slow spin do not warn
    with warnings.catch_warnings():
        warnings.simplefilter("error", animate.AliasingWarning)
        animate.poinsot_animation(animate.orbit_row(FIG6, n=3, branch="SAM"), frames=40, dpi=40)


def test_a_row_that_does_not_close_is_not_titled_closed():
    """A hand-made or edited row was drawn under "closed orbit 2 pi 7" at a
    spin of 2 pi 3, its branch and closes_after taken on trust ("nan T"),
    and a NaN n was a bare ValueError, a missing branch a KeyError."""
    row = dict(animate.orbit_row(FIG6, n=3, branch="SAM"))
    refused = [
        (dict(row, n=7), r"does not close: its spin's total phase is 18\.849"),
        (dict(row, dtheta=row["dtheta"] * 1.01), "does not close"),
        (dict(row, q=2), "does not close"),
        (dict(row, branch="LAM"), "branch 'LAM' is not its spin's"),
        (dict(row, closes_after="1"), "closes_after '1' is not that of 2 pi 3/1: 1/2"),
        (dict(row, n=float("nan")), "the row's n must be an integer"),
        (dict(row, q=0), "the row's q must be an integer >= 1"),
        (dict(row, I1="x"), "I1, I2, I3"),
    ]
    for edited, says in refused:
        with pytest.raises(orbits.OrbitsError, match=says):
            animate.animation_motion(edited)
    # what a row may leave out is derived from its spin and its n/q
    for kept in (
        dict(row, closes_after=float("nan")),
        {k: v for k, v in row.items() if k not in ("branch", "closes_after")},
    ):
        _, periods, label = animate.animation_motion(kept)
        assert periods == 1.0
        assert r"2\pi\cdot3$, SAM" in label and "closed after 1/2 T" in label
    # n/q not in lowest terms: the orbit of 2 pi 3, back after 1 period
    _, periods, label = animate.animation_motion(dict(row, n=6, q=2, closes_after=None))
    assert periods == 1.0 and r"2\pi\cdot3$" in label


@pytest.mark.parametrize(
    "moments", [[1e-8, 1.0, 1.0 + 3e-9], [1.0, 1.0 + 1e-14, 2.0], [1.0, 2.0 - 1e-12, 2.0]]
)
def test_rows_of_nearly_symmetric_bodies_and_rods_are_drawn_without_their_body(moments):
    """Their rows' rounded I/|I| move the phase beyond 1e-9 (571 of 571 rod
    rows were refused as "does not close"): that rounding is allowed."""
    frame = orbits.catalog([Body(moments)], n_max=12, q_max=2)
    assert len(frame) > 10
    for row in frame.itertuples():
        motion, periods, label = animate.animation_motion(row)
        assert periods == row.q and "closed orbit" in label
    edited = frame.iloc[0].copy()
    edited["n"] = edited["n"] + 7
    with pytest.raises(InputError, match="does not close"):
        animate.animation_motion(edited)


@pytest.mark.skipif(not animate.mp4_available(), reason="imageio-ffmpeg not installed")
@pytest.mark.parametrize(
    "script, words",
    [
        (
            'echo "[out#0/mp4] Error writing trailer: No space left on device" >&2; exit 1',
            "No space left on device",
        ),
        ("kill -XFSZ $$", "File too large"),
        # its messages lost (a full disk), the status still says ENOSPC
        ("exit 228", "No space left on device"),
        (
            'echo "Unknown encoder libx264" >&2; exit 1',
            r"ffmpeg failed \(Unknown encoder libx264\)",
        ),
    ],
    ids=["disk-full", "file-size-limit", "status-only", "other"],
)
def test_an_mp4_that_ffmpeg_fails_to_write_is_an_error(script, words, tmp_path, monkeypatch):
    """ffmpeg's exit status was not read: a full disk or a file-size limit
    ended it while the MP4 was said written (exit 0), and the broken file
    replaced the old one."""
    import imageio_ffmpeg

    fake = tmp_path / "ffmpeg"
    fake.write_text(f"#!/bin/sh\ncat > /dev/null\n{script}\n")
    fake.chmod(0o755)
    monkeypatch.setattr(imageio_ffmpeg, "get_ffmpeg_exe", lambda: str(fake))
    target = tmp_path / "a.mp4"
    target.write_bytes(b"the old animation")
    motion = Motion.from_spin(FIG6, 0.5)
    with pytest.raises(InputError, match=rf"^cannot write {target}: {words}"):
        animate.poinsot_animation(motion, frames=4, dpi=30, out=target)
    assert target.read_bytes() == b"the old animation"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "ffmpeg"]


@pytest.mark.skipif(not animate.mp4_available(), reason="imageio-ffmpeg not installed")
def test_an_ffmpeg_that_cannot_be_found_is_one_line(tmp_path, monkeypatch):
    """With few file descriptors left imageio-ffmpeg finds no ffmpeg and
    raised its RuntimeError ("No ffmpeg exe could be found"): a traceback."""
    import imageio_ffmpeg

    def missing():
        raise RuntimeError("No ffmpeg exe could be found. Install ffmpeg on your system.")

    monkeypatch.setattr(imageio_ffmpeg, "get_ffmpeg_exe", missing)
    target = tmp_path / "a.mp4"
    with pytest.raises(InputError, match=rf"^cannot write {target}: no usable ffmpeg \(No ffmpeg"):
        animate.poinsot_animation(Motion.from_spin(FIG6, 0.5), frames=4, dpi=30, out=target)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits.animation_scene that passed the suite (a
# mutation audit, 2026-11-29: 47 mutants of the figure, plotting, cell and
# limit code; 14 survived, and 11 were caught only by the pixel baselines,
# which skip on other matplotlib/FreeType versions).


# M33: the space panel holds the herpolhode with a 15 % margin, also for a thin rod
def test_space_panel_holds_a_thin_rods_herpolhode_with_its_margin():
    from orbits.animation_scene import PoinsotScene

    rod = Body((0.002, 0.998001, 1.0))
    motion = orbits.Motion.from_spin(rod, 1.5613619707)
    scene = PoinsotScene(motion, np.linspace(0.0, motion.period, 9))
    half, reach = scene.extents()
    radius = np.hypot(scene.rho_space[:, 0], scene.rho_space[:, 1]).max()
    assert 1.15 * radius > reach  # the herpolhode, not the ellipsoid, sets the box
    assert half == pytest.approx(1.15 * radius, rel=1e-12)
    assert reach == pytest.approx(1.05 * scene.semi_axes.max(), rel=1e-12)


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/animate.py or orbits/cli/animate.py
# that passed the suite (a mutation audit, 2026-11-29: 47 mutants, 17
# survivors that changed the animation or its text with exit 0), or guards
# a refusal that another check also makes.


def flip_period(moments, offset, speed=1.0):
    """Eq. 16a in plain floats (scipy's K): the period of the flip spin
    speed (sin o cos o, cos^2 o, sin o), independent of orbits' own phase code."""
    i1, i2, i3 = moments
    w = speed * np.array(
        [math.sin(offset) * math.cos(offset), math.cos(offset) ** 2, math.sin(offset)]
    )
    two_e = i1 * w[0] ** 2 + i2 * w[1] ** 2 + i3 * w[2] ** 2
    m_sq = (i1 * w[0]) ** 2 + (i2 * w[1]) ** 2 + (i3 * w[2]) ** 2
    if m_sq > two_e * i2:
        k2 = (i2 - i1) * (two_e * i3 - m_sq) / ((i3 - i2) * (m_sq - two_e * i1))
        rate = math.sqrt((i3 - i2) * (m_sq - two_e * i1) / (i1 * i2 * i3))
    else:
        k2 = (i3 - i2) * (m_sq - two_e * i1) / ((i2 - i1) * (two_e * i3 - m_sq))
        rate = math.sqrt((i2 - i1) * (two_e * i3 - m_sq) / (i1 * i2 * i3))
    return 4.0 * ellipk(k2) / rate


def cli_span(tmp_path, capsys, argv):
    """Run `orbits animate` (2-3 frames, tiny dpi); the stderr summary's
    (frames, span in s, periods)."""
    out = tmp_path / "a.gif"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["animate", *argv, "--dpi", "10", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    found = re.search(r"(\d+) frames over (\S+) s = (\S+) period", err)
    assert found, err
    return int(found.group(1)), float(found.group(2)), float(found.group(3))


def spy_on_animations(monkeypatch):
    """The PoinsotAnimation objects the command line builds, in a list."""
    drawn = []
    original = animate.poinsot_animation

    def spy(*args, **kwargs):
        drawn.append(original(*args, **kwargs))
        return drawn[-1]

    monkeypatch.setattr(animate, "poinsot_animation", spy)
    return drawn


# M02: clock decimals: one digit finer than the frame interval's magnitude
def test_clock_resolves_a_tenth_of_a_sub_millisecond_frame_interval():
    times = np.linspace(0.0, 7.5e-4, 4)  # 0.25 ms frames
    shown = [animate.clock_text(t, times) for t in times]
    assert shown == ["0.00000", "0.00025", "0.00050", "0.00075"]


# M03: the clock's decimals come from the *smallest* frame interval
def test_clock_tells_apart_unevenly_spaced_frames():
    times = [0.0, 1e-4, 0.5, 1.0]
    shown = [animate.clock_text(t, times) for t in times]
    assert len(set(shown)) == 4, shown
    assert shown[1] == "0.00010"


# M07: the row chosen matches p AND q
def test_orbit_row_from_a_catalog_matches_q_too():
    table = orbits.closed_orbits(FIG6, n_max=3, q_max=3)
    # SAM has no 2 pi 2/3 (its lowest level is above 2 pi 4/3); 2 pi 2/1 must not stand in
    with pytest.raises(InputError, match="no closed orbit"):
        animate.orbit_row(FIG6, p=2, q=3, branch="SAM", orbits=table)
    # 5/3 and 5/2 are both SAM rows of the table: only 5/3 is the one asked for
    row = animate.orbit_row(FIG6, p=5, q=3, branch="SAM", orbits=table)
    assert (row["n"], row["q"], row["branch"]) == (5, 3, "SAM")


# M17: flip_motion's speed is |omega0|
def test_flip_motion_speed_scales_omega_and_period():
    slow = animate.flip_motion(offset=0.1)
    fast = animate.flip_motion(offset=0.1, speed=2.5)
    assert np.linalg.norm(fast.omega0) == pytest.approx(2.5, rel=1e-15)
    np.testing.assert_allclose(fast.omega0, 2.5 * slow.omega0, rtol=1e-15)
    assert fast.period == pytest.approx(flip_period(T_HANDLE.moments, 0.1, 2.5), rel=1e-10)


# M18: the FuncAnimation plays at the animation's own fps
def test_player_interval_follows_fps():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        anim = animate.poinsot_animation(FIG6, 0.5, frames=2, fps=5, dpi=10)
    player = anim.animation
    assert player.event_source.interval == pytest.approx(200.0)
    player._draw_was_started = True


# C02: --flip OFFSET is the offset drawn
def test_cli_flip_offset_is_drawn(tmp_path, capsys):
    frames, span, turns = cli_span(
        tmp_path, capsys, ["--preset", "t-handle", "--flip", "0.2", "--frames", "2"]
    )
    assert (frames, turns) == (2, 1.0)
    assert span == pytest.approx(flip_period(T_HANDLE.moments, 0.2), rel=1e-3)


# C03: --speed is applied to --flip
def test_cli_flip_speed_is_drawn(tmp_path, capsys):
    _, span, _ = cli_span(
        tmp_path, capsys, ["--preset", "t-handle", "--flip", "--speed", "4", "--frames", "2"]
    )
    assert span == pytest.approx(flip_period(T_HANDLE.moments, 0.05, 4.0), rel=1e-3)


# C04: --speed is in --units
def test_cli_speed_takes_its_units(tmp_path, capsys):
    period = Motion.from_spin(FIG6, 0.5).period  # at 1 rad/s
    _, span, _ = cli_span(
        tmp_path,
        capsys,
        ["--preset", "fig6", "--theta", "0.5", "--speed", "60", "--units", "rpm", "--frames", "2"],
    )
    # 60 rpm = 2 pi rad/s: the period scales as 1/|omega0|
    assert span == pytest.approx(period / (2.0 * math.pi), rel=1e-3)


# C06: --periods is the duration of a --theta/--dtheta/--flip/--n animation
def test_cli_periods_sets_the_duration(tmp_path, capsys):
    period = Motion.from_spin(FIG6, 0.5).period
    frames, span, turns = cli_span(
        tmp_path,
        capsys,
        ["--preset", "fig6", "--theta", "0.5", "--periods", "2.5", "--frames", "3"],
    )
    assert (frames, turns) == (3, 2.5)
    assert span == pytest.approx(2.5 * period, rel=1e-3)


# M20: an MP4 plays at the animation's fps
@pytest.mark.skipif(not animate.mp4_available(), reason="imageio-ffmpeg not installed")
def test_mp4_plays_at_its_fps(tmp_path):
    import imageio_ffmpeg

    out = tmp_path / "a.mp4"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        animate.poinsot_animation(FIG6, 0.5, frames=3, fps=5, dpi=10, out=out)
    reader = imageio_ffmpeg.read_frames(str(out))
    meta = next(reader)
    reader.close()
    assert meta["fps"] == pytest.approx(5.0)
    assert meta["duration"] == pytest.approx(3 / 5, abs=0.15)


# M21: the default heading states |omega0|, the branch and T
def test_default_heading_states_the_spin_rate():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        anim = animate.poinsot_animation(FIG6, 0.5, speed=3.0, frames=2, dpi=10)
    period = Motion.from_spin(FIG6, 0.5).period / 3.0
    heading = anim._title.get_text()
    assert heading.endswith(f"T = {period:.4g} s at |omega0| = 3 rad/s"), heading
    assert f", {anim.motion.branch}," in heading


# C08: the flip's title: T and the flip every T/2
def test_cli_flip_title_states_half_the_period(tmp_path, capsys, monkeypatch):
    drawn = spy_on_animations(monkeypatch)
    cli_span(tmp_path, capsys, ["--preset", "t-handle", "--flip", "0.1", "--frames", "2"])
    title = drawn[0]._title.get_text()
    found = re.search(r"T = (\S+) s, flips every T/2 = (\S+) s", title)
    assert found, title
    whole, half = float(found.group(1)), float(found.group(2))
    assert whole == pytest.approx(flip_period(T_HANDLE.moments, 0.1), rel=1e-3)
    assert half == pytest.approx(whole / 2, rel=1e-3)
    assert "tipped 0.1 rad" in title and "|omega0| = 1 rad/s" in title


# M22: the body panel's caption states the solid's scale (length units -> ellipsoid units)
def test_caption_states_the_solids_scale():
    a, b, c, mass = 0.071, 0.147, 0.0078, 0.17
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        anim = animate.poinsot_animation(Body.box(a, b, c, mass), 0.5, frames=2, dpi=10)
    # the box's corners are drawn on x.I.x = 0.95^2: s^2 sum I_k (side_k / 2)^2 = 0.95^2
    moments = mass / 12 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    scale = 0.95 / math.sqrt(float(np.sum(moments * (np.array([a, b, c]) / 2) ** 2)))
    (caption,) = [t.get_text() for t in anim.figure.texts if "drawn x" in t.get_text()]
    shown = float(caption.split("drawn x")[1])
    assert caption.split("\n")[1].startswith("box drawn x")
    assert shown == pytest.approx(scale, rel=1e-2)  # 1.07e+03


# C09: the title states --speed in its own --units
def test_cli_title_states_speed_in_its_units(tmp_path, capsys, monkeypatch):
    drawn = spy_on_animations(monkeypatch)
    cli_span(
        tmp_path,
        capsys,
        ["--preset", "fig6", "--theta", "0.5", "--speed", "60", "--units", "rpm", "--frames", "2"],
    )
    assert drawn[0]._title.get_text().endswith("at |omega0| = 60 rpm")


# C10 (guard; C10 was equivalent, C10b/C10c -- count-1, times[-2] -- are killed here and by the suite)
def test_cli_summary_counts_a_rows_q_periods(tmp_path, capsys):
    row = animate.orbit_row(FIG6, p=7, q=2, branch="SAM")
    period = Motion.from_spin(Body((row["I1"], row["I2"], row["I3"])), dtheta=row["dtheta"]).period
    frames, span, turns = cli_span(
        tmp_path,
        capsys,
        ["--preset", "fig6", "--p", "7", "--q", "2", "--branch", "SAM", "--frames", "2"],
    )
    assert (frames, turns) == (2, 2.0)
    assert span == pytest.approx(2 * period, rel=1e-3)


# C12 (equivalent: the applicability layer refuses first) -- kept as a guard of the refusal
@pytest.mark.parametrize("spin", [["--n", "5", "--branch", "SAM"], ["--omega", "0.1", "1", "0.1"]])
def test_cli_speed_with_an_orbit_or_throw_is_refused(tmp_path, capsys, monkeypatch, spin):
    monkeypatch.chdir(tmp_path)
    code = main(["animate", "--preset", "fig6", *spin, "--speed", "3", "--out", "a.gif"])
    assert code == 2
    assert "--speed applies to --theta, --dtheta and --flip" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


# C14: --units with neither --omega nor --speed is refused, not ignored
def test_cli_units_without_a_rate_is_refused(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = main(
        ["animate", "--preset", "fig6", "--theta", "0.5", "--units", "rpm", "--out", "a.gif"]
    )
    assert code == 2
    assert "--units applies to --omega and --speed" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


# C16: --phi is part of the --theta spin
def test_cli_phi_is_drawn(tmp_path, capsys, monkeypatch):
    drawn = spy_on_animations(monkeypatch)
    _, span, _ = cli_span(
        tmp_path,
        capsys,
        ["--moments", "2", "3", "4", "--theta", "0.5", "--phi", "1.0", "--frames", "2"],
    )
    expected = np.array(
        [math.sin(0.5) * math.cos(1.0), math.sin(0.5) * math.sin(1.0), math.cos(0.5)]
    )
    np.testing.assert_allclose(drawn[0].motion.omega0, expected, rtol=0, atol=1e-15)
    assert span == pytest.approx(Motion(Body((2.0, 3.0, 4.0)), expected).period, rel=1e-3)
