"""Figures: compute the picture's data first, then render it with matplotlib."""
