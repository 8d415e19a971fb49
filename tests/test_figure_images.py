"""Image regression: the figures as drawn, against committed small baselines.

The baselines in ``tests/baseline/`` are PNGs at ``DPI`` = 40, written by
``tests/baseline/regenerate.py`` (run it after an intended change to a
figure, look at the new PNGs, commit them).  ``versions.txt`` there records
the matplotlib minor version and the FreeType version that drew them: text
rendering changes between those, so the comparison is skipped (with the
reason) on any other pair.

Tolerance: ``compare_images`` RMS of the pixel difference on the 0-255
scale, ``TOLERANCE`` = 1.0.  The same versions redraw these figures
byte-identically (RMS 0; the figures are deterministic).  Measured at this
size: Fig. 3's period label moved sideways by 1 s (2 % of the axis) gives
RMS 3.05, the same label lifted off the axes by 1 %, 20.8 (the layout
reflows); Fig. 6's legend moved by 5 % of the width, 6.69.  A one-digit
change of that label gives 0.34: the images guard the layout, the values
drawn are checked by the data tests (test_plotting, test_figures).
:func:`test_the_tolerance_catches_a_moved_label` checks the sideways move.
"""

import importlib.util
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.ft2font  # noqa: E402
import pytest  # noqa: E402
from matplotlib.testing.compare import compare_images  # noqa: E402

import orbits  # noqa: E402
from orbits import Body, figures  # noqa: E402

BASELINE = Path(__file__).parent / "baseline"
DPI = 40
TOLERANCE = 1.0


def _fig6_catalog():
    return orbits.closed_orbits(Body.preset("fig6"), n_max=6)


def _contact_sheet():
    return figures.contact_sheet(Body.preset("fig6"), _fig6_catalog())


def _odd_herpolhode():
    """An odd multiple (drawn over T/2) with all its marks."""
    table = _fig6_catalog()
    row = next(table[(table["n"] == 3) & (table["branch"] == "LAM")].itertuples())
    return figures.closed_herpolhode_figure(Body.preset("fig6"), row)


# name -> builder; the baselines are <name>.png
CASES = dict(figures.PAPER_FIGURES)
CASES.update(contact_sheet=_contact_sheet, herpolhode_LAM_n003=_odd_herpolhode)


def versions():
    """The (matplotlib minor, FreeType) pair that decides the rendering."""
    major, minor = matplotlib.__version__.split(".")[:2]
    return f"matplotlib {major}.{minor}; freetype {matplotlib.ft2font.__freetype_version__}"


def render(name, path):
    """Draw case ``name`` into ``path`` (PNG at DPI, deterministic metadata)."""
    figure = CASES[name]()
    figure.savefig(path, format="png", dpi=DPI, metadata={"Software": None})
    return path


def _recorded():
    stamp = BASELINE / "versions.txt"
    return stamp.read_text().strip() if stamp.exists() else None


def _skip_unless_same_versions():
    recorded = _recorded()
    if recorded is None:
        pytest.skip("no baselines recorded: run tests/baseline/regenerate.py")
    if recorded != versions():
        pytest.skip(
            f"baselines drawn with {recorded}, this is {versions()}: text "
            "rendering differs; regenerate with tests/baseline/regenerate.py"
        )


@pytest.mark.parametrize("name", list(CASES))
def test_figure_matches_its_baseline(name, tmp_path):
    _skip_unless_same_versions()
    expected = BASELINE / f"{name}.png"
    assert expected.exists(), f"missing baseline {expected}"
    actual = render(name, tmp_path / f"{name}.png")
    failure = compare_images(str(expected), str(actual), tol=TOLERANCE, in_decorator=True)
    assert failure is None, (
        f"{name}: RMS {failure['rms']:.2f} > {TOLERANCE}; diff image {failure['diff']}"
    )


def test_the_tolerance_catches_a_moved_label(tmp_path, monkeypatch):
    """Move Fig. 3's period label sideways by 1 s (2 % of the axis): the comparison fails."""
    _skip_unless_same_versions()
    from orbits import plotting

    original = plotting.plot_omega_components

    def moved(ax, *args, **kwargs):
        drawn = original(ax, *args, **kwargs)
        # the tick that names T, 1 s to the right of the period's line
        drawn["period_axis"].set_xticks([drawn["period"] + 1.0], [f"T = {drawn['period']:.4f} s"])
        return drawn

    monkeypatch.setattr(plotting, "plot_omega_components", moved)
    actual = render("fig3", tmp_path / "fig3.png")
    failure = compare_images(
        str(BASELINE / "fig3.png"), str(actual), tol=TOLERANCE, in_decorator=True
    )
    assert failure is not None and failure["rms"] > TOLERANCE


def test_the_regeneration_script_draws_these_cases():
    spec = importlib.util.spec_from_file_location("regenerate", BASELINE / "regenerate.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    assert script.cases() == list(CASES)
