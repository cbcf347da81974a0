"""Fixtures for the command-line tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref.data import paper_objectives


@pytest.fixture
def grid_file(tmp_path: Path) -> Path:
    """One of the paper's objectives over its 30 x 30 grid, as ``--objective FILE.npy``."""
    path = tmp_path / "objective.npy"
    np.save(path, paper_objectives()[5])
    return path
