"""Figures: compute the picture's data first, then render it with matplotlib."""

#: the half-width of every posterior band, in standard deviations (mean +- 2 sd, as the paper)
BAND_SD = 2.0
#: how every figure names that band
BAND_LABEL = "mean ± 2 sd"
