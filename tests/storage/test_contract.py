"""The storage contract (``gaitpref.storage.testing``), run against every backend.

``TestStorageContract`` runs the importable suite on memory, SQLite and PostgreSQL (the ``open_db``
fixture of ``tests/conftest.py``); the last test checks that the suite works as a lab would use
it, through ``make_storage``, and that it fails a backend that breaks the contract.
"""

from __future__ import annotations

import pytest

from gaitpref.storage.testing import Opener, StorageContract


class TestStorageContract(StorageContract):
    @pytest.fixture
    def open_db(self, open_db: Opener) -> Opener:
        """The conftest's ``open_db``: memory, a SQLite file and a PostgreSQL database."""
        return open_db


_LAB_MODULE = '''
from pathlib import Path

from gaitpref.storage import MemoryStorage, SQLStorage, Storage
from gaitpref.storage.testing import StorageContract


class TestLabSQLite(StorageContract):
    def make_storage(self, tmp_path: Path) -> Storage:
        return SQLStorage(f"sqlite:///{tmp_path / 'lab.db'}")


class AfterIgnored(MemoryStorage):
    """A broken backend: events(session, after) ignores ``after``."""

    def events(self, session_id, after=0):
        return super().events(session_id)


class TestBrokenMemory(StorageContract):
    def make_storage(self, tmp_path: Path) -> Storage:
        if not hasattr(self, "store"):
            self.store = AfterIgnored()
        return self.store
'''


def test_a_lab_runs_the_suite_and_it_fails_a_broken_backend(pytester: pytest.Pytester) -> None:
    pytester.makepyfile(test_lab=_LAB_MODULE)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-rA")
    outcomes = result.parseoutcomes()
    n_contract = sum(1 for n in vars(StorageContract) if n.startswith("test_")) + 4  # 5 payloads
    assert outcomes.get("passed") == 2 * n_contract - 1, result.outlines[-40:]
    assert outcomes.get("failed") == 1
    result.stdout.fnmatch_lines(
        ["FAILED test_lab.py::TestBrokenMemory::test_append_numbers_events_and_round_trips_json*"]
    )
