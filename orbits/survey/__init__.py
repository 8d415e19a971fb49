"""Body-space survey: closed orbits and minimum phases over many bodies.

A survey covers the region of physical asymmetric bodies in the paper's
I1-I2 plane (``|I| = 1``), or an explicit list, and writes a directory::

    DIR/manifest.json          parameters (a rerun must match them), ledger, SHA-256
    DIR/bodies/part-NNNNN.parquet  one row per body (or .csv)
    DIR/orbits/part-NNNNN.parquet  the closed orbits
    DIR/report.json            summary and the minimum-at-the-ends test

By default (``columns="compact"``) an orbit row keeps only what cannot be
recomputed cheaply -- body, branch, n, q, dtheta -- and the bodies table
also each body's canonical moments; :func:`read_survey` derives every other
catalog column on read, bit for bit those of :func:`orbits.catalog` of the
moments the survey was given (its grid, :func:`orbits.region_grid`, or its
list); the bodies table's ``I1, I2, I3`` are ``I/|I|`` rounded, within an
ulp of those, so :func:`orbits.catalog` of a row's ``I1, I2, I3`` agrees
only to the moments' rounding, not to the last bit.  About 570 bytes per
body at n <= 30 in Parquet, against about 4,100 with ``columns="all"``,
which keeps the full catalog rows on disk.

The bodies are cut into chunks; each finished chunk is written atomically
(orbits, then bodies), and then recorded in the manifest's ledger (file
names, row counts, body-id range, SHA-256 of each part).  A chunk is done
exactly when its ledger entry matches its files: a rerun checks every part,
recomputes the missing or damaged ones and never reads a file that is not
in the ledger.  The manifest carries the SHA-256 of its own canonical JSON
(a hand edit is damage), and no symbolic link inside the directory is ever
followed.  One run at a time holds the directory (``fcntl`` lock).

Chunks run in-process -- the search on all cores (numba), each searched
chunk's tables, files and hashes on a pool of threads beside it -- or on a
``dask.distributed`` cluster (``scheduler="tcp://host:port"`` or a
``Client``): the same functions compute each chunk there and the results
come back to be written here, so both engines write identical files.  The
tables are made and written from arrays (:func:`chunk_columns`, pyarrow):
a survey run does not load pandas; :func:`read_survey` gives DataFrames.

The package's modules, bottom to top:

* :mod:`orbits.survey.ledger`: the manifest, its ledger and checksum, the
  lock, verification of a directory (:func:`check_survey`);
* :mod:`orbits.survey.compute`: one chunk of bodies to its tables, and the
  survey's cost (:func:`compute_chunk`, :func:`check_survey_bounds`);
* :mod:`orbits.survey.tables`: the parts on disk (:func:`read_survey`);
* :mod:`orbits.survey.report`: ``report.json``;
* :mod:`orbits.survey.runner`: :class:`Survey`, which runs them.
"""

from .compute import (
    BODY_COLUMNS,
    CATEGORIES,
    COMPACT_COLUMNS,
    GRID_INSIDE,
    LAYOUTS,
    UNIT_COLUMNS,
    check_survey_bounds,
    chunk_columns,
    chunk_tables,
    compute_chunk,
    derive_orbit_rows,
    search_chunk,
    survey_estimate,
)
from .ledger import (
    FORMATS,
    LOCK,
    MANIFEST,
    REPORT,
    SURVEY_FORMAT,
    TABLES,
    Ledger,
    check_parts,
    check_unlocked,
    chunk_bounds,
    load_manifest,
    manifest_checksum,
    part_name,
    refuse_links,
    sha256_file,
)
from .report import check_report, check_survey, survey_report
from .runner import CONNECT_TIMEOUT, DEFAULT_CHUNK, Survey
from .tables import read_part, read_survey, read_table, survey_grid, write_part

__all__ = [
    "BODY_COLUMNS",
    "CATEGORIES",
    "COMPACT_COLUMNS",
    "LAYOUTS",
    "UNIT_COLUMNS",
    "chunk_columns",
    "chunk_tables",
    "derive_orbit_rows",
    "search_chunk",
    "CONNECT_TIMEOUT",
    "DEFAULT_CHUNK",
    "FORMATS",
    "GRID_INSIDE",
    "LOCK",
    "MANIFEST",
    "REPORT",
    "SURVEY_FORMAT",
    "TABLES",
    "Ledger",
    "Survey",
    "check_parts",
    "check_report",
    "check_survey",
    "check_survey_bounds",
    "check_unlocked",
    "chunk_bounds",
    "compute_chunk",
    "load_manifest",
    "manifest_checksum",
    "part_name",
    "read_part",
    "read_survey",
    "read_table",
    "refuse_links",
    "sha256_file",
    "survey_estimate",
    "survey_grid",
    "survey_report",
    "write_part",
]
