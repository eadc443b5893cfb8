"""Vectors as lists of Python floats, for the per-frame arithmetic on 3-, 4- and 6-vectors.

On the teleop chain's per-frame path (sequencer, core, dispatcher) numpy's per-call cost
on such small vectors exceeds the arithmetic when the caches are cold between two frames,
so that arithmetic runs on plain floats (bench/e2e_latency). Converting an array
is one tolist() call: iterating it instead yields numpy scalars, several times slower per
element.
"""

import numpy as np


def float_list(values) -> list:
    """``values`` (an array or any flat sequence of numbers) as a list of Python floats."""
    return [float(v) for v in (values.tolist() if isinstance(values, np.ndarray) else values)]
