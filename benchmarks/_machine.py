"""Describe the machine a benchmark ran on (recorded beside every result)."""

from __future__ import annotations

import os
import platform
from datetime import UTC, datetime

import numpy as np
import scipy


def machine_description() -> dict[str, object]:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "cpu": cpu,
        "cores": os.cpu_count(),
        "load_average_1min": round(os.getloadavg()[0], 2),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "platform": platform.platform(),
    }


def machine_markdown(info: dict[str, object]) -> str:
    return "\n".join(f"- {k}: {v}" for k, v in info.items())
