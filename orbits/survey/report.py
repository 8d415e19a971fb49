"""The survey's report: its summary and the minimum-at-the-ends test, ``report.json``."""

import json
from pathlib import Path

import numpy as np

from ..atomic import read_bytes_nofollow, write_bytes_under
from ..errors import InputError
from .ledger import REPORT, check_parts, load_manifest
from .tables import read_table

TWO_PI = 2.0 * np.pi

# the columns of each counterexample to the minimum-at-the-ends conjecture
COUNTEREXAMPLE_COLUMNS = ("body", "I1", "I2", "I3", "min_total_phase", "min_theta")


def bodies_summary(bodies):
    """The report's figures of one bodies table: a chunk's or a whole survey's.

    Summaries of consecutive chunks combine (:func:`combined_summary`) into
    the summary of their union, so a run can report on the chunks it has
    just written without reading them back.

    Parameters
    ----------
    bodies : dict or pandas.DataFrame
        The columns of :data:`orbits.survey.BODY_COLUMNS` (arrays, as
        :func:`orbits.survey.compute.chunk_columns` makes them, or a
        DataFrame read back).

    Returns
    -------
    dict
        ``bodies``, ``orbits``, ``two_pi`` (bodies whose minimum phase is
        below 2 pi, so that a spin with ``Delta alpha = 2 pi`` exists: the
        level 2 pi is not searched), ``unresolved`` (counts),
        ``min``, ``max`` (of ``min_total_phase``, rad; NaN skipped, NaN
        when none) and ``counterexamples`` (records of the bodies whose
        minimum is not at an end, in the table's order).
    """
    at_end = np.asarray(bodies["min_at_end"]).astype(bool)
    minimum = np.asarray(bodies["min_total_phase"], dtype=float)
    # usually none: no records made (under the GIL)
    counterexamples = []
    if not at_end.all():
        inside = [np.asarray(bodies[name])[~at_end].tolist() for name in COUNTEREXAMPLE_COLUMNS]
        counterexamples = [dict(zip(COUNTEREXAMPLE_COLUMNS, row)) for row in zip(*inside)]
    return {
        "bodies": int(at_end.size),
        "orbits": int(np.asarray(bodies["orbits"]).sum()),
        "counterexamples": counterexamples,
        # a minimum below 2 pi (only possible inside a branch: the ends are
        # >= 2 pi) means some spin has Delta alpha = 2 pi exactly
        "two_pi": int((minimum < TWO_PI).sum()),
        "min": _skipping_nan(np.min, minimum),
        "max": _skipping_nan(np.max, minimum),
        "unresolved": int((np.asarray(bodies["unresolved"]) > 0).sum()),
    }


def _skipping_nan(reduce, values):
    """``reduce`` of the values that are not NaN (as pandas reduces a column); NaN if none."""
    values = values[~np.isnan(values)]
    return float(reduce(values)) if values.size else float("nan")


def combined_summary(summaries):
    """One :func:`bodies_summary` of consecutive tables' summaries (given in order)."""
    minima = np.array([s["min"] for s in summaries], dtype=float)
    maxima = np.array([s["max"] for s in summaries], dtype=float)
    return {
        "bodies": sum(s["bodies"] for s in summaries),
        "orbits": sum(s["orbits"] for s in summaries),
        "counterexamples": [row for s in summaries for row in s["counterexamples"]],
        "two_pi": sum(s["two_pi"] for s in summaries),
        "min": _skipping_nan(np.min, minima),
        "max": _skipping_nan(np.max, maxima),
        "unresolved": sum(s["unresolved"] for s in summaries),
    }


def survey_report(out_dir, n_max, q_max, skipped_rows, verify=True, summaries=None):
    """Summary of a complete survey from its parts; written to ``DIR/report.json``.

    Parameters
    ----------
    out_dir : path
    n_max, q_max : int
        The survey's parameters (reported as they are).
    skipped_rows : int
        Rows of the bodies file that were skipped (``--skip-invalid``).
    verify : bool
        Check every part against the ledger first (off when the caller has
        just verified or written each part under the lock).
    summaries : dict, optional
        :func:`bodies_summary` of chunks the caller has just written, by
        chunk index.  When they cover every chunk of the ledger (and
        ``verify`` is off) the parts are not read back; otherwise the
        bodies table is read.

    Raises
    ------
    InputError
        Not a complete, verified survey.
    """
    out_dir = Path(out_dir)
    report = build_report(out_dir, n_max, q_max, skipped_rows, verify, summaries)
    text = json.dumps(report, indent=2) + "\n"
    write_bytes_under(out_dir, REPORT, text.encode("utf-8"))
    return report


