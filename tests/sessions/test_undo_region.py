"""An undo checks the query it restores against the region of avoidance as it is now.

The region depends on the model, and an exclusion made after the answer changes the model: a
"good" rating at one gait can make a neighbour look safe enough to propose; once that rating is
excluded, the neighbour may lie in the region.  Undoing the neighbour's answer then withdraws its
query (as an unsafe flag would) and proposes a new one, in replay too.  Undo events logged before
this rule (payload version 1) replay by their own rule: the query restored as it was.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref import Rating, Session
from tests.sessions import regionkit

GAITS = list(regionkit.GAITS)


def _rated(url: str) -> Session:
    """Six answers: trial 1 "good", the gaits below 5 "very bad", the others "okay"; the
    seventh query pending; then trial 1 excluded (the good rating leaves the model)."""
    s = Session.create(url, regionkit.config(), "S01")
    regionkit.rate_trials(s, 6)
    assert [t.action for t in s.trials()] == GAITS  # the case under test
    s.next_query()
    s.exclude(1, "device_fault", "the treadmill belt slipped")
    return s


def test_an_undo_withdraws_its_query_when_an_exclusion_since_puts_its_gait_in_the_region(
    tmp_path: Path,
) -> None:
    url = f"sqlite:///{tmp_path / 'u.db'}"
    s = _rated(url)
    answered = next(
        e for e in s.events() if e.kind == "query_issued" and e.payload["trials"] == [6]
    )
    new = s.undo()
    assert new is not None and s.pending == new
    assert new.id != answered.seq, "the restored query proposes a gait in the region"
    assert new.trials == (6,)
    proposable = s._state.loop.proposable()
    assert not proposable[GAITS[-1]]  # gait 1 is in the region without trial 1's rating
    assert all(proposable[a] for a in new.actions)
    kinds = [e.kind for e in s.events()]
    assert kinds[-2:] == ["undo", "query_issued"]
    mean = np.asarray(s.posterior().mean).copy()
    s.close()
    with Session.open(url, s.id) as again:  # replay derives the same withdrawal
        assert again.pending == new
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
        again.answer(new.id, [Rating(new.actions[0], "okay")])


def test_an_undo_logged_as_version_1_restores_its_query_as_it_did(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A log written before the region check (undo payload version 1) replays as it ran: the
    restored query pending again, though its gait is in the region now."""
    from gaitpref.sessions import events

    url = f"sqlite:///{tmp_path / 'u.db'}"
    s = _rated(url)
    monkeypatch.setattr(events.Undo, "version", 1)
    restored = s.undo()
    monkeypatch.undo()
    assert restored is not None and restored.actions == (GAITS[-1],)
    s.answer(restored.id, [Rating(GAITS[-1], "very bad")])
    mean = np.asarray(s.posterior().mean).copy()
    s.close()
    with Session.open(url, s.id) as again:
        assert [e.version for e in again.events() if e.kind == "undo"] == [1]
        assert [t.action for t in again.trials()] == GAITS
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
