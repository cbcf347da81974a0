"""Objectives that break a run of a study, importable by joblib's worker processes (a test's
monkeypatch does not reach them): one raises when the run reads it, one kills its worker."""

from __future__ import annotations

import os
from typing import Any


class Raising:
    """An objective whose values cannot be read: the run raises ``ValueError``."""

    def __array__(self, dtype: Any = None, copy: Any = None) -> Any:
        raise ValueError("the objective broke")


class Dying:
    """An objective whose reading kills the process that runs the run (a crash, say)."""

    def __array__(self, dtype: Any = None, copy: Any = None) -> Any:
        os._exit(3)


def fails_at_three(x: int) -> int:
    """A run function for :func:`~gaitpref.simulate.sweep.run_tasks`: task 3 raises."""
    if x == 3:
        raise ValueError("three broke")
    return x * x
