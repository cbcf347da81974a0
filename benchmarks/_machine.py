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


def machine_footer(what: str, seconds: float, load_before: float) -> list[str]:
    """The closing lines of a result file: how long ``what`` took, the load before it, and the
    machine (whose ``load_average_1min`` is the load at the end)."""
    return [
        "",
        f"{what}: {seconds:.0f} s.  Load average (1 min) at the start: {load_before:.2f}; at "
        "the end: below.  Timings on a shared two-core machine vary by a factor of 2-3 between "
        "runs.",
        "",
        "Machine:",
        "",
        machine_markdown(machine_description()),
        "",
    ]
