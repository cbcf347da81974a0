"""Figures: compute the picture's data first, then render it with matplotlib.

Text that comes from a user (a feature's name or unit, a config's name, a subject code, a
validation label) goes through :func:`plain` before matplotlib sees it: matplotlib reads text
between ``$`` signs as mathtext, so a unit ``$\\foo$`` made every figure of the session fail
and ``$x$`` was drawn as a formula.
"""

#: the half-width of every posterior band, in standard deviations (mean +- 2 sd, as the paper)
BAND_SD = 2.0
#: how every figure names that band
BAND_LABEL = "mean ± 2 sd"


def plain(text: str) -> str:
    """``text`` as matplotlib draws it literally: every ``$`` escaped (no mathtext)."""
    return text.replace("$", r"\$")
