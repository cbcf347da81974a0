"""Checks of the numbers a caller hands the library (loops, models, kernels, rating scales).

A number is an ``int`` or ``float`` or a NumPy one, never a ``bool`` (``True`` is not a noise of
1) nor a string; a count is an integer of either kind.  Each check returns the plain Python value
and raises ``ValueError`` with the caller's message otherwise, so that a bad argument is named
where it is given rather than failing deep in NumPy.
"""

from __future__ import annotations

import math
import sys

import numpy as np


def is_number(value: object) -> bool:
    """Whether ``value`` is a real number (Python or NumPy; not a bool, not a string)."""
    return not isinstance(value, bool | np.bool_) and isinstance(
        value, int | float | np.integer | np.floating
    )


#: The largest noise a model takes: its square (what the likelihoods and predictive
#: probabilities use) must be a finite float, and Python's ``**`` raises past it.
MAX_NOISE = math.sqrt(sys.float_info.max)


def is_noise(value: object) -> bool:
    """Whether ``value`` is a number in ``(0, MAX_NOISE]``: a noise whose square is finite."""
    return is_number(value) and 0 < value <= MAX_NOISE  # type: ignore[operator]


def is_count(value: object) -> bool:
    """Whether ``value`` is an integer (Python or NumPy; not a bool)."""
    return not isinstance(value, bool | np.bool_) and isinstance(value, int | np.integer)


def check_evaluations(value: object) -> int:
    """An optimiser's ``max_evaluations``: an integer >= 1, else a ValueError naming it (0, -1
    or 2.5 ran one evaluation and reported "limit reached"; True was 1)."""
    if not is_count(value) or not isinstance(value, int | np.integer) or value < 1:
        raise ValueError(f"max_evaluations must be an integer >= 1, got {value!r}")
    return int(value)


__all__ = ["MAX_NOISE", "check_evaluations", "is_count", "is_noise", "is_number"]
