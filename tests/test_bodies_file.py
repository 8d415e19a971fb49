"""The strict ``--bodies`` reader: both parsers (pyarrow and the csv module) agree."""

import sys

import numpy as np
import pytest

import orbits
import orbits.catalog
import orbits.survey
from orbits.catalog import read_bodies_csv
from orbits.cli import main
from orbits.errors import InputError

pytest.importorskip("pyarrow")


@pytest.fixture(params=["arrow", "csv-module"])
def parser(request, monkeypatch):
    """Run each test with the pyarrow fast path and with the csv-module path."""
    module = sys.modules["orbits.catalog"]
    if request.param == "csv-module":
        monkeypatch.setattr(module, "_have_pyarrow", lambda: False)
    else:
        # these files need no fallback: the pyarrow path alone must read them
        def no_fallback(*args):
            raise AssertionError("fell back to the csv module")

        monkeypatch.setattr(module, "_python_cells", no_fallback)
    return request.param


def write(tmp_path, text):
    path = tmp_path / "b.csv"
    path.write_text(text)
    return path


def test_hash_inside_quoted_names_is_kept(tmp_path, parser):
    path = write(
        tmp_path, '# a comment\nI1,I2,I3,name\n0.26,0.55,0.793662,"body#1"\n0.3,0.5,0.7,"body#2"\n'
    )
    table = read_bodies_csv(path)
    assert table.names == ["body#1", "body#2"]
    np.testing.assert_array_equal(table.moments, [[0.26, 0.55, 0.793662], [0.3, 0.5, 0.7]])


def test_quoted_comma_and_newline_in_a_name(tmp_path, parser):
    path = write(tmp_path, 'name,I1,I2,I3\n"a, b",0.26,0.55,0.793662\n"two\nlines",1,2,2.5\n')
    table = read_bodies_csv(path)
    assert table.names == ["a, b", "two\nlines"]
    assert table.rows.tolist() == [1, 2]


def test_row_numbers_after_quoted_newlines_and_blank_lines(tmp_path, parser):
    path = write(
        tmp_path, 'name,I1,I2,I3\n"two\nlines",1,2,2.5\n\n"x",1,2\n"y",1,1,2\n"z",0.3,0.5,0.7\n'
    )
    table = read_bodies_csv(path, skip_invalid=True)
    assert table.names == ["two\nlines", "z"] and table.rows.tolist() == [1, 4]
    assert [message.split(": ", 1)[0] for _, message in table.skipped] == [
        f"{path}, row 2",
        f"{path}, row 3 ('y')",
    ]


def test_no_implicit_index_column(tmp_path, parser):
    path = write(tmp_path, "I1,I2,I3\n0.1,0.26,0.55,0.793662\n")
    with pytest.raises(InputError, match=r"row 1: 4 fields, the header has 3"):
        read_bodies_csv(path)


@pytest.mark.parametrize(
    "cell",
    ["True", "1_000", "0x10", "nan", "NaN", "inf", "-inf", "infinity", "", "1e", "1,5", "١"],
)
def test_cells_must_be_plain_decimal_numbers(tmp_path, parser, cell):
    text = f'I1,I2,I3\n0.26,0.55,0.793662\n"{cell}",1200,1500\n'
    with pytest.raises(InputError) as error:
        read_bodies_csv(write(tmp_path, text))
    message = str(error.value)
    assert message.count("row 2") == 1 and "row 1" not in message
    assert f"I1 {cell!r} is not a number" in message


