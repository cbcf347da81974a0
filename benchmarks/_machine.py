"""Describe the machine a benchmark ran on (recorded beside every result)."""

from __future__ import annotations

import os
import platform
from datetime import UTC, datetime

import numpy as np
import scipy

from gaitpref.simulate.report import cpu_model, load_average


def machine_description() -> dict[str, object]:
    return {
        "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "load_average_1min": round(load_average()[0], 2),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "platform": platform.platform(),
    }


def machine_markdown(info: dict[str, object]) -> str:
    return "\n".join(f"- {k}: {v}" for k, v in info.items())
