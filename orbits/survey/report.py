"""The survey's report: its summary and the minimum-at-the-ends test, ``report.json``."""

import json
from pathlib import Path

from ..atomic import write_text_atomic
from .ledger import REPORT
from .tables import read_table


def survey_report(out_dir, n_max, q_max, skipped_rows, verify=True):
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

    Raises
    ------
    InputError
        Not a complete, verified survey.
    """
    out_dir = Path(out_dir)
    bodies = read_table(out_dir, "bodies", verify=verify)
    failed = bodies[~bodies["min_at_end"].astype(bool)]
    report = {
        "bodies": int(len(bodies)),
        "orbits": int(bodies["orbits"].sum()),
        "n_max": n_max,
        "q_max": q_max,
        "conjecture_minimum_at_the_ends": {
            "held_on_every_body": bool(failed.empty),
            "counterexamples": failed[
                ["body", "I1", "I2", "I3", "min_total_phase", "min_theta"]
            ].to_dict("records"),
        },
        "bodies_with_a_two_pi_orbit": int((bodies["n_smallest"] == 1).sum()),
        "min_total_phase_range": [
            float(bodies["min_total_phase"].min()),
            float(bodies["min_total_phase"].max()),
        ],
        "bodies_with_unresolved_orbits": int((bodies["unresolved"] > 0).sum()),
        "skipped_rows": int(skipped_rows),
    }
    write_text_atomic(out_dir / REPORT, json.dumps(report, indent=2) + "\n", follow_links=False)
    return report
