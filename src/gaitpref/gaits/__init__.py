"""Compass-gait model, HZD gait optimization and the gait library (issue 4)."""