def build_report(out_dir, n_max, q_max, skipped_rows, verify=True, summaries=None):
    """The document :func:`survey_report` writes, computed without writing it."""
    out_dir = Path(out_dir)
    keys = None
    if summaries and not verify:
        keys = sorted(int(key) for key in load_manifest(out_dir)["parts"])
    if keys and all(key in summaries for key in keys):
        summary = combined_summary([summaries[key] for key in keys])
    else:
        summary = bodies_summary(read_table(out_dir, "bodies", verify=verify))
    return {
        "bodies": summary["bodies"],
        "orbits": summary["orbits"],
        "n_max": n_max,
        "q_max": q_max,
        "conjecture_minimum_at_the_ends": {
            "held_on_every_body": not summary["counterexamples"],
            "counterexamples": summary["counterexamples"],
        },
        "bodies_with_a_two_pi_orbit": summary["two_pi"],
        "min_total_phase_range": [summary["min"], summary["max"]],
        "bodies_with_unresolved_orbits": summary["unresolved"],
        "skipped_rows": int(skipped_rows),
    }


_RERUN = "rerun the survey command to rewrite it"


def _canonical(document):
    """Key order, indentation and float spelling are not content."""
    return json.dumps(document, sort_keys=True)


def check_report(out_dir, document=None):
    """The problem of ``DIR/report.json``, or '' if it is the report of the parts.

    The report is recomputed from the bodies table (read without hashing
    again: call this after :func:`~orbits.survey.ledger.check_parts` found
    every part intact) and compared, as JSON values, with the file.

    Returns
    -------
    str
        One line (``report.json is missing``, ``... differs from ...``,
        ...), ending with how to repair it; '' when it matches.
    """
    out_dir = Path(out_dir)
    if document is None:
        document = load_manifest(out_dir)
    parameters = document["parameters"]
    skipped = document.get("skipped_rows") or []
    expected = build_report(
        out_dir, parameters["n_max"], parameters["q_max"], len(skipped), verify=False
    )
    try:
        text = read_bytes_nofollow(out_dir / REPORT).decode("utf-8")
    except FileNotFoundError:
        return f"{REPORT} is missing; {_RERUN}"
    except UnicodeDecodeError:
        return f"{REPORT} is not valid JSON; {_RERUN}"
    except IsADirectoryError:  # damage, as a missing report (exit 1), not unreadable
        return f"{REPORT} is a directory, not the report; remove it and {_RERUN}"
    except OSError as error:
        raise InputError(f"cannot read {out_dir / REPORT}: {error.strerror}") from None
    try:
        found = json.loads(text)
    except ValueError:
        return f"{REPORT} is not valid JSON; {_RERUN}"
    # through JSON, as the file was written (tuples are lists, NaN is NaN)
    if _canonical(found) != _canonical(json.loads(json.dumps(expected))):
        keys = [
            key
            for key in expected
            if not isinstance(found, dict)
            or key not in found
            or _canonical(found[key]) != _canonical(json.loads(json.dumps(expected[key])))
        ]
        extra = [key for key in found if key not in expected] if isinstance(found, dict) else []
        what = ", ".join((keys + extra)[:3]) or "its layout"
        return f"{REPORT} differs from the report of the verified parts ({what}); {_RERUN}"
    return ""


def check_survey(out_dir):
    """Verify a survey directory without computing anything: parts and report.

    Every part is checked against its ledger entry (SHA-256); when all are
    intact, ``report.json`` is recomputed from the bodies table and
    compared with the file (a missing or different report is damage, and a
    rerun of the survey command rewrites it).

    Returns
    -------
    dict
        ``chunks`` (expected), ``verified`` (count), ``damaged`` and
        ``missing`` (lists of one-line descriptions; a problem with the
        report is listed under ``damaged``), ``report`` (``"ok"``, the
        report's problem, or ``"not checked"`` while parts are damaged or
        missing), ``complete`` (bool).

    Raises
    ------
    InputError
        Not a survey directory, its manifest is damaged, or a link.
    """
    document = load_manifest(out_dir)
    status = check_parts(out_dir)
    status["report"] = "not checked"
    if status["complete"]:
        problem = check_report(out_dir, document)
        status["report"] = problem or "ok"
        if problem:
            status["damaged"].append(problem)
            status["complete"] = False
    return status
