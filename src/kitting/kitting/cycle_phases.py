"""Where a pick's cycle goes: the phases of one pick (``KittingPicker`` times them) and
their summary over a campaign (``kitting_trials`` puts it into kitting_summary.json).

A pick, in order:

- ``approach``: from where the last pick left the arm (above its slot) to the hover point
  above the intercept;
- ``wait``: at the hover point until the descent must start (magnet on, re-planned from
  the newest sighting);
- ``descent``: onto the part, with the belt;
- ``lift``: straight up off the belt;
- ``carry``: from the lift point to above the part's slot (the camera's miss check runs
  meanwhile);
- ``check``: above the slot, waiting for the miss check's images beyond the carry (0 when
  the carry took longer than the check needs);
- ``release``: down into the slot, magnet off, back up.
"""

import math

import numpy as np

__all__ = ["PHASES", "phase_summary"]

PHASES = ("approach", "wait", "descent", "lift", "carry", "check", "release")


def phase_summary(picks) -> dict:
    """Per phase p50 / mean / p95 (s) over ``picks`` (mappings phase -> s; a phase a pick
    lacks is not counted), and the whole cycle's (the sum of a pick's phases)."""
    picks = [p for p in picks if p]
    out = {}
    for name in PHASES + ("cycle",):
        values = [sum(p.values()) if name == "cycle" else p[name] for p in picks if name == "cycle" or name in p]
        out[name] = (
            {
                "p50": float(np.percentile(values, 50)),
                "mean": float(np.mean(values)),
                "p95": float(np.percentile(values, 95)),
            }
            if values
            else {"p50": math.nan, "mean": math.nan, "p95": math.nan}
        )
    out["picks"] = len(picks)
    return out
