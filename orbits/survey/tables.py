"""Survey tables on disk: writing and reading the parts, and the tables they make.

Each chunk has two parts, ``DIR/bodies/part-NNNNN.FMT`` and
``DIR/orbits/part-NNNNN.FMT`` (Parquet or CSV), written atomically and never
through a symbolic link.  :func:`read_table` reads only the parts in the
ledger (:mod:`orbits.survey.ledger`), checks each against its entry, and
joins them.
"""

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .._args import flag
from ..atomic import (
    FLOAT_FORMAT,
    csv_float_options,
    read_bytes_nofollow,
    write_bytes_atomic,
    write_bytes_under,
)
from ..cells import neutralize, unneutralize
from ..errors import InputError
from ..search import CATALOG_COLUMNS
from .compute import BODY_COLUMNS, CATEGORIES, UNIT_COLUMNS, as_frame, derive_orbit_rows
from .ledger import check_parts, entry_problem, load_manifest, missing_chunks, one_line


def require_pyarrow():
    if not have_pyarrow():
        raise InputError("--format parquet needs pyarrow: pip install 'orbits[parquet]'")


def write_part(table, path, fmt, engine=None, root=None):
    """Write one table part atomically; return the SHA-256 (hex) of its bytes.

    Parameters
    ----------
    table : dict or pandas.DataFrame
        Column name to 1-d array, in order, as
        :func:`orbits.survey.compute.chunk_columns` makes them (columns
        named in :data:`~orbits.survey.compute.CATEGORIES` hold codes), or
        a DataFrame.
    path : path
    fmt : {"parquet", "csv"}
    engine : {"arrow", "pandas"}, optional
        The CSV writer (default: pyarrow's).
    root : path, optional
        The survey's directory, which ``path`` lies in: no directory from
        it down to the part is followed if it is a link
        (:func:`orbits.atomic.write_bytes_under`), even one swapped in
        while the survey runs.

    Notes
    -----
    The part is made in memory, hashed there and written with one call
    (:func:`orbits.atomic.write_bytes_atomic`): the ledger's hash is that
    of the bytes on disk without reading them back.  The Arrow table is
    built from the columns' buffers on this thread (:func:`arrow_table`:
    no pandas, and none of the thread pool pyarrow's own conversion starts
    for every table while the survey writes its chunks side by side).
    Parquet parts carry a plain Arrow schema, without pandas' metadata;
    ``pandas.read_parquet`` reads them back with the same types (the
    branch a categorical; tests/test_survey.py checks it).

    CSV goes through pyarrow's writer (ten times faster than pandas here,
    and like it writes the shortest decimal that reads back to the same
    double), or through pandas with ``engine="pandas"``.  Names are
    neutralised against spreadsheet formulas (:func:`orbits.cells.neutralize`).
    """
    import hashlib

    if engine is None:
        engine = "arrow" if have_pyarrow() else "pandas"
    if not isinstance(engine, str) or engine not in ("arrow", "pandas"):
        raise InputError(f"engine must be 'arrow' or 'pandas', got {engine!r}")
    if fmt == "csv" and "name" in table:  # a key, or a DataFrame's column
        names = [neutralize(str(v)) for v in table["name"]]
        if isinstance(table, Mapping):
            table = {**table, "name": names}
        else:
            table = table.assign(name=names)
    if fmt == "parquet" or engine == "arrow":
        import pyarrow as pa

        arrow = arrow_table(table)
        sink = pa.BufferOutputStream()
        if fmt == "parquet":
            import pyarrow.parquet as pq

            # dictionary pages only for text columns: on doubles they never
            # pay off and cost pyarrow ~4x the write time
            text = [
                field.name
                for field in arrow.schema
                if not pa.types.is_integer(field.type)
                and not pa.types.is_floating(field.type)
                and not pa.types.is_boolean(field.type)
            ]
            pq.write_table(arrow, sink, compression="snappy", use_dictionary=text)
        else:
            from pyarrow.csv import write_csv

            write_csv(arrow, sink)
        data = memoryview(sink.getvalue())
    else:
        frame = as_frame(table)
        data = frame.to_csv(index=False, float_format=FLOAT_FORMAT).encode("utf-8")
    digest = hashlib.sha256(data).hexdigest()
    if root is None:
        write_bytes_atomic(path, data)
    else:
        write_bytes_under(root, Path(path).relative_to(root), data)
    return digest


