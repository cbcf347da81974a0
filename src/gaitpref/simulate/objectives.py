"""The compass-gait objective of the paper's Fig. 2, as the authors' code has it.

Section "Optimizing the Compass-Gait Biped's Cost of Transport": the cost of transport (COT) of
gaits over step length at a fixed forward hip velocity of 0.2 m/s, lower is better.  The authors'
simulation code uses a 5th-degree polynomial fit in metres (``COT_COEFFICIENTS`` below): 0.0314 at
0.08 m, a minimum of about 0.0195 near 0.134 m, 0.0263 at 0.18 m.

(The synthetic 2-D objectives of Fig. 4 and the published curves are in :mod:`gaitpref.data`.)

Notation: ``x`` step length in metres; COT is dimensionless (J / (N m)).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.space import FloatArray

#: ``numpy.polyval`` coefficients (highest degree first) of the authors' COT fit, x in metres.
COT_COEFFICIENTS: tuple[float, ...] = (-660.1898, 556.5202, -186.4672, 34.1877, -3.4090, 0.1602)


def cot_polynomial(step_length: ArrayLike) -> FloatArray:
    """The authors' compass-gait COT at ``step_length`` (metres), fitted on [0.08, 0.18] m."""
    x = np.asarray(step_length, dtype=np.float64)
    return np.asarray(np.polyval(COT_COEFFICIENTS, x), dtype=np.float64)
