"""Survey tables: the default (pyarrow) CSV writer and Parquet are exact.

pyarrow is a core dependency, so the fast writer is what every install
uses.  Its CSV floats are the shortest decimal that reads back to the same
double; these tests check the round trip bit for bit over arbitrary
doubles, including subnormals, signed zeros and the extreme exponents.
"""

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from orbits.survey import read_part, write_part

finite_doubles = st.floats(allow_nan=False, allow_infinity=False, width=64)
special = st.sampled_from(
    [
        0.0,
        -0.0,
        5e-324,
        -5e-324,
        2.2250738585072014e-308,
        2.225073858507201e-308,
        1.7976931348623157e308,
        -1.7976931348623157e308,
        0.1,
        1.0 / 3.0,
        9007199254740993.0,
    ]
)


def _bits(values):
    return np.asarray(values, dtype=np.float64).view(np.int64)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.one_of(finite_doubles, special), min_size=1, max_size=300))
def test_csv_round_trip_is_bit_exact(tmp_path_factory, values):
    path = tmp_path_factory.mktemp("csv") / "part.csv"
    # a real float column of the survey schema, read back by the survey's reader
    frame = pd.DataFrame(
        {
            "min_total_phase": np.array(values, dtype=np.float64),
            "orbits": np.arange(len(values), dtype=np.int64),
        }
    )
    write_part(frame, path, "csv")
    again = read_part(path)
    np.testing.assert_array_equal(_bits(again["min_total_phase"]), _bits(frame["min_total_phase"]))
    np.testing.assert_array_equal(again["orbits"], frame["orbits"])


def test_csv_signed_zero_alone_stays_float(tmp_path):
    # the CI failure: a column holding only -0.0 was read back as integer 0
    frame = pd.DataFrame({"min_dtheta": [-0.0], "body": [7]})
    write_part(frame, tmp_path / "z.csv", "csv")
    again = read_part(tmp_path / "z.csv")
    assert again["min_dtheta"].dtype == np.float64
    assert _bits(again["min_dtheta"])[0] == _bits([-0.0])[0]


@settings(max_examples=20, deadline=None)
@given(st.lists(st.one_of(finite_doubles, special), min_size=1, max_size=300))
def test_parquet_round_trip_is_bit_exact(tmp_path_factory, values):
    path = tmp_path_factory.mktemp("pq") / "part.parquet"
    frame = pd.DataFrame({"x": np.array(values, dtype=np.float64)})
    write_part(frame, path, "parquet")
    np.testing.assert_array_equal(_bits(pd.read_parquet(path)["x"]), _bits(frame["x"]))


def test_csv_writer_bits_on_random_bit_patterns(tmp_path):
    # every finite double is equally likely here (uniform over bit patterns)
    rng = np.random.default_rng(13)
    bits = rng.integers(0, 2**63, size=200_000, dtype=np.int64)
    bits[rng.random(bits.size) < 0.5] |= np.int64(-(2**63))
    values = bits.view(np.float64)
    values = values[np.isfinite(values)]
    frame = pd.DataFrame({"x": values})
    write_part(frame, tmp_path / "b.csv", "csv")
    from orbits.atomic import csv_float_options

    again = pd.read_csv(tmp_path / "b.csv", dtype={"x": np.float64}, **csv_float_options())
    np.testing.assert_array_equal(_bits(again["x"]), _bits(values))