def arrow_table(table):
    """A part's Arrow table, built from buffers: pyarrow never loads pandas here.

    ``pyarrow.array`` and ``Table.from_pandas`` import pandas on their
    first call (to test for pandas objects), a tenth of a second and more
    of a survey's serial start-up; the columns here go in as buffers.
    Numbers and booleans keep their type (int8/int64, float64, bool; NaN
    stays NaN, never null); text is ``large_string``; a column named in
    :data:`~orbits.survey.compute.CATEGORIES` (codes) is a dictionary of
    its labels with int8 indices, as a pandas categorical.  A DataFrame is
    taken apart the same way (its categoricals by their codes), so a table
    gives the same bytes as arrays or as a DataFrame.

    Raises
    ------
    InputError
        A column that is neither numbers, booleans, text (``str``) nor a
        categorical of text, is not 1-d, or is a nullable column holding
        missing values; columns of different lengths.
    """
    import pyarrow as pa

    names, arrays = [], []
    for name, values in _columns(table):
        names.append(name)
        arrays.append(_arrow_array(name, values))
    lengths = {len(array) for array in arrays}
    if len(lengths) > 1:
        raise InputError(f"the columns have different lengths ({sorted(lengths)}): not a table")
    return pa.Table.from_arrays(arrays, names=names)


def _columns(table):
    """(name, values) of each column: arrays, lists, or (codes, labels) pairs."""
    if isinstance(table, Mapping):
        for name, values in table.items():
            yield name, (values, CATEGORIES[name]) if name in CATEGORIES else values
        return
    for name in table.columns:  # a DataFrame
        column = table[name]
        if column.dtype.name == "category":
            yield name, (column.cat.codes.to_numpy(), [str(v) for v in column.cat.categories])
        elif column.dtype.kind in "biuf":
            if not isinstance(column.dtype, np.dtype):  # pandas' nullable Int64, boolean, ...
                if column.isna().any():
                    raise InputError(f"column {name!r} has missing values: not a table column")
                yield name, column.to_numpy(dtype=column.dtype.numpy_dtype)
            else:
                yield name, column.to_numpy()
        else:
            yield name, column.tolist()


def _arrow_array(name, values):
    import pyarrow as pa

    if isinstance(values, np.ndarray) and values.ndim != 1:
        raise InputError(f"column {name!r} has shape {values.shape}: a column is 1-d")
    if isinstance(values, tuple):  # codes into labels
        codes, labels = values
        codes = np.asarray(codes)
        if codes.ndim != 1 or codes.dtype.kind not in "iu":
            raise InputError(f"column {name!r} needs 1-d integer codes, got {codes.dtype}")
        if codes.size and (codes.min() < 0 or codes.max() >= len(labels)):
            raise InputError(f"column {name!r} has codes outside its {len(labels)} labels")
        return pa.DictionaryArray.from_arrays(
            _number_array(codes.astype(np.int8)), _text_array(labels)
        )
    if isinstance(values, np.ndarray) and values.dtype.kind in "biuf":
        return _number_array(values)
    texts = list(values)
    if not all(isinstance(text, str) for text in texts):
        kind = values.dtype if isinstance(values, np.ndarray) else "values"
        raise InputError(f"column {name!r} holds {kind} that are not text: not a table column")
    return _text_array(texts)


def _number_array(values):
    import pyarrow as pa

    values = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("="))
    if values.dtype == np.bool_:  # Arrow packs booleans, least significant bit first
        bits = np.packbits(values, bitorder="little")
        return pa.Array.from_buffers(pa.bool_(), values.size, [None, pa.py_buffer(bits)])
    kind = pa.from_numpy_dtype(values.dtype)
    return pa.Array.from_buffers(kind, values.size, [None, pa.py_buffer(values)])


def _text_array(strings):
    import pyarrow as pa

    encoded = [text.encode("utf-8") for text in strings]
    offsets = np.zeros(len(encoded) + 1, dtype=np.int64)
    np.cumsum([len(text) for text in encoded], out=offsets[1:])
    buffers = [None, pa.py_buffer(offsets), pa.py_buffer(b"".join(encoded))]
    return pa.Array.from_buffers(pa.large_string(), len(encoded), buffers)


