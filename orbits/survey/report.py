"""The survey's report: its summary and the minimum-at-the-ends test, ``report.json``."""

import json
from pathlib import Path

from ..atomic import write_text_atomic
from .ledger import REPORT, load_manifest
from .tables import read_table

# the columns of each counterexample to the minimum-at-the-ends conjecture
COUNTEREXAMPLE_COLUMNS = ("body", "I1", "I2", "I3", "min_total_phase", "min_theta")


def bodies_summary(bodies):
    """The report's figures of one bodies table: a chunk's or a whole survey's.

    Summaries of consecutive chunks combine (:func:`combined_summary`) into
    the summary of their union, so a run can report on the chunks it has
    just written without reading them back.

    Parameters
    ----------
    bodies : pandas.DataFrame
        The columns of :data:`orbits.survey.BODY_COLUMNS`.

    Returns
    -------
    dict
        ``bodies``, ``orbits``, ``two_pi``, ``unresolved`` (counts),
        ``min``, ``max`` (of ``min_total_phase``, rad) and
        ``counterexamples`` (records of the bodies whose minimum is not at
        an end, in the table's order).
    """
    failed = bodies[~bodies["min_at_end"].astype(bool)]
    return {
        "bodies": int(len(bodies)),
        "orbits": int(bodies["orbits"].sum()),
        "counterexamples": failed[list(COUNTEREXAMPLE_COLUMNS)].to_dict("records"),
        "two_pi": int((bodies["n_smallest"] == 1).sum()),
        "min": float(bodies["min_total_phase"].min()),
        "max": float(bodies["min_total_phase"].max()),
        "unresolved": int((bodies["unresolved"] > 0).sum()),
    }


def combined_summary(summaries):
    """One :func:`bodies_summary` of consecutive tables' summaries (given in order)."""
    import pandas as pd

    return {
        "bodies": sum(s["bodies"] for s in summaries),
        "orbits": sum(s["orbits"] for s in summaries),
        "counterexamples": [row for s in summaries for row in s["counterexamples"]],
        "two_pi": sum(s["two_pi"] for s in summaries),
        # pandas' reductions, as on the whole column (NaN skipped)
        "min": float(pd.Series([s["min"] for s in summaries], dtype=float).min()),
        "max": float(pd.Series([s["max"] for s in summaries], dtype=float).max()),
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
    keys = None
    if summaries and not verify:
        keys = sorted(int(key) for key in load_manifest(out_dir)["parts"])
    if keys and all(key in summaries for key in keys):
        summary = combined_summary([summaries[key] for key in keys])
    else:
        summary = bodies_summary(read_table(out_dir, "bodies", verify=verify))
    report = {
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
    write_text_atomic(out_dir / REPORT, json.dumps(report, indent=2) + "\n")
    return report