def test_numbers_read_bit_for_bit(tmp_path, parser):
    """Each cell parses to the double Python's float() gives (correct rounding)."""
    rng = np.random.default_rng(7)
    values = np.sort(
        rng.uniform(0.2, 1.0, size=(300, 3)) * 10.0 ** rng.integers(-200, 200, size=(300, 1)),
        axis=1,
    )
    values[:, 2] = np.minimum(values[:, 2], 0.999 * (values[:, 0] + values[:, 1]))
    cells = [
        [repr(v), f"{v:.17g}", f"{v:.25e}", f"{v:.3f}"][k % 4]
        for k, v in enumerate(values.ravel().tolist())
    ]
    rows = ["{},{},{}".format(*cells[3 * k : 3 * k + 3]) for k in range(300)]
    path = write(tmp_path, "I1,I2,I3\n" + "\n".join(rows) + "\n")
    expected = np.array([float(c) for c in cells]).reshape(300, 3)
    keep = np.all(expected > 0, axis=1) & (expected[:, 2] < expected[:, 0] + expected[:, 1])
    table = read_bodies_csv(path, skip_invalid=True)
    np.testing.assert_array_equal(table.moments, expected[table.rows - 1])
    assert keep[table.rows - 1].all()


def test_one_message_per_bad_row_and_skip_invalid(tmp_path, parser):
    text = (
        "I1,I2,I3,name\n"
        '0.26,0.55,0.793662,"ok"\n'  # row 1
        '1,1,2,"symmetric"\n'  # row 2
        "\n"  # blank: not a row
        'True,2,2.5,"bool"\n'  # row 3
        '0.3,0.5,0.7,"ok2"\n'  # row 4
        "1,2,2.5\n"
    )  # row 5: 3 fields
    path = write(tmp_path, text)
    with pytest.raises(InputError, match=r"row 2 \('symmetric'\): .*; 2 more bad row"):
        read_bodies_csv(path)
    table = read_bodies_csv(path, skip_invalid=True)
    assert table.names == ["ok", "ok2"] and table.rows.tolist() == [1, 4]
    assert [row for row, _ in table.skipped] == [2, 3, 5]
    for row, message in table.skipped:
        assert message.count(f"row {row}") == 1
    note = f"skipped 3 invalid rows of {path} (--skip-invalid): 2, 3, 5"
    assert table.skipped_note() == [note]