def have_pyarrow():
    from importlib.util import find_spec

    return find_spec("pyarrow") is not None


def _csv_dtypes():
    types = {name: np.float64 for name in BODY_COLUMNS + CATALOG_COLUMNS + UNIT_COLUMNS}
    types.update(
        {
            name: np.int64
            for name in ("body", "orbits", "n_smallest", "n_largest", "unresolved", "n", "q")
        }
    )
    types.update(name=str, branch=str, closes_after=str, min_at_end=object)
    return types


_CSV_DTYPES = _csv_dtypes()


def read_part(path):
    import io

    import pandas as pd

    data = io.BytesIO(read_bytes_nofollow(path))  # never through a link
    if path.suffix == ".parquet":
        return pd.read_parquet(data)
    # Types by schema, not by inference: a part whose float column holds only
    # "-0" or "0" would otherwise come back as integers (losing the sign).
    frame = pd.read_csv(data, dtype=_CSV_DTYPES, keep_default_na=False, **csv_float_options())
    if "name" in frame.columns:
        frame["name"] = frame["name"].map(unneutralize).astype(frame["name"].dtype)
    if "min_at_end" in frame.columns and frame["min_at_end"].dtype == object:
        frame["min_at_end"] = frame["min_at_end"].map(
            {"true": True, "false": False, "True": True, "False": False}
        )
    return frame


def read_table(out_dir, table, verify=True):
    """One table of a survey directory (``"bodies"`` or ``"orbits"``), all parts.

    Only the parts in the manifest's ledger are read, in order; other files
    in the directory are ignored.

    Raises
    ------
    InputError
        Not a survey directory, incomplete (a chunk the run never wrote,
        whatever ``verify``), or (with ``verify``) a part that is missing or
        does not match its SHA-256.
    """
    import pandas as pd

    if not isinstance(table, str) or table not in ("bodies", "orbits"):
        raise InputError(f"table must be 'bodies' or 'orbits', got {table!r}")
    verify = flag("verify", verify)
    document = load_manifest(out_dir)
    if verify:
        status = check_parts(out_dir)
    else:
        # the parts are not hashed, but an interrupted run's directory
        # (chunks never written) is refused all the same: a partial table
        # would pass for the survey
        missing = missing_chunks(document)
        status = {"damaged": [], "missing": missing, "complete": not missing}
    if not status["complete"]:
        problems = status["damaged"] + [f"{m} missing" for m in status["missing"]]
        raise InputError(
            f"{out_dir} is damaged or incomplete ({len(problems)} "
            f"problem(s), first: {problems[0]}); rerun the survey command "
            "to recompute, or check it with 'orbits survey --check'"
        )
    ledger, parameters = document["parts"], document["parameters"]
    compact = parameters.get("columns", "all") == "compact"  # format 2: all
    frames = []
    for key in sorted(ledger, key=int):
        entry = ledger[key]
        problem = entry_problem(key, entry, parameters)
        if problem:
            raise InputError(f"{out_dir}: chunk {key}: {problem}")
        frame = _read_checked(out_dir, key, table, entry, parameters)
        if compact and table == "bodies":
            frame = frame.drop(columns=list(UNIT_COLUMNS))
        elif compact:
            bodies = _read_checked(out_dir, key, "bodies", entry, parameters)
            try:
                frame = derive_orbit_rows(
                    frame,
                    bodies[list(UNIT_COLUMNS)].to_numpy(dtype=float),
                    entry["first_body"],
                    parameters["n_max"],
                    parameters["q_max"],
                )
            except (KeyError, ValueError, TypeError) as error:
                raise InputError(f"{out_dir}: chunk {key} is damaged: {one_line(error)}") from None
            except InputError as error:
                raise InputError(f"{out_dir}: chunk {key} of orbits: {error}") from None
        frames.append(frame)
    if not frames:
        raise InputError(f"no {table} table in {out_dir}")
    return pd.concat(frames, ignore_index=True)


