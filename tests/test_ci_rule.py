"""The CI rule fails skipped postgres/browser tests under CI=true, and only those."""

from __future__ import annotations

import pytest

TESTS = """
import pytest

@pytest.mark.postgres
def test_needs_a_server():
    pytest.skip("no server")

def test_plain_skip():
    pytest.skip("not marked")
"""


@pytest.mark.parametrize("ci, failed, skipped", [("true", 1, 1), ("", 0, 2)])
def test_ci_turns_marked_skips_into_failures(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch, ci: str, failed: int, skipped: int
) -> None:
    monkeypatch.setenv("CI", ci)
    pytester.makeconftest('pytest_plugins = ("tests.ci_rule",)\n')
    pytester.makeini("[pytest]\nmarkers =\n    postgres: x\n    browser: y\n")
    pytester.makepyfile(TESTS)
    result = pytester.runpytest_inprocess()
    result.assert_outcomes(failed=failed, skipped=skipped)
    if failed:
        result.stdout.fnmatch_lines(["*CI=true runs every test, but this one skipped*no server*"])
