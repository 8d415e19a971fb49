"""Figure files: the paper's figures, herpolhode sets, determinism, the CLI."""

import matplotlib

matplotlib.use("Agg")

import math  # noqa: E402
import re  # noqa: E402

import matplotlib.image as mpimg  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import orbits  # noqa: E402
from orbits import Body, figures  # noqa: E402
from orbits.cli import main  # noqa: E402
from orbits.errors import InputError  # noqa: E402

FIG6 = Body.preset("fig6")


def all_axes(figure):
    return [ax for ax in figure.get_axes() if ax.get_label() != "<colorbar>"]


def assert_not_blank(path):
    image = mpimg.imread(path)
    assert image.std() > 0.05, f"{path} looks blank"
    assert image.shape[0] > 300 and image.shape[1] > 300


@pytest.fixture(scope="module")
def paper(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    built = {name: build() for name, build in figures.PAPER_FIGURES.items()}
    for name, figure in built.items():
        figures.save_figure(figure, out / name, ("png",))
    return out, built


@pytest.mark.parametrize("name", list(figures.PAPER_FIGURES))
def test_paper_figure_is_drawn_and_labelled(paper, name):
    out, built = paper
    assert_not_blank(out / f"{name}.png")
    figure = built[name]
    for ax in all_axes(figure):
        if not ax.get_visible() or not ax.axison:
            continue
        if ax in getattr(figure, "inset_axes_list", []):
            continue
        if hasattr(ax, "get_zlabel"):
            assert ax.get_xlabel() and ax.get_ylabel() and ax.get_zlabel(), name
        elif ax.get_xticks().size and ax.get_xlabel() == "" and ax.get_ylabel() == "":
            # insets of Fig. 6 carry only a title
            assert ax.get_title(), name
        else:
            assert ax.get_xlabel() or ax.get_ylabel(), name


@pytest.mark.parametrize("name", ["fig2", "fig4"])
def test_maps_have_colour_bars(paper, name):
    _, built = paper
    bars = [ax for ax in built[name].get_axes() if ax.get_label() == "<colorbar>"]
    assert len(bars) == 1 and bars[0].get_ylabel()


def test_fig6_insets_are_closed_catalog_orbits(paper):
    _, built = paper
    catalog = orbits.closed_orbits(FIG6, n_max=8)
    insets = built["fig6"].insets
    assert len(insets) >= 6
    for inset, row in insets:
        assert row.dtheta in set(catalog["dtheta"])
        xy = inset.get_lines()[0].get_xydata()
        assert np.abs(xy[-1] - xy[0]).max() <= 1e-9


def test_fig5_marks_the_critical_angle(paper):
    _, built = paper
    ax = built["fig5"].get_axes()[0]
    verticals = [line.get_xdata()[0] for line in ax.get_lines() if len(set(line.get_xdata())) == 1]
    assert verticals == [pytest.approx(orbits.critical_angle(Body.preset("t-handle")))]


def test_herpolhode_set_files_order_and_closure(tmp_path):
    written = figures.herpolhode_set(FIG6, 5, tmp_path, q_max=2, formats=("png", "svg"))
    catalog = orbits.closed_orbits(FIG6, n_max=5, q_max=2)
    stems = sorted({p.stem for p in written})
    assert "contact_sheet" in stems
    assert len(stems) == len(catalog) + 1
    assert {p.suffix for p in written} == {".png", ".svg"}
    for path in written:
        if path.suffix == ".png":
            assert_not_blank(path)
    sheet = figures.contact_sheet(FIG6, catalog)
    drawn = [ax for ax in sheet.get_axes() if ax.get_lines()]
    ordered = figures._paper_order(catalog)
    assert len(drawn) == len(ordered)
    assert list(ordered["dtheta"]) == sorted(ordered["dtheta"])  # left to right in theta
    for ax, row in zip(drawn, ordered.itertuples()):
        multiple = f"{row.n}" if row.q == 1 else f"{row.n}/{row.q}"
        assert rf"{row.branch} $2\pi\cdot{multiple}$" in ax.get_title()
        xy = ax.get_lines()[0].get_xydata()
        assert np.abs(xy[-1] - xy[0]).max() <= 1e-9  # closed over closes_after
        # one common scale on every panel
        assert ax.get_xlim() == (-sheet.limit, sheet.limit)
        assert ax.get_ylim() == (-sheet.limit, sheet.limit)


def test_fig6_leader_lines_do_not_cross(paper):
    """Leader segments (inset bottom -> dot), in figure pixels, pairwise disjoint."""
    _, built = paper
    figure = built["fig6"]
    figure.canvas.draw()
    segments = []
    for inset, row in figure.insets:
        a = inset.transAxes.transform((0.5, 0.0))
        b = figure.main_axes.transData.transform((row.theta, row.total_phase))
        segments.append((a, b))

    def cross(p, q, r):
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    for i, (p1, p2) in enumerate(segments):
        for p3, p4 in segments[i + 1 :]:
            d1, d2 = cross(p3, p4, p1), cross(p3, p4, p2)
            d3, d4 = cross(p1, p2, p3), cross(p1, p2, p4)
            assert not (d1 * d2 < 0 and d3 * d4 < 0)
    # the insets sit above the main axes: they cover no data, level name or the spike
    top = figure.main_axes.get_window_extent().y1
    for inset, _ in figure.insets:
        assert inset.get_window_extent().y0 >= top


def test_output_is_deterministic(tmp_path):
    for fmt in ("png", "svg", "pdf"):
        first = figures.save_figure(figures.figure5(), tmp_path / "a", (fmt,))[0]
        second = figures.save_figure(figures.figure5(), tmp_path / "b", (fmt,))[0]
        assert first.read_bytes() == second.read_bytes(), fmt


class TestCli:
    def test_paper(self, tmp_path, capsys):
        assert main(["figures", "--paper", "--formats", "png", "--out", str(tmp_path)]) == 0
        assert sorted(p.name for p in tmp_path.iterdir()) == [f"fig{k}.png" for k in range(1, 7)]

    def test_body_set(self, tmp_path, capsys):
        out = tmp_path / "made" / "here"
        assert (
            main(
                [
                    "figures",
                    "--t-handle",
                    "8",
                    "4",
                    "1",
                    "--n-max",
                    "3",
                    "--formats",
                    "svg",
                    "--out",
                    str(out),
                ]
            )
            == 0
        )
        names = sorted(p.name for p in out.iterdir())
        assert "contact_sheet.svg" in names and "herpolhode_SAM_n002.svg" in names
        # only the formats asked (a mutant that dropped --formats wrote PNGs too)
        assert all(name.endswith(".svg") for name in names), names

    @pytest.mark.parametrize(
        "argv, fragment",
        [
            (["figures", "--out", "d"], "exactly one"),
            (["figures", "--paper", "--preset", "fig6", "--out", "d"], "exactly one"),
            (["figures", "--preset", "fig6", "--out", "d"], "--n-max is required"),
            (
                ["figures", "--preset", "fig6", "--n-max", "0", "--out", "d"],
                "must be an integer >= 1",
            ),
            (["figures", "--moments", "1", "1", "2", "--n-max", "2", "--out", "d"], "symmetric"),
            (["figures", "--preset", "nope", "--n-max", "2", "--out", "d"], "invalid choice"),
            (["figures", "--paper", "--formats", "gif", "--out", "d"], "invalid choice"),
            (["figures", "--paper", "--out", "/proc/orbits-figures"], "cannot create"),
        ],
    )
    def test_bad_input(self, tmp_path, capsys, monkeypatch, argv, fragment):
        monkeypatch.chdir(tmp_path)
        code = main(argv)
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and len(err) == 1 and fragment in err[0], err


def test_contact_sheet_titles_state_the_closure_time():
    """p/q with p and q odd close after q/2 periods: 3T/2 for q = 3, T/2 for odd n."""
    catalog = orbits.closed_orbits(FIG6, n_max=3, q_max=3)
    sheet = figures.contact_sheet(FIG6, catalog)
    titles = [ax.get_title() for ax in sheet.get_axes() if ax.get_lines()]
    expected = {1: "(T/2)", 3: "(3T/2)"}
    seen = set()
    for title, row in zip(titles, figures._paper_order(catalog).itertuples()):
        if row.n % 2 and row.q % 2:
            assert expected[row.q] in title, title
            seen.add(row.q)
        else:
            assert "T/2" not in title, title
    assert seen == {1, 3}


def _inside(inner, outer, slack=1.0):
    return (
        inner.x0 >= outer.x0 - slack
        and inner.y0 >= outer.y0 - slack
        and inner.x1 <= outer.x1 + slack
        and inner.y1 <= outer.y1 + slack
    )


@pytest.mark.parametrize("name", list(figures.PAPER_FIGURES))
def test_no_label_or_title_is_clipped(paper, name):
    """Every axis label, title and legend lies wholly inside the figure (Fig. 1's
    x label was cut to '...length uni')."""
    _, built = paper
    figure = built[name]
    renderer = figure.canvas.get_renderer()
    figure.canvas.draw()
    page = figure.bbox
    texts = [t for t in figure.texts if t.get_text()]
    if figure._suptitle is not None:
        texts.append(figure._suptitle)
    for ax in figure.get_axes():
        texts.append(ax.title)
        if ax.axison:  # Fig. 4 draws its own labelled axes instead
            texts += [ax.xaxis.label, ax.yaxis.label]
            if hasattr(ax, "zaxis"):
                texts.append(ax.zaxis.label)
        if ax.get_legend() is not None:
            texts.append(ax.get_legend())
    checked = 0
    for text in texts:
        if not text.get_visible() or (hasattr(text, "get_text") and not text.get_text()):
            continue
        extent = text.get_window_extent(renderer)
        assert _inside(extent, page), (name, getattr(text, "get_text", str)(), extent, page)
        checked += 1
    assert checked >= 2


def test_fig3_period_label_and_legend_clear_of_curves_and_axis(paper):
    """T is named above the plot (not on the time axis, no curve under it, clear of
    the panel title); the legend sits under the time axis (it covered the curves)."""
    _, built = paper
    figure = built["fig3"]
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    ax = next(a for a in figure.get_axes() if a.get_xlabel().startswith("time"))
    labels = [
        t
        for child in ax.child_axes
        for t in child.get_xticklabels()
        if t.get_text().startswith("T = ")
    ]
    assert len(labels) == 1
    box = labels[0].get_window_extent(renderer)
    assert box.y0 >= ax.bbox.y1  # above the data area
    title = ax.title.get_window_extent(renderer)
    assert box.y1 <= title.y0 or box.x1 <= title.x0 or box.x0 >= title.x1
    # the label is centred on the period's vertical line
    period = ax.transData.transform((_period(ax), 0.0))[0]
    assert abs(0.5 * (box.x0 + box.x1) - period) < 1.0
    legend = ax.get_legend().get_window_extent(renderer)
    assert legend.y1 <= ax.xaxis.get_tightbbox(renderer).y0 + 1.0


def _period(ax):
    verticals = [line.get_xdata()[0] for line in ax.get_lines() if len(set(line.get_xdata())) == 1]
    assert len(verticals) == 1
    return verticals[0]


def test_a_body_without_closed_orbits_writes_no_figure(tmp_path):
    # Delta alpha > 2 pi for every spin: no orbit with n = 1
    assert figures.herpolhode_set(FIG6, 1, tmp_path, formats=("png",)) == []
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(orbits.errors.InputError, match="at least one"):
        figures.contact_sheet(FIG6, orbits.closed_orbits(FIG6, n_max=1))


@pytest.mark.parametrize("stop", [KeyboardInterrupt, RuntimeError])
def test_a_figure_set_is_written_whole_or_not_at_all(tmp_path, monkeypatch, capsys, stop):
    """A stop (or an error) while the contact sheet is drawn leaves the directory as it was.

    An adversarial probe found 9 of 19 figures after Ctrl-C, under the line
    "no partial output was written".  The set is drawn into a staging
    directory and moved into place only when whole.
    """
    from orbits import figures as module
    from orbits.cli import main

    out = tmp_path / "figs"
    out.mkdir()
    (out / "herpolhode_SAM_n002.png").write_bytes(b"an older figure")

    def broken(*args, **kwargs):
        raise stop()

    monkeypatch.setattr(module, "contact_sheet", broken)
    argv = ["figures", "--preset", "fig6", "--n-max", "3", "--formats", "png", "--out", str(out)]
    if stop is KeyboardInterrupt:
        assert main(argv) == 130
        assert "no partial output" in capsys.readouterr().err
    else:
        with pytest.raises(RuntimeError):
            main(argv)
    assert sorted(p.name for p in out.iterdir()) == ["herpolhode_SAM_n002.png"]
    assert (out / "herpolhode_SAM_n002.png").read_bytes() == b"an older figure"
    # and without the fault, the whole set
    monkeypatch.undo()
    assert main(argv) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(
        ["contact_sheet.png"]
        + [f"herpolhode_{b}_n00{n}.png" for b in ("SAM", "LAM") for n in (2, 3)]
    )
    assert (out / "herpolhode_SAM_n002.png").read_bytes()[:4] == b"\x89PNG"


# ------------------------------------------------------------------ long curves
NEAR_SPHERE = Body((1.0, 1.00001, 1.00002))


def test_a_set_whose_curves_are_too_long_is_refused_before_anything(tmp_path, capsys):
    """--n-max 100000 on a body that closes there: 10^5 turns, more than a
    curve may have; refused before the search's estimate and the directory."""
    out = tmp_path / "made" / "here"
    argv = ["figures", "--moments", "1", "1.00001", "1.00002", "--n-max", "100000"]
    assert main(argv + ["--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "orbits: error: the closed herpolhode at n = 100000 makes about 1e+05 turns, more "
        "than the 99999 a drawn curve may have (10000000 samples, 100 a turn); lower --n-max"
    ]
    assert list(tmp_path.iterdir()) == []
    # p/q orbits are checked with the catalog, naming both options
    with pytest.raises(orbits.errors.InputError, match="99999 a drawn curve.*; lower --n-max or"):
        figures.check_figure_set(3, ["png"], "lower --n-max or --q-max", turns=[2.0, 1.5e5])


@pytest.mark.slow
def test_a_curve_that_fills_its_ring_is_saved(tmp_path):
    """35,000 turns (3.5 * 10^6 samples) on a 150-dpi figure: Agg refused the
    path whole ("Exceeded cell block limit"); it is rasterized in pieces."""
    figure = figures.new_figure(5.2, 5.9)
    ax = figure.add_subplot()
    line = orbits.plotting.plot_herpolhode(ax, NEAR_SPHERE, 0.01, periods=0.5)
    assert len(line.get_xydata()) > 3_000_000
    (path,) = figures.save_figure(figure, tmp_path / "ring", "png")
    image = mpimg.imread(path)[..., :3]
    # the ring is drawn solid in the curve's colour between r_min and r_max
    colour = np.array(matplotlib.colors.to_rgb("tab:purple"))
    close = np.abs(image - colour).max(axis=-1) < 0.05
    assert close.mean() > 0.1


# ------------------------------------------------------------------ paths, errors, stops
@pytest.mark.parametrize("option", ["--out", "--survey"])
def test_an_empty_path_is_refused(tmp_path, capsys, monkeypatch, option):
    """--out "" wrote the set into the current directory."""
    monkeypatch.chdir(tmp_path)
    if option == "--out":
        argv = ["figures", "--preset", "fig6", "--n-max", "2", "--out", ""]
    else:
        argv = ["figures", "--survey", "", "--out", "d"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"orbits: error: {option} must be a non-empty path, got '' (str)"]
    assert list(tmp_path.iterdir()) == []


def _fault(kind):
    import errno
    import signal

    from orbits.atomic import Terminated

    if kind == "error":
        return orbits.errors.InputError("a fault")
    if kind == "full":
        return OSError(errno.ENOSPC, "No space left on device")
    return KeyboardInterrupt() if kind == "interrupt" else Terminated(signal.SIGTERM)


@pytest.mark.parametrize(
    "kind, code, message",
    [
        ("error", 2, "orbits: error: a fault"),
        ("full", 2, None),
        ("interrupt", 130, "orbits: interrupted; no partial output was written"),
        ("terminate", 143, "orbits: stopped by SIGTERM; no partial output was written"),
    ],
)
def test_the_directories_a_run_made_are_removed_after_an_error_or_a_stop(
    tmp_path, monkeypatch, capsys, kind, code, message
):
    """nd/sub/dir was left behind, empty, after a stop, a full disk or an error;
    a full disk named the private staging directory."""
    from matplotlib.figure import Figure

    monkeypatch.chdir(tmp_path)
    (tmp_path / "kept").mkdir()

    def broken(*args, **kwargs):
        raise _fault(kind)

    if kind == "full":  # the figures are drawn in memory: the disk fills as one is written
        import orbits.atomic

        monkeypatch.setattr(orbits.atomic.os, "fsync", broken)
    else:
        monkeypatch.setattr(Figure, "savefig", broken)
    argv = ["figures", "--preset", "fig6", "--n-max", "3", "--formats", "png"]
    assert main(argv + ["--out", "kept/nd/sub/dir"]) == code
    err = capsys.readouterr().err.strip().splitlines()
    if kind == "full":
        # the first figure of the set, in the paper's order
        message = (
            "orbits: error: cannot write kept/nd/sub/dir/herpolhode_SAM_n002.png: "
            "No space left on device"
        )
    assert err[-1] == message
    assert [p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*")] == ["kept"]


def test_a_read_only_directory_is_named(tmp_path, monkeypatch, capsys):
    """The message named DIR/probe, a file the user never gave."""
    import os

    target = tmp_path / "ro"
    target.mkdir()
    access = os.access
    monkeypatch.setattr(os, "access", lambda path, mode: access(path, mode) and path != target)
    argv = ["figures", "--preset", "fig6", "--n-max", "2", "--out", str(target)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"orbits: error: cannot write into output directory {target}: it is not writable"
    ]
    assert list(target.iterdir()) == []


def test_save_figure_writes_every_format_or_none(tmp_path, monkeypatch):
    figure = figures.figure5()
    with pytest.raises(orbits.errors.InputError, match="unknown figure format 'jpg'"):
        figures.save_figure(figure, tmp_path / "f", ("png", "jpg"))
    with pytest.raises(orbits.errors.InputError, match="formats is empty"):
        figures.save_figure(figure, tmp_path / "f", ())
    assert list(tmp_path.iterdir()) == []
    # a failure on the second format (the disk fills as it is written)
    # leaves no first one either
    from orbits import atomic

    original, synced = atomic.os.fsync, []

    def second_fails(descriptor):
        synced.append(descriptor)
        if len(synced) == 2:
            raise OSError(28, "No space left on device")
        return original(descriptor)

    monkeypatch.setattr(atomic.os, "fsync", second_fails)
    with pytest.raises(orbits.errors.InputError) as caught:
        figures.save_figure(figure, tmp_path / "f", ("png", "svg"))
    assert str(caught.value) == f"cannot write {tmp_path / 'f.svg'}: No space left on device"
    assert list(tmp_path.iterdir()) == []


def test_each_file_is_the_same_whatever_the_other_formats(tmp_path):
    """svg pdf png and pdf svg png gave different SVG and PDF bytes: the
    constrained layout moved ~0.4 pt between saves of one figure."""
    figure = figures.figure5()
    engine = figure.get_layout_engine()
    first = figures.save_figure(figure, tmp_path / "a", ("svg", "pdf", "png"))
    second = figures.save_figure(figures.figure5(), tmp_path / "b", ("pdf", "svg", "png"))
    alone = [
        figures.save_figure(figures.figure5(), tmp_path / f"c{k}", fmt)[0]
        for k, fmt in enumerate(("png", "svg", "pdf"))
    ]
    by_format = {path.suffix: path.read_bytes() for path in first}
    for path in second + alone:
        assert path.read_bytes() == by_format[path.suffix], path.name
    # and the figure keeps its layout engine
    assert figure.get_layout_engine() is engine


def test_unknown_paper_figures_and_bad_columns_are_refused(tmp_path):
    with pytest.raises(orbits.errors.InputError, match="unknown paper figure 'fig7'; use fig1"):
        figures.paper_figures(tmp_path, names=["fig7"])
    catalog = orbits.closed_orbits(FIG6, n_max=3)
    for columns, message in (
        (-1, "columns must be an integer >= 1, got -1"),
        (0, "columns must be an integer >= 1, got 0"),
        (10**6, "a contact sheet of 4 orbits in columns=1000000 would be 300000000 x 480"),
    ):
        with pytest.raises(orbits.errors.InputError, match=message):
            figures.contact_sheet(FIG6, catalog, columns=columns)
    assert list(tmp_path.iterdir()) == []


def test_rows_of_another_body_or_beyond_n_max_are_refused(tmp_path, capsys):
    """A catalog row is drawn from its dtheta and the body given: fig6 rows
    drawn on the t-handle came out titled 2 pi 2 with a spin of 2.15 turns
    that does not close, and herpolhode_set(n_max=2) drew the n = 3 rows of
    the catalog it was given (an audit)."""
    t_handle = Body.preset("t-handle")
    catalog = orbits.closed_orbits(FIG6, n_max=3)
    other = (
        r"a catalog row \(n/q = 2/1, dtheta = -0.0563702163535538[0-9]\) is no closed "
        r"orbit of the body drawn: its total phase there is 13.500359119235.* rad, not 2 pi "
        r"n/q = 12.566370614359172; a row of another body"
    )
    with pytest.raises(orbits.errors.InputError, match=other):
        figures.herpolhode_set(t_handle, 3, tmp_path, orbits=catalog)
    with pytest.raises(orbits.errors.InputError, match=other):
        figures.closed_herpolhode_figure(t_handle, next(catalog.itertuples()))
    with pytest.raises(orbits.errors.InputError, match=other):
        figures.contact_sheet(t_handle, catalog)
    with pytest.raises(orbits.errors.InputError, match="n/q = 3/1, beyond n_max = 2, q_max = 1"):
        figures.herpolhode_set(FIG6, 2, tmp_path, orbits=catalog)
    rational = orbits.closed_orbits(FIG6, n_max=3, q_max=2)
    with pytest.raises(orbits.errors.InputError, match="n/q = 5/2, beyond n_max = 2, q_max = 2"):
        figures.herpolhode_set(FIG6, 2, tmp_path, q_max=2, orbits=rational)
    with pytest.raises(orbits.errors.InputError, match="q_max = 1"):
        figures.herpolhode_set(FIG6, 3, tmp_path, orbits=rational)
    assert list(tmp_path.iterdir()) == []
    # the same body built another way (moments a few ulps apart: 48 ulps for
    # these point masses listed in another order) is the body of the catalog
    masses = [0.631, 1.722, 0.995, 1.212, 0.758]
    points = [
        [0.276, -0.26, -0.201],
        [-1.034, 2.517, -0.268],
        [0.913, -1.484, -0.356],
        [-0.11, -0.182, 0.207],
        [-0.345, -0.041, -0.022],
    ]
    order = [1, 0, 4, 2, 3]
    listed = Body.from_point_masses(masses, points)
    reordered = Body.from_point_masses([masses[k] for k in order], [points[k] for k in order])
    assert not np.array_equal(listed.normalized_moments, reordered.normalized_moments)
    figures.check_orbits_of(reordered, orbits.closed_orbits(listed, n_max=3), 3, 1)
    centimetres = orbits.closed_orbits(Body.box(0.1, 0.2, 1.7), n_max=2)
    figures.check_orbits_of(Body.box(0.001, 0.002, 0.017), centimetres, 2, 1)
    # the catalog of this body read back from its CSV is drawn
    path = tmp_path / "fig6.csv"
    orbits.write_catalog(catalog, path)
    written = (
        figures.herpolhode_set(
            FIG6, 3, tmp_path / "set", formats=("png",), orbits=orbits.read_catalog(path)
        )
        if (tmp_path / "set").mkdir() is None
        else None
    )
    assert sorted(p.name for p in written)[-1] == "herpolhode_SAM_n003.png"
    assert len(written) == len(catalog) + 1


def test_a_directory_of_another_set_is_refused(tmp_path, capsys):
    """A second run into the same --out replaced only its own names, leaving
    the old set's p/q figures and SVG contact sheet beside it (an audit)."""
    out = tmp_path / "set"
    first = ["figures", "--moments", "1", "2", "3", "--n-max", "3", "--q-max", "2"]
    assert main([*first, "--formats", "png", "svg", "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert "contact_sheet.svg" in before and "herpolhode_SAM_p005q2.png" in before
    capsys.readouterr()
    again = ["figures", "--moments", "1", "2", "3", "--n-max", "2", "--formats", "png"]
    assert main([*again, "--out", str(out)]) == 2
    last = capsys.readouterr().err.splitlines()[-1]
    assert last.startswith("orbits: error: ") and "holds figures of another set" in last
    assert "herpolhode_LAM_n003.png" in last
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # the same set again is written over, and other files are no concern
    (out / "notes.txt").write_text("mine")
    assert main([*first, "--formats", "png", "svg", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted([*before, "notes.txt"])


def test_figure6_n_inset_is_checked():
    for bad, message in ((0, ">= 1, got 0"), (-1, ">= 1, got -1"), (2.5, "got 2.5"), (6, "<= 5")):
        with pytest.raises(orbits.errors.OrbitsError, match=message):
            figures.figure6(n_inset=bad)


def test_figures_help_says_each_orbit_is_drawn_until_it_closes(capsys):
    assert main(["figures", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "drawn over q periods" not in text
    assert "T/2 for odd n, q/2 periods when p and q are odd, else q" in text


def test_contact_sheet_of_rows_without_closes_after(tmp_path):
    """p/q rows without closes_after (or NaN there) are drawn over q periods,
    and their panels say so (an AttributeError before)."""
    import numpy as np

    import orbits
    from orbits import figures, plotting

    body = orbits.Body.preset("fig6")
    rows = orbits.catalog(body, n_max=3, q_max=2)
    for table in (rows.drop(columns="closes_after"), rows.assign(closes_after=np.nan)):
        figure = figures.contact_sheet(body, table)
        titles = [ax.get_title() for ax in figure.axes if ax.get_title()]
        assert any("(2T)" in title for title in titles)
        row = next(table[table.q == 2].itertuples())
        assert plotting.orbit_label(row, "fig6").endswith("closes after 2 T (drawn once)")


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits.figures or orbits.cli.figures that passed the suite (a
# mutation audit, 2026-11-29: 47 mutants of the figure, plotting, cell and
# limit code; 14 survived, and 11 were caught only by the pixel baselines,
# which skip on other matplotlib/FreeType versions).


@pytest.fixture(scope="module")
def fig6_catalog():
    return orbits.closed_orbits(FIG6, n_max=3, q_max=2)


# M10: the figure-set memory estimate must count the curves' samples
def test_figure_set_memory_counts_the_curve_samples(monkeypatch):
    # one orbit: the contact sheet (6.4 x 3.2 in at 150 dpi) is ~0.46 Mpx, a few
    # RGBA buffers ~6 MB; a curve of 50,000 turns is drawn with >= 100 samples a
    # turn = 5e6 samples, >= 16 bytes each (x, y doubles) = 80 MB at the least
    monkeypatch.setattr(figures, "memory_budget", lambda: 50 * 2**20)
    figures.check_figure_set(1, ("png",), turns=[1.0])  # the sheet alone fits
    with pytest.raises(InputError, match="memory"):
        figures.check_figure_set(1, ("png",), turns=[50_000.0])


# M12: the turns drawn are those over closes_after (T/2 for odd n), not q periods
def test_drawn_turns_follow_closes_after(fig6_catalog):
    turns = figures.drawn_turns(fig6_catalog)
    for row, got in zip(fig6_catalog.itertuples(), turns):
        # Delta alpha = 2 pi n/q a period; odd n (q = 1) closes after T/2,
        # p/q = 3/2 or 5/2 (p odd, q even) after q = 2 periods
        expected = {(3, 1): 1.5, (2, 1): 2.0, (3, 2): 3.0, (5, 2): 5.0}[(row.n, row.q)]
        assert got == pytest.approx(expected, rel=1e-12)


# M15: the contact sheet's pixel height is bounded by Agg's 65535 (at most 1584 orbits)
def test_contact_sheet_height_limit_is_1584_orbits(monkeypatch):
    monkeypatch.setattr(figures, "memory_budget", lambda: 1 << 50)
    # 1584 orbits: 8 columns, 198 rows, (2.2 * 198 + 1) in * 150 dpi = 65490 px
    figures.check_figure_set(1584, ("png",))
    # 1585: 199 rows, 65820 px > 65535
    with pytest.raises(InputError, match="pixels tall"):
        figures.check_figure_set(1585, ("png",))


# M37: the figures' own search estimate takes --q-max into account
def test_cli_figures_estimates_its_search_with_q_max(tmp_path, capsys, monkeypatch):
    import orbits.search
    from orbits.cli import main

    def stop(*args, **kwargs):
        raise InputError("stopped before the search")

    monkeypatch.setattr(orbits.search, "closed_orbits", stop)
    # n_max = 2, q_max = 800: 2 * 800 * 801 / 2 = 640,800 candidate fractions,
    # at the measured 7 us each about 4.5 s: announced before the search
    argv = [
        "figures",
        "--preset",
        "fig6",
        "--n-max",
        "2",
        "--q-max",
        "800",
        "--out",
        str(tmp_path / "o"),
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "orbits figures: estimated" in err and "stopped before the search" in err
    # a hopeless q_max is refused by the figures' search estimate itself
    argv[6] = "1000000"
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the figures' search" in err[0] and "q_max=1000000" in err[0]


# M41: a row whose phase misses 2 pi n/q by far more than the catalog's 1e-10 is refused
def test_a_row_that_misses_its_level_by_1e_8_is_refused():
    from orbits.search import RESIDUAL_TOLERANCE

    row = next(orbits.closed_orbits(FIG6, n_max=2).itertuples())
    target = 2 * math.pi * row.n / row.q
    # move dtheta until the phase misses by ~1e-8 relative (100x the tolerance)
    step = 1e-9 * abs(row.dtheta)
    for _ in range(60):
        moved = row._replace(dtheta=row.dtheta + step)
        miss = abs(float(orbits.total_phase(FIG6, dtheta=moved.dtheta)) - target) / target
        if miss > 1e-8:
            break
        step *= 2
    assert 50 * RESIDUAL_TOLERANCE < miss < 1e-6
    with pytest.raises(InputError, match="no closed orbit of the body drawn"):
        figures.check_orbits_of(FIG6, moved)
    figures.check_orbits_of(FIG6, row)  # the row itself is drawn


# M44: "no closed orbit" message gives the smallest total phase in turns (not radians)
def test_cli_no_orbit_message_states_turns(tmp_path, capsys):
    from orbits.cli import main

    # fig6: Delta alpha > 2 pi for every spin, and the n = 2 orbits exist, so
    # the smallest total phase is between 1 and 2 turns
    argv = ["figures", "--preset", "fig6", "--n-max", "1", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    found = re.search(r"smallest total phase is ([0-9.e+-]+) turns", err)
    assert found, err
    assert 1.0 < float(found.group(1)) < 2.0


# M45: the search estimate's row bound covers a real catalog (two orbits a level)
def test_search_estimate_row_bound_covers_a_real_catalog():
    from orbits import limits

    n_max = 10
    rows = len(orbits.closed_orbits(FIG6, n_max=n_max))  # n = 2..10, SAM and LAM: 18
    assert rows == 18
    one, _ = limits.search_estimate(n_max, 1, 1)
    none, _ = limits.search_estimate(n_max, 1, 0)
    bound = (one - none - limits._BYTES_PER_BODY) / limits._BYTES_PER_ROW
    assert bound >= rows


# M06, M22: Fig. 3 states the T-handle's moments and its period (4 decimals)
def test_fig3_states_the_moments_and_the_period():
    figure = figures.figure3()
    moments = _numbers(figure._suptitle.get_text())
    np.testing.assert_allclose(moments, Body.preset("t-handle").normalized_moments, atol=5e-7)
    period = orbits.Motion.from_spin(Body.preset("t-handle"), **figures.T_HANDLE_SPIN).period
    labels = [
        t.get_text()
        for ax in figure.get_axes()
        for child in ax.child_axes
        for t in child.get_xticklabels()
        if t.get_text().startswith("T = ")
    ]
    assert labels == [f"T = {period:.4f} s"]


# M07: Fig. 1 (b) gives the equivalent ellipsoid's (a, b, c) in order
def test_fig1_states_the_semi_axes_in_order():
    figure = figures.figure1()
    title = figure.get_axes()[1].get_title()
    a, b, c = _numbers(title.split("=")[-1])
    want = Body.t_handle(8.0, 4.0, 1.0).equivalent_ellipsoid()
    np.testing.assert_allclose((a, b, c), want, atol=6e-6)
    assert a > b > c


# M05, M40, M08: contact sheet labels on the outer panels; every curve inside its view
def test_contact_sheet_labels_and_view(fig6_catalog):
    sheet = figures.contact_sheet(FIG6, fig6_catalog, columns=3)  # 7 panels: 3 rows
    axes = [ax for ax in sheet.get_axes()]
    grid = np.array(axes[:9]).reshape(3, 3)
    for r in range(3):
        assert "omega_y" in grid[r, 0].get_ylabel()
        assert all(grid[r, c].get_ylabel() == "" for c in (1, 2))
    # x labels under the lowest drawn panel of each column: row 2 col 0, row 1 cols 1-2
    assert "omega_x" in grid[2, 0].get_xlabel()
    assert "omega_x" in grid[1, 1].get_xlabel() and "omega_x" in grid[1, 2].get_xlabel()
    for ax in axes[:7]:
        xy = ax.get_lines()[0].get_xydata()
        lo, hi = ax.get_xlim()
        assert np.abs(xy).max() < hi and -hi == lo


# M03: Fig. 6's inset titles give theta to 4 decimals
def test_fig6_inset_titles_give_theta():
    figure = figures.figure6()
    for inset, row in figure.insets:
        theta = re.search(r"\$\\theta\$=([0-9.]+)", inset.get_title()).group(1)
        assert len(theta.split(".")[1]) == 4 and abs(float(theta) - row.theta) <= 5e-5


def _numbers(text):
    return [float(x) for x in re.findall(r"-?\d+\.\d+(?:e[+-]?\d+)?", text)]
