"""An exclusion checks the pending query against the region of avoidance as it leaves it.

The region depends on the model, and an exclusion changes the model: a "good" rating at one gait
can make a neighbour look safe enough to propose; once that rating is excluded while the query
proposing the neighbour is pending, the neighbour may lie in the region.  The exclusion then
withdraws the pending query (as an unsafe flag would) and the next ask proposes anew, in replay
too.  Exclusions logged before this rule (``trial_excluded`` payload version 1) replay by their
own rule: the pending query kept as it was.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref import Rating, Session
from gaitpref.config import parse_config
from tests.sessions import regionkit

GAITS = list(regionkit.GAITS[:5])
NEXT = regionkit.GAITS[5]  # what query 6 proposes while trial 1's "good" rating is in the model


def _pending(url: str) -> tuple[Session, int]:
    """Five answers: trial 1 "good", the gaits below 5 "very bad", the others "okay"; query 6
    pending (it proposes gait 1); returns the session and query 6's id."""
    s = Session.create(url, regionkit.config(), "S01")
    regionkit.rate_trials(s, 5)
    assert [t.action for t in s.trials()] == GAITS
    q = s.next_query()
    assert q.actions == (NEXT,) and q.trials == (6,)  # the case under test
    return s, q.id


def test_an_exclusion_withdraws_the_pending_query_when_it_puts_its_gait_in_the_region(
    tmp_path: Path,
) -> None:
    url = f"sqlite:///{tmp_path / 'e.db'}"
    s, asked = _pending(url)
    s.exclude(1, "device_fault", "the treadmill belt slipped")
    proposable = s._state.loop.proposable()
    assert not proposable[NEXT]  # gait 1 is in the region without trial 1's rating
    assert s.pending is None, "the pending query proposes a gait in the region now"
    assert [e.kind for e in s.events()][-1] == "trial_excluded"
    new = s.next_query()
    assert new.id != asked and new.trials == (6,)
    assert all(proposable[a] for a in new.actions)
    mean = np.asarray(s.posterior().mean).copy()
    s.close()
    with Session.open(url, s.id) as again:  # replay derives the same withdrawal
        assert [e.version for e in again.events() if e.kind == "trial_excluded"] == [2]
        assert again.pending == new
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
        again.answer(new.id, [Rating(new.actions[0], "okay")])
        assert [t.action for t in again.trials()] == [*GAITS, new.actions[0]]


def test_an_exclusion_keeps_a_pending_query_it_leaves_proposable(tmp_path: Path) -> None:
    """Excluding a trial whose answer did not make the pending query's gaits proposable
    withdraws nothing: the same query stays pending."""
    url = f"sqlite:///{tmp_path / 'e.db'}"
    s, asked = _pending(url)
    s.exclude(4, "stumble")
    assert s._state.loop.proposable()[NEXT]
    pending = s.pending
    assert pending is not None and pending.id == asked
    assert s.next_query().id == asked
    s.close()
    with Session.open(url, s.id) as again:
        assert again.pending == pending


def _exclude_as_version_1(
    s: Session, monkeypatch: pytest.MonkeyPatch, trial: int, reason: str, detail: str = ""
) -> None:
    """Exclude ``trial`` as a release before the region check logged it (``trial_excluded``
    payload version 1)."""
    from gaitpref.sessions import events

    monkeypatch.setattr(events.TrialExcluded, "version", 1)
    s.exclude(trial, reason, detail)
    monkeypatch.undo()