def test_skip_invalid_on_the_command_line(tmp_path, capsys):
    path = write(
        tmp_path, 'I1,I2,I3,name\n0.26,0.55,0.793662,"=cmd|\' /C calc\'!A0"\n1,1,2,"bad"\n'
    )
    out = tmp_path / "c.csv"
    assert (
        main(
            ["catalog", "--bodies", str(path), "--skip-invalid", "--n-max", "3", "--out", str(out)]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert "skipped" in err and "row 2 ('bad')" in err
    text = out.read_text()
    assert "# skipped 1 invalid row " in text and "(--skip-invalid): 2" in text
    assert "\"'=cmd|' /C calc'!A0\"" in text  # neutralised in the file
    frame = orbits.read_catalog(out)
    assert set(frame["body"]) == {"=cmd|' /C calc'!A0"}  # and read back unchanged


def test_names_are_kept_through_a_survey(tmp_path):
    path = write(tmp_path, 'I1,I2,I3,name\n0.26,0.55,0.793662,"+SUM(1,2)"\n0.3,0.5,0.7,"b#2"\n')
    assert (
        main(
            [
                "survey",
                "--bodies",
                str(path),
                "--n-max",
                "3",
                "--format",
                "csv",
                "--out",
                str(tmp_path / "s"),
            ]
        )
        == 0
    )
    bodies, _ = orbits.survey.read_survey(tmp_path / "s")
    assert bodies["name"].tolist() == ["+SUM(1,2)", "b#2"]
    raw = (tmp_path / "s" / "bodies" / "part-00000.csv").read_text()
    assert "'+SUM(1,2)" in raw


def test_same_bodies_by_another_path_resume(tmp_path, monkeypatch, capsys):
    """Parameters are compared by meaning: ./b.csv and b.csv are the same bodies."""
    write(tmp_path, "I1,I2,I3\n0.26,0.55,0.793662\n0.3,0.5,0.7\n")
    monkeypatch.chdir(tmp_path)
    argv = ["survey", "--n-max", "3", "--format", "csv", "--out", "s", "--bodies"]
    assert main(argv + ["b.csv"]) == 0
    (tmp_path / "copy.csv").write_text("# same\nI1 , I2,I3\n0.26,0.55,0.793662\n0.3, 0.5,0.7\n")
    assert main(argv + ["./copy.csv"]) == 0
    assert "(0 computed now" in capsys.readouterr().out


# issue 20, item 5: an unclosed quote, rows swallowed into a name, subnormal moments
THREE = "0.26,0.55,0.793662,{0}a\n0.3,0.5,0.7,b\n0.2,0.6,0.75,c{1}\n"


def test_an_unclosed_quote_is_refused_with_its_line(tmp_path, parser):
    path = write(tmp_path, "# made by hand\n\nI1,I2,I3,name\n" + THREE.format('"', ""))
    with pytest.raises(InputError, match=r"b.csv, line 4: a quote opened on this line is never"):
        read_bodies_csv(path)


def test_a_lone_quote_inside_an_unquoted_name_is_text(tmp_path):
    # an odd number of quotes, but no quote left open (the csv-module path reads it)
    path = write(tmp_path, 'I1,I2,I3,name\n0.3,0.5,0.7,my 5" top\n0.26,0.55,0.793662,x\n')
    assert read_bodies_csv(path).names == ['my 5" top', "x"]


def test_rows_swallowed_into_a_name_are_refused(tmp_path, parser):
    path = write(tmp_path, "I1,I2,I3,name\n" + THREE.format('"', '"'))
    with pytest.raises(InputError, match="row 1 .*look like rows of bodies"):
        read_bodies_csv(path)


def test_subnormal_moments_are_refused_as_on_the_command_line(tmp_path, parser, capsys):
    path = write(tmp_path, "I1,I2,I3\n0.3,0.5,0.7\n1e-320,2e-320,2.5e-320\n0.3,4e-310,0.7\n")
    with pytest.raises(InputError, match=r"row 2: I1 1e-320 is below the smallest normal") as e:
        read_bodies_csv(path)
    assert "1 more bad row" in str(e.value)
    table = read_bodies_csv(path, skip_invalid=True)
    assert table.rows.tolist() == [1] and [row for row, _ in table.skipped] == [2, 3]
    assert "I2 4e-310" in table.skipped[1][1]
    # the same words as --moments
    assert main(["phase", "--moments", "1e-320", "2e-320", "2.5e-320", "--theta", "0.3"]) == 2
    assert "below the smallest normal double (2.2e-308)" in capsys.readouterr().err
    # the smallest normal double itself is a number like any other
    path = write(tmp_path, "I1,I2,I3\n2.2250738585072014e-308,4e-308,5e-308\n")
    np.testing.assert_array_equal(read_bodies_csv(path).moments[0, 0], sys.float_info.min)


def test_a_moment_that_reads_as_zero_is_named_as_typed(tmp_path, parser, capsys):
    """``1e-400`` reads as 0: the message said "moments (0, 2, 2.5) must all
    be positive", not what was typed (an audit); a typed zero still says that."""
    path = write(tmp_path, "I1,I2,I3\n1e-400,2,2.5\n")
    with pytest.raises(InputError, match=r"row 1: I1 1e-400 is below the smallest normal double"):
        read_bodies_csv(path)
    path = write(tmp_path, "I1,I2,I3\n0.0e5,2,2.5\n")
    with pytest.raises(InputError, match=r"moments \(0, 2, 2.5\) must all be positive"):
        read_bodies_csv(path)
    path = write(tmp_path, "I1,I2,I3\n-1e-400,2,2.5\n")
    with pytest.raises(InputError, match=r"I1 -1e-400 is negative and below the smallest normal"):
        read_bodies_csv(path)
    assert main(["phase", "--moments", "1e-400", "2", "2.5", "--theta", "0.3"]) == 2
    err = capsys.readouterr().err
    assert "'1e-400' is below the smallest normal double (2.2e-308): it reads as 0" in err
    assert main(["phase", "--moments", "-1e-400", "2", "2.5", "--theta", "0.3"]) == 2
    assert "'-1e-400' is negative and below" in capsys.readouterr().err
