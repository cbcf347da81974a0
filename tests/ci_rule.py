"""The CI rule: under ``CI=true`` a skipped ``postgres`` or ``browser`` test is a failure.

Locally such tests skip with a message that says how to enable them; CI installs everything they
need (``.ci/system-deps``), so a skip there means something is broken.  ``tests/conftest.py``
registers the hook.
"""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest

CI_MARKERS = ("postgres", "browser")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Iterator[None]:
    """Under ``CI=true`` a skipped ``postgres``/``browser`` test is a failure: CI runs them all."""
    outcome = yield
    report = outcome.get_result()  # type: ignore[attr-defined]
    if (
        report.skipped
        and os.environ.get("CI", "").lower() == "true"
        and any(item.get_closest_marker(m) for m in CI_MARKERS)
    ):
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else report.longrepr
        report.outcome = "failed"
        report.longrepr = f"CI=true runs every test, but this one skipped: {reason}"


__all__ = ["CI_MARKERS", "pytest_runtest_makereport"]