def test_an_exclusion_logged_as_version_1_keeps_the_pending_query_as_it_did(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A log written before the region check (``trial_excluded`` payload version 1) replays as
    it ran: the pending query kept, though its gait is in the region now, and its answer
    follows."""
    url = f"sqlite:///{tmp_path / 'e.db'}"
    s, asked = _pending(url)
    _exclude_as_version_1(s, monkeypatch, 1, "device_fault", "the treadmill belt slipped")
    kept = s.pending
    assert kept is not None and kept.id == asked and kept.actions == (NEXT,)
    s.answer(asked, [Rating(NEXT, "very bad")])
    mean = np.asarray(s.posterior().mean).copy()
    s.close()
    with Session.open(url, s.id) as again:
        assert [e.version for e in again.events() if e.kind == "trial_excluded"] == [1]
        assert [t.action for t in again.trials()] == [*GAITS, NEXT]
        assert np.array_equal(np.asarray(again.posterior().mean), mean)


def _round(url: str) -> Session:
    """Five answers (gaits 2, 5, 8, 8, 4: "okay", "good", "good", "very bad", "very bad"),
    then a blind validation round showing gait 7 (proposable while trials 2 and 3, "good"
    at its neighbours 5 and 8, are in the model), and trial 2 excluded (gait 7 stays
    proposable)."""
    s = Session.create(url, regionkit.config(), "S01")
    for label in ("okay", "good", "good", "very bad", "very bad"):
        q = s.next_query()
        s.answer(q.id, [Rating(q.actions[0], label)])
    assert [t.action for t in s.trials()] == [2, 5, 8, 8, 4]
    plan = s.start_validation()
    assert 7 in [g.action for g in plan.gaits]  # the case under test
    s.exclude(2, "stumble")
    assert s.validation_plan == plan and s._state.loop.proposable()[7]
    return s


def test_an_exclusion_withdraws_an_open_round_showing_a_gait_in_the_region_now(
    tmp_path: Path,
) -> None:
    """As an unsafe flag does: the round is withdrawn and drawn again among the gaits that
    may be proposed now."""
    url = f"sqlite:///{tmp_path / 'e.db'}"
    s = _round(url)
    shown = s.validation_plan
    s.exclude(3, "stumble")
    proposable = s._state.loop.proposable()
    assert not proposable[7]
    plan = s.validation_plan
    assert plan is not None and plan != shown
    assert plan.round == 1  # the withdrawn round is not counted, as after a flag
    assert all(proposable[g.action] for g in plan.gaits)
    assert [e.kind for e in s.events()][-2:] == ["trial_excluded", "validation_started"]
    s.close()
    with Session.open(url, s.id) as again:
        assert again.validation_plan == plan


def test_an_exclusion_logged_as_version_1_keeps_the_open_round(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    url = f"sqlite:///{tmp_path / 'e.db'}"
    s = _round(url)
    plan = s.validation_plan
    _exclude_as_version_1(s, monkeypatch, 3, "stumble")
    assert s.validation_plan == plan
    s.close()
    with Session.open(url, s.id) as again:
        assert again.validation_plan == plan


def test_the_cli_says_when_an_exclusion_withdrew_the_pending_query(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from gaitpref.cli import app

    db = tmp_path / "e.db"
    s, asked = _pending(f"sqlite:///{db}")
    s.close()
    args = ["session", "exclude", str(s.id), "1", "--reason", "device-fault", "--db", str(db)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "trial 1 excluded" in result.output
    assert f"pending query {asked} proposed a gait in the region of avoidance" in result.output
    with Session.open(f"sqlite:///{db}", s.id) as again:
        assert again.pending is None


def test_the_cli_says_when_an_unsafe_flag_withdrew_the_pending_query(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from gaitpref.cli import app

    db = tmp_path / "f.db"
    with Session.create(
        f"sqlite:///{db}", parse_config(regionkit.CONFIG + "unsafe_radius = 0.1\n"), "S01"
    ) as s:
        regionkit.rate_trials(s, 5)
        asked = s.next_query()  # gait 1, within 0.1 of the range of trial 1's gait 2
    args = ["session", "unsafe", str(s.id), "1", "--reason", "knee", "--db", str(db)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert f"pending query {asked.id} proposed a gait near it and was withdrawn" in result.output
    args = ["session", "unsafe", str(s.id), "2", "--reason", "hip", "--db", str(db)]
    result = CliRunner().invoke(app, args)  # nothing pending now: nothing withdrawn
    assert result.exit_code == 0 and "withdrawn" not in result.output