def _read_checked(out_dir, key, table, entry, parameters):
    """One part, read and checked against its ledger entry (rows, body ids)."""
    try:
        frame = read_part(Path(out_dir) / entry[table]["file"])
        problem = _rows_problem(frame, table, entry, parameters)
        if problem:
            raise InputError(f"{out_dir}: chunk {key} of {table}: {problem}")
        return frame
    except InputError:
        raise
    except (OSError, ValueError, KeyError) as error:
        raise InputError(
            f"{out_dir}: cannot read chunk {key} of {table}: {one_line(error)}"
        ) from None
    except Exception as error:  # noqa: BLE001 - pyarrow's own errors
        raise InputError(
            f"{out_dir}: chunk {key} of {table} is damaged: {one_line(error)}"
        ) from None


def _rows_problem(frame, table, entry, parameters):
    """A part's rows against its ledger entry: count and body ids ('' if they agree)."""
    if len(frame) != entry[table]["rows"]:
        return f"{len(frame)} rows, the ledger says {entry[table]['rows']}"
    if "body" not in frame.columns:
        return "no body column"
    body = frame["body"].to_numpy()
    first, last = entry["first_body"], entry["last_body"]
    if table == "bodies":
        if not np.array_equal(body, np.arange(first, last + 1)):
            return f"its body ids are not the chunk's {first}..{last}"
    elif len(body) and (body.min() < first or body.max() > last or (np.diff(body) < 0).any()):
        return f"its orbits are not of the chunk's bodies {first}..{last}"
    return ""


def read_survey(out_dir, verify=True):
    """``(bodies, orbits)`` DataFrames of a complete, verified survey directory.

    The orbits have every catalog column (a compact survey's are derived
    here), bit for bit those of :func:`orbits.catalog` of the moments the
    survey was given (the grid of :func:`orbits.region_grid`, or the bodies
    of a list); ``bodies``' ``I1, I2, I3`` are ``I/|I|`` rounded to doubles,
    within an ulp of those, so :func:`orbits.catalog` of them agrees with
    the orbit rows only to the moments' rounding (measured on a grid of 40:
    total phase and period within 2e-15 relative; theta, m and the
    geometric phase, ill-conditioned where small, within 7e-14), not to
    the last bit.

    Raises
    ------
    InputError
        Not a survey directory, incomplete, or damaged (a part missing,
        changed or truncated: each is checked against the ledger's SHA-256).
    """
    bodies = read_table(out_dir, "bodies", verify)
    table = read_table(out_dir, "orbits", verify)
    if len(table) != int(bodies["orbits"].sum()):
        raise InputError(
            f"{out_dir}: {len(table)} orbit rows, but the bodies table counts "
            f"{int(bodies['orbits'].sum())}; rerun the survey into a new directory"
        )
    return bodies, table


def survey_grid(out_dir):
    """The Fig. 2 data (i1, i2, minimum) of a grid survey.

    Raises
    ------
    InputError
        Not a survey directory, damaged, not complete, or not a grid survey.
    """
    parameters = load_manifest(out_dir)["parameters"]
    grid = parameters["bodies"]
    resolution = grid.get("grid") if isinstance(grid, dict) else None
    if not isinstance(resolution, int) or resolution < 2:
        raise InputError(f"{out_dir} surveys a list of bodies; Fig. 2 needs a grid survey")
    bodies = read_table(out_dir, "bodies")
    if len(bodies) != parameters["body_count"]:
        raise InputError(f"{out_dir}: the survey is not complete")
    from ..bodies import REGION_BOX

    (lo1, hi1), (lo2, hi2) = REGION_BOX
    # grid cells are centred: i = lo + (k + 1/2) (hi - lo) / N
    k1 = np.rint((bodies["I1"].to_numpy() - lo1) / (hi1 - lo1) * resolution - 0.5).astype(int)
    k2 = np.rint((bodies["I2"].to_numpy() - lo2) / (hi2 - lo2) * resolution - 0.5).astype(int)
    if k1.min() < 0 or k2.min() < 0 or k1.max() >= resolution or k2.max() >= resolution:
        raise InputError(f"{out_dir}: bodies outside the grid of the manifest")
    axis1 = lo1 + (np.arange(resolution) + 0.5) * (hi1 - lo1) / resolution
    axis2 = lo2 + (np.arange(resolution) + 0.5) * (hi2 - lo2) / resolution
    i1, i2 = np.meshgrid(axis1, axis2, indexing="xy")
    minimum = np.full(i1.shape, np.nan)
    minimum[k2, k1] = bodies["min_total_phase"].to_numpy()
    return i1, i2, minimum
