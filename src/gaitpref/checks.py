"""Checks of the numbers a caller hands the library (loops, models, kernels, rating scales),
and of text a terminal would show as it is (:func:`hidden_in`).

A number is an ``int`` or ``float`` or a NumPy one, never a ``bool`` (``True`` is not a noise of
1) nor a string; a count is an integer of either kind.  Each check returns the plain Python value
and raises ``ValueError`` with the caller's message otherwise, so that a bad argument is named
where it is given rather than failing deep in NumPy.
"""

from __future__ import annotations

import math
import sys
import unicodedata

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


#: Bidirectional formatting characters (Unicode's Bidi_Control property): embeddings,
#: overrides, isolates and marks, which reorder the text shown around them.
BIDI_CONTROLS = frozenset(
    {
        "\u061c",
        "\u200e",
        "\u200f",
        *map(chr, range(0x202A, 0x202F)),
        *map(chr, range(0x2066, 0x206A)),
    }
)


#: Unicode categories a one-line name may not hold (a config's name, a feature's unit and words,
#: rating labels, gait ids): controls, format characters (zero width, bidirectional
#: overrides), surrogates, line and paragraph separators.  Private-use and unassigned code points
#: are let through: whether a code point is assigned depends on the Python version's tables.
NAME_HIDDEN = frozenset({"Cc", "Cf", "Cs", "Zl", "Zp"})


def hidden_in(text: str, *, name: bool = False) -> list[tuple[int, str]]:
    """The characters of ``text`` that would garble a terminal or the text shown around it,
    with their indexes.  Free text (``name=False``: a description, a note, a reason): a control
    character other than a tab or a newline (ESC, NUL, a carriage return, DEL, C1), a
    surrogate, a line or paragraph separator, or a bidirectional formatting character; other
    format characters pass (zero width joiners, which Persian and emoji sequences need).  A
    name (``name=True``): any character of :data:`NAME_HIDDEN`, tabs and newlines included."""
    if name:
        return [(i, c) for i, c in enumerate(text) if unicodedata.category(c) in NAME_HIDDEN]
    return [
        (i, c)
        for i, c in enumerate(text)
        if c in BIDI_CONTROLS
        or (unicodedata.category(c) in ("Cc", "Cs", "Zl", "Zp") and c not in "\t\n")
    ]


def char_name(char: str) -> str:
    """``"U+001B"``, or ``"U+202E RIGHT-TO-LEFT OVERRIDE"`` where Unicode names it."""
    return f"U+{ord(char):04X} {unicodedata.name(char, '')}".strip()


def check_mask(
    allowed: object, size: int, *, what: str = "actions", optional: bool = False, empty: str
) -> np.ndarray[tuple[int], np.dtype[np.bool_]]:
    """``allowed`` as a boolean mask over ``size`` ``what`` with at least one allowed, else a
    ``ValueError`` naming it, with ``empty`` as the message when none is allowed.  A mask of
    integers is refused: NumPy reads it bitwise (``~1`` is ``-2``) and as indices, so the
    result would come silently from other actions.  ``optional``: the message says ``None``
    is taken too."""
    arr = np.asarray(allowed)
    if arr.dtype != np.bool_ or arr.shape != (size,):
        none = "None or " if optional else ""
        raise ValueError(
            f"allowed must be {none}a boolean mask over the {size} {what}, got dtype "
            f"{arr.dtype} and shape {arr.shape}"
        )
    if not arr.any():
        raise ValueError(empty)
    return arr
