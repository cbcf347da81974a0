"""Warm starts: earlier sessions' answers in a new session's model; read, recorded, replayed."""

from __future__ import annotations

import dataclasses
import json
import re
import sqlite3
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import Session, load_config
from gaitpref.config import parse_config
from gaitpref.errors import ReplayError
from gaitpref.sessions import ExportError
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.sessions.export import export_session, import_session
from gaitpref.sessions.warm import log_sha256, prepare_state, read_prior_from
from gaitpref.storage import MemoryStorage, Storage
from tests.sessions.sessionkit import CONFIG, state_of


def _run(session: Session, subject: SimulatedSubject, answers: int) -> None:
    for _ in range(answers):
        q = session.next_query()
        comparisons, suggestions = subject.respond(q)
        session.answer(q.id, comparisons, suggestions)


def _earlier(db: str | Storage) -> list[int]:
    """Two earlier subjects (S01 twice, S02 once) with the same utility."""
    space = load_config(CONFIG).space
    ids = []
    for code, seed in (("S01", 1), ("S01", 2), ("S02", 3)):
        with Session.create(db, CONFIG, code, seed=seed) as s:
            _run(s, SimulatedSubject(space, bump_utility(space), seed=seed), 6)
            ids.append(s.id)
    return ids


def _snapshot(db: str | Storage, ids: list[int]) -> list[object]:
    out: list[object] = []
    for i in ids:
        with Session.open(db, i) as s:
            out.append((s.record, [(e.seq, e.kind, e.payload, e.at) for e in s.events()]))
    return out


def test_a_warm_start_is_recorded_replays_and_never_writes_to_what_it_reads(
    db: str | Storage,
) -> None:
    ids = _earlier(db)
    before = _snapshot(db, ids)
    space = load_config(CONFIG).space
    s = Session.create(db, CONFIG, "S03", seed=5, prior_from=["S01", ids[2]])
    created = s.events()[0].payload
    assert [p["session"] for p in created["prior_from"]] == ids
    assert 0.0 < created["prior_rho"] < 1.0
    assert s.record.meta["prior_from"] == created["prior_from"]
    _run(s, SimulatedSubject(space, bump_utility(space), seed=5), 5)
    mean, var, query, rng = state_of(s)
    again = Session.open(db, s.id)
    mean2, var2, query2, rng2 = state_of(again)
    assert np.array_equal(mean, mean2) and np.array_equal(var, var2)
    assert (query, rng) == (query2, rng2)
    assert _snapshot(db, ids) == before  # read, never written


def test_a_warm_start_made_now_starts_alone_and_shares_once_the_answers_agree() -> None:
    db = MemoryStorage()
    ids = _earlier(db)
    cold = Session.create(db, CONFIG, "S03", seed=5)
    warm = Session.create(db, CONFIG, "S04", seed=5, prior_from=ids)
    created = warm.events()[0].payload
    assert created["prior_relearn_every"] == 1 and created["prior_share_gate"] == 0.0
    space = load_config(CONFIG).space
    best = int(np.argmax(bump_utility(space)))
    assert np.array_equal(cold.posterior().mean, warm.posterior().mean)  # alone at first
    _run(warm, SimulatedSubject(space, bump_utility(space), seed=5), 4)
    refits = [e.payload for e in warm.events() if e.kind == "share_refit"]
    assert len(refits) == 4 and refits[0]["before"] == 0.0
    loop = warm._state.loop
    assert loop.warm is not None and loop.warm.share == refits[-1]["after"] > 0.0
    assert abs(int(np.argmax(warm.posterior().mean)) - best) <= 2
    mean = np.asarray(warm.posterior().mean).copy()
    with Session.open(db, warm.id) as again:  # the share refits replay exactly
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
        assert again._state.loop.warm is not None
        assert again._state.loop.warm.share == loop.warm.share
    # recorded before share refits (no prior_relearn_every): rho held, the others shape the
    # first query, as such sessions ran
    meta = {k: v for k, v in warm.record.meta.items() if not k.startswith("prior_")}
    meta.update(prior_from=warm.record.meta["prior_from"], prior_rho=warm.record.meta["prior_rho"])
    old = prepare_state(db, dataclasses.replace(warm.record, meta=meta))
    assert old.loop.warm is not None and old.loop.warm.share is None
    assert old.loop.warm.relearn_every == 0
    assert abs(int(np.argmax(old.loop.posterior.mean)) - best) <= 2


def test_replay_refuses_when_an_earlier_session_changed(tmp_path: Path) -> None:
    path = tmp_path / "s.db"
    url = f"sqlite:///{path}"
    ids = _earlier(url)
    s = Session.create(url, CONFIG, "S03", seed=5, prior_from=[ids[0]])
    s.close()
    with Session.open(url, ids[0]) as earlier:  # going on afterwards is fine
        earlier.note("walked again later")
    Session.open(url, s.id).close()
    with sqlite3.connect(path) as con:  # an edit of the stored log (by another tool) is not
        con.execute("DROP TRIGGER events_no_update")
        con.execute(
            "UPDATE events SET payload = replace(payload, '\"first\"', '\"second\"') "
            "WHERE session_id = ? AND kind = 'comparison_answered'",
            (ids[0],),
        )
    with pytest.raises(ReplayError, match=f"session {ids[0]} \\(subject S01\\).*has changed"):
        Session.open(url, s.id)


def test_prior_from_names_what_it_cannot_use() -> None:
    db = MemoryStorage()
    ids = _earlier(db)
    with pytest.raises(ValueError, match=r"subject 'S09' has no sessions$"):
        Session.create(db, CONFIG, "S03", prior_from=["S09"])
    # codes match letter case: one typed otherwise said only that it had no sessions
    with pytest.raises(ValueError, match=r"'s01' has no sessions \(.*did you mean 'S01'\?\)"):
        Session.create(db, CONFIG, "S03", prior_from=["s01"])
    # an id given as text (a JSON body's "3", a list read from a file) is a subject code
    with pytest.raises(ValueError, match=rf"for session {ids[2]}, give the number"):
        Session.create(db, CONFIG, "S03", prior_from=[str(ids[2])])
    with pytest.raises(ValueError, match=f"session {ids[0]} .*another grid"):
        Session.create(db, "exo-2d-length-duration", "S03", prior_from=[ids[0]])


def test_the_same_grid_worded_otherwise_is_the_same_grid_and_another_is_named() -> None:
    """A config that words the coactive moves otherwise (or moves by other fractions) was refused
    as 'run on another grid'; another grid named no difference."""
    base = load_config(CONFIG)
    db = MemoryStorage()

    def variant(old: str, new: str) -> int:
        cfg = parse_config(base.text.replace(old, new))
        with Session.create(db, cfg, "S01") as s:
            return s.id

    worded = variant('words = ["longer", "shorter"]', 'words = ["up", "down"]')
    moved = variant("coactive = [0.1, 0.2]", "coactive = [0.1, 0.3]")
    Session.create(db, base, "S02", prior_from=[worded, moved]).close()
    for old, new, says in (
        ('unit = "m"', 'unit = "cm"', "step_length is in 'cm', not 'm'"),
        ("num = 15", "num = 16", "step_length takes 16 values 0.08..0.18, not 15 values"),
    ):
        other = variant(old, new)
        with pytest.raises(ValueError, match=rf"another grid \(config '[^']+': {re.escape(says)}"):
            Session.create(db, base, "S02", prior_from=[other])


def test_the_cli_warm_starts_a_new_session(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from gaitpref.cli import app

    url = f"sqlite:///{tmp_path / 's.db'}"
    ids = _earlier(url)
    args = ["session", "new", "--config", CONFIG, "--subject", "S03", "--db", url]
    result = CliRunner().invoke(app, [*args, "--prior-from", "S01", "--prior-from", str(ids[2])])
    assert result.exit_code == 0, result.output
    new_id = int(result.output.split()[1].rstrip(":"))
    with Session.open(url, new_id) as s:
        assert [p["session"] for p in s.record.meta["prior_from"]] == ids
    bad = CliRunner().invoke(app, [*args, "--prior-from", "S09"])
    assert bad.exit_code != 0 and "subject 'S09' has no sessions" in bad.output
    before = len(Session.list_sessions(url))
    for blank in ("", ",", " , "):  # "$PRIOR" unset: a cold session was created, saying nothing
        bad = CliRunner().invoke(app, [*args, "--prior-from", "S01", "--prior-from", blank])
        assert bad.exit_code != 0 and f"--prior-from {blank!r} names no session" in bad.output
    assert len(Session.list_sessions(url)) == before


def test_a_warm_started_session_is_refused_on_import_naming_its_earlier_sessions(
    tmp_path: Path,
) -> None:
    db = MemoryStorage()
    ids = _earlier(db)
    with Session.create(db, CONFIG, "S03", seed=5, prior_from=[ids[0]]) as s:
        space = load_config(CONFIG).space
        _run(s, SimulatedSubject(space, bump_utility(space), seed=9), 2)
        export_session(s, tmp_path / "export", fmt="json")
    before = [r.id for r in db.list_sessions()]
    with pytest.raises(ExportError, match=rf"warm-started from earlier sessions {ids[0]} \(S01\)"):
        import_session(db, tmp_path / "export", as_new=True)
    assert [r.id for r in db.list_sessions()] == before


def test_a_subjects_chain_of_warm_started_sessions_replays_each_earlier_one_once(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each session of S01 warm-started from S01's earlier ones: opening the k-th replayed every
    path to an earlier session (2**(k-1) - 1 replays: 31 for the sixth, a minute by the tenth,
    hours by the twentieth); now each once, the same posterior."""
    from gaitpref.sessions import warm
    from gaitpref.sessions.replay import replay
    from gaitpref.sessions.state import SessionState
    from gaitpref.storage import EventRecord

    db = MemoryStorage()
    space = load_config(CONFIG).space
    for k in range(6):
        with Session.create(db, CONFIG, "S01", seed=k, prior_from=["S01"] if k else []) as s:
            _run(s, SimulatedSubject(space, bump_utility(space), seed=k), 2)
            mean = np.asarray(s.posterior().mean).copy()
    calls: list[EventRecord] = []

    def counted(state: SessionState, events: Sequence[EventRecord]) -> None:
        calls.append(events[0])
        replay(state, events)

    monkeypatch.setattr(warm, "replay", counted)
    with Session.open(db, s.id) as again:
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
    assert len(calls) == 5


def test_creating_a_warm_start_replays_each_earlier_session_once(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Creating replayed every earlier session twice (once to learn rho, once more to build the
    new session's state): at 40 subjects of 60 answers, 5 of its 25 s.  Now once; the state built
    from them is the one a reopening builds."""
    from gaitpref.sessions import warm
    from gaitpref.sessions.replay import replay
    from gaitpref.sessions.state import SessionState
    from gaitpref.storage import EventRecord

    db = MemoryStorage()
    ids = _earlier(db)
    calls: list[EventRecord] = []

    def counted(state: SessionState, events: Sequence[EventRecord]) -> None:
        calls.append(events[0])
        replay(state, events)

    monkeypatch.setattr(warm, "replay", counted)
    with Session.create(db, CONFIG, "S03", seed=5, prior_from=["S01", ids[2]]) as s:
        created = state_of(s)
        sid = s.id
    assert len(calls) == 3
    with Session.open(db, sid) as again:
        reopened = state_of(again)
    assert len(calls) == 6  # a reopening replays them all again, as always
    assert np.array_equal(created[0], reopened[0]) and created[2:] == reopened[2:]


def test_a_warm_start_past_the_node_limit_is_refused_by_count_before_anything_is_written(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Hundreds of earlier subjects were taken whole: 300 subjects of 15 answers made every
    answer of the new session take 150 s (a dense refit over every (gait, subject) pair)."""
    from gaitpref.errors import PriorFromError
    from gaitpref.sessions import warm

    db = MemoryStorage()
    ids = _earlier(db)
    monkeypatch.setattr(warm, "MAX_PRIOR_NODES", 5)
    before = [r.id for r in db.list_sessions()]
    with pytest.raises(PriorFromError, match=r"visit \d+ \(gait, subject\) pairs; a warm start "):
        Session.create(db, CONFIG, "S03", prior_from=ids)
    assert [r.id for r in db.list_sessions()] == before
    monkeypatch.setattr(warm, "MAX_PRIOR_NODES", 2000)
    monkeypatch.setattr(warm, "MAX_PRIOR_SESSIONS", 2)  # sessions with no answer cost replays
    with pytest.raises(PriorFromError, match="names more than 2 sessions"):
        Session.create(db, CONFIG, "S03", prior_from=["S01", "S02"])
    assert [r.id for r in db.list_sessions()] == before
    monkeypatch.setattr(warm, "MAX_PRIOR_SESSIONS", 3)
    Session.create(db, CONFIG, "S03", prior_from=ids).close()


def test_an_earlier_session_whose_row_was_edited_is_named_when_it_does_not_replay(
    tmp_path: Path,
) -> None:
    """Its log intact (the hash matches) but its seed edited: the error was the earlier
    session's 'event 2 (query_issued): actions ...' alone, read as the opened session's own."""
    path = tmp_path / "s.db"
    url = f"sqlite:///{path}"
    ids = _earlier(url)
    with Session.create(url, CONFIG, "S03", seed=5, prior_from=[ids[0]]) as s:
        new = s.id
    with sqlite3.connect(path) as con:
        con.execute("UPDATE sessions SET seed = 12345 WHERE id = ?", (ids[0],))
    with pytest.raises(
        ReplayError, match=rf"session {ids[0]} \(subject S01\), which .* does not replay.*event"
    ):
        Session.open(url, new)


def test_an_earlier_session_missing_from_the_database_is_named_as_the_warm_starts(
    tmp_path: Path,
) -> None:
    """Deleted by another tool: opening the warm session said 'no session 1', not which."""
    path = tmp_path / "s.db"
    url = f"sqlite:///{path}"
    ids = _earlier(url)
    with Session.create(url, CONFIG, "S03", seed=5, prior_from=[ids[0]]) as s:
        new = s.id
    with sqlite3.connect(path) as con:
        con.execute("DROP TRIGGER events_no_delete")
        con.execute("DELETE FROM events WHERE session_id = ?", (ids[0],))
        con.execute("DELETE FROM sessions WHERE id = ?", (ids[0],))
    with pytest.raises(ReplayError, match=rf"session {ids[0]} \(subject S01\), which .* not in"):
        Session.open(url, new)


def test_prior_from_must_be_a_list_not_one_code_a_number_or_a_mapping() -> None:
    """'S01' was read a character at a time (subjects 'S', '0', '1': a subject 'S' was taken
    silently), 7 was a TypeError ('int' object is not iterable), a dict gave its keys."""
    db = MemoryStorage()
    ids = _earlier(db)
    Session.create(db, CONFIG, "S", seed=4).close()
    before = [r.id for r in db.list_sessions()]
    for bad in ("S01", ids[0], {ids[0]: 1}, b"S01"):
        with pytest.raises(ValueError, match="prior_from: expected a list of session ids"):
            Session.create(db, CONFIG, "S03", prior_from=bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"prior_from: expected session ids .*got 1\.0"):
        Session.create(db, CONFIG, "S03", prior_from=[1.0])  # type: ignore[list-item]
    assert [r.id for r in db.list_sessions()] == before
    lazy: Any = iter(["S01"])  # any iterable of ids, read once
    with Session.create(db, CONFIG, "S03", prior_from=lazy) as s:
        assert [p["session"] for p in s.record.meta["prior_from"]] == ids[:2]
    numpy_ids: Any = np.array(ids)  # NumPy ids are ids
    with Session.create(db, CONFIG, "S04", prior_from=numpy_ids) as s:
        assert [p["session"] for p in s.record.meta["prior_from"]] == ids


def test_a_warm_start_naming_a_later_session_is_refused_as_an_altered_database(
    tmp_path: Path,
) -> None:
    """A row edited so that a session's warm start names itself (its hash matching): opening it
    recursed until Python's RecursionError."""
    path = tmp_path / "s.db"
    url = f"sqlite:///{path}"
    ids = _earlier(url)
    with Session.create(url, CONFIG, "S03", seed=5, prior_from=[ids[0]]) as s:
        new, meta, sha = s.id, s.record.meta, log_sha256(s.events()[:1])
    itself = {"session": new, "subject": "S03", "last_seq": 1, "sha256": sha}  # hash matches
    with sqlite3.connect(path) as con:
        con.execute(
            "UPDATE sessions SET meta = ? WHERE id = ?",
            (json.dumps({**meta, "prior_from": [itself]}), new),
        )
    with pytest.raises(ReplayError, match=f"session {new}: its warm start names session {new}"):
        Session.open(url, new)


def _damaged(path: Path, ids: list[int]) -> list[tuple[str, str]]:
    """Earlier sessions damaged in each way a warm start meets (another tool's edits), with
    what the refusal must say: the session it names, and why."""
    chained = Session.create(f"sqlite:///{path}", CONFIG, "S04", seed=6, prior_from=[ids[1]])
    chained.close()
    with sqlite3.connect(path) as con:
        con.execute("DROP TRIGGER events_no_update")
        con.execute("UPDATE sessions SET seed = 12345 WHERE id = ?", (ids[0],))
        con.execute("UPDATE sessions SET config_text = config_text || ' ' WHERE id = ?", (ids[2],))
        # the session a warm-started one read has changed since
        con.execute(
            "UPDATE events SET payload = replace(payload, '\"first\"', '\"second\"') "
            "WHERE session_id = ? AND kind = 'comparison_answered'",
            (ids[1],),
        )
    return [
        (str(ids[0]), rf"session {ids[0]} \(subject S01\).* does not replay"),
        (str(ids[2]), rf"session {ids[2]}: the stored config text does not match its hash"),
        (str(chained.id), rf"session {ids[1]} \(subject S01\).* has changed since"),
    ]


def test_an_earlier_session_that_cannot_be_rebuilt_is_a_refused_prior_from(
    tmp_path: Path,
) -> None:
    """It raised the earlier session's ReplayError (the console answered 500, as for a damaged
    session of its own): the warm start names a session it cannot use, as for one that is not
    there, and nothing is created."""
    from gaitpref.errors import PriorFromError

    path = tmp_path / "s.db"
    url = f"sqlite:///{path}"
    ids = _earlier(url)
    cases = _damaged(path, ids)
    before = [r.id for r in Session.list_sessions(url)]
    for item, why in cases:
        with pytest.raises(PriorFromError, match=rf"^prior_from: .*cannot be rebuilt.*{why}"):
            Session.create(url, CONFIG, "S05", prior_from=[int(item)])
    assert [r.id for r in Session.list_sessions(url)] == before


def test_the_cli_refuses_an_earlier_session_that_cannot_be_rebuilt_as_the_library_does(
    tmp_path: Path,
) -> None:
    from typer.testing import CliRunner

    from gaitpref.cli import app

    path = tmp_path / "s.db"
    url = f"sqlite:///{path}"
    ids = _earlier(url)
    cases = _damaged(path, ids)
    before = [r.id for r in Session.list_sessions(url)]
    args = ["session", "new", "--config", CONFIG, "--subject", "S05", "--db", url]
    for item, why in cases:
        bad = CliRunner().invoke(app, [*args, "--prior-from", item])
        said = " ".join(bad.output.split())
        assert bad.exit_code == 2, said
        assert re.search(rf"error: prior_from: .*cannot be rebuilt.*{why}", said), said
    assert [r.id for r in Session.list_sessions(url)] == before


def test_an_earlier_sessions_warm_start_garbled_in_its_row_is_named_not_a_validation_error(
    tmp_path: Path,
) -> None:
    """Its meta's prior_from edited into something that is not a list of earlier sessions:
    opening it raised pydantic's ValidationError (or a TypeError), naming no session."""
    path = tmp_path / "s.db"
    url = f"sqlite:///{path}"
    ids = _earlier(url)
    with Session.create(url, CONFIG, "S03", seed=5, prior_from=[ids[0]]) as s:
        new, meta = s.id, s.record.meta
    for garbled in ([{"session": "x"}], 7, [3]):
        with sqlite3.connect(path) as con:
            con.execute(
                "UPDATE sessions SET meta = ? WHERE id = ?",
                (json.dumps({**meta, "prior_from": garbled}), new),
            )
        with pytest.raises(ReplayError, match=rf"session {new}: its warm start's prior_from"):
            Session.open(url, new)


def test_prior_from_naming_a_session_many_times_reads_it_once() -> None:
    """Each item was looked up in the database, repeated or not: the console's 'Warm start
    from' field of '1,' thirty thousand times took 30 s (the form's field may hold half a
    million); now each distinct item is read once, and what is recorded is the same."""
    db = MemoryStorage()
    ids = _earlier(db)
    reads: list[object] = []
    get_session, list_sessions = db.get_session, db.list_sessions

    def counted_get(session_id: int) -> object:
        reads.append(session_id)
        return get_session(session_id)

    def counted_list(subject: str | None = None) -> object:
        reads.append(subject)
        return list_sessions(subject)

    db.get_session = counted_get  # type: ignore[method-assign, assignment]
    db.list_sessions = counted_list  # type: ignore[method-assign, assignment]
    with Session.create(db, CONFIG, "S03", prior_from=[ids[2], "S01"] * 50_000) as s:
        assert [p["session"] for p in s.record.meta["prior_from"]] == ids
    assert reads.count("S01") == 1 and len(reads) < 50, len(reads)  # not one per item


def test_typed_digits_that_are_also_a_subjects_code_are_refused_not_read_as_a_session_id() -> None:
    """Subjects coded by number: ``--prior-from 1`` read as session 1 warm-started from whoever
    ran session 1, silently, though subject ``1`` was meant.  Digits that are also a code are
    refused, naming both; ``session:N`` and ``subject:CODE`` say which."""
    db = MemoryStorage()
    space = load_config(CONFIG).space
    ids = []
    for code, seed in (("S01", 1), ("1", 2)):  # session 1 is S01's, subject "1" ran session 2
        with Session.create(db, CONFIG, code, seed=seed) as s:
            _run(s, SimulatedSubject(space, bump_utility(space), seed=seed), 4)
            ids.append(s.id)
    assert ids == [1, 2]
    with pytest.raises(ValueError, match="'1' is both session id 1 and a subject's code; write"):
        Session.create(db, CONFIG, "S03", prior_from=read_prior_from(["1"]))
    assert [r.id for r in db.list_sessions()] == ids  # nothing created
    as_id = Session.create(db, CONFIG, "S03", prior_from=read_prior_from(["session:1"]))
    as_code = Session.create(db, CONFIG, "S04", prior_from=read_prior_from(["subject:1"]))
    assert [p["session"] for p in as_id.record.meta["prior_from"]] == [1]
    assert [p["session"] for p in as_code.record.meta["prior_from"]] == [2]
    # digits no subject uses stay a session id, and an API caller's int is never ambiguous
    assert read_prior_from(["2, S01"]) == [2, "S01"]
    Session.create(db, CONFIG, "S05", prior_from=[1]).close()
    with pytest.raises(ValueError, match=r"'session:x1': a session id is digits"):
        read_prior_from(["session:x1"])
    long = "é" * 5000
    with pytest.raises(ValueError) as refused:
        read_prior_from([long])
    assert len(str(refused.value)) < 300  # a pasted megabyte is not echoed back whole


def test_session_new_and_show_name_the_sessions_a_warm_start_read(tmp_path: Path) -> None:
    """A subject code names every session of the subject: neither ``session new`` nor ``session
    show`` (text or --json) said which sessions (and up to which event) the model took in, so an
    operator could not tell what a warm start was made of without reading the events."""
    from typer.testing import CliRunner

    from gaitpref.cli import app

    url = f"sqlite:///{tmp_path / 's.db'}"
    ids = _earlier(url)
    args = ["session", "new", "--config", CONFIG, "--subject", "S03", "--db", url]
    made = CliRunner().invoke(app, [*args, "--prior-from", "S01", "--prior-from", str(ids[2])])
    assert made.exit_code == 0, made.output
    new_id = int(made.output.split()[1].rstrip(":"))
    with Session.open(url, new_id) as s:
        prior = s.record.meta["prior_from"]
        rho = s.record.meta["prior_rho"]
    said = ", ".join(
        f"session {p['session']} ({p['subject']}) to event {p['last_seq']}" for p in prior
    )
    assert f"warm-started from 3 earlier sessions: {said}; rho {rho:.2f}" in made.output
    show = ["session", "show", str(new_id), "--no-figure", "--db", url]
    shown = CliRunner().invoke(app, show)
    assert shown.exit_code == 0, shown.output
    assert f"warm-started from 3 earlier sessions: {said}" in shown.output
    info = json.loads(CliRunner().invoke(app, [*show, "--json"]).output)
    assert info["prior_from"] == prior and info["prior_rho"] == rho
    cold = json.loads(
        CliRunner()
        .invoke(app, ["session", "show", str(ids[0]), "--no-figure", "--json", "--db", url])
        .output
    )
    assert cold["prior_from"] == [] and cold["prior_rho"] is None
    text = CliRunner().invoke(app, ["session", "show", str(ids[0]), "--no-figure", "--db", url])
    assert "warm-started" not in text.output
    for _ in range(13):  # a subject code may name 256: past 12 the rest are counted
        Session.create(url, CONFIG, "S05").close()
    many = CliRunner().invoke(app, [*args[:5], "S06", *args[6:], "--prior-from", "S05"])
    assert many.exit_code == 0, many.output
    assert "warm-started from 13 earlier sessions: session " in many.output
    assert "and 1 more (session show --json lists them)" in many.output


def test_a_subject_code_over_two_grids_says_which_sessions_could_be_named() -> None:
    """A subject walked in two protocols could not be named by code in either: the refusal
    named one session on the other grid and left the operator to find the others by hand."""
    db = MemoryStorage()
    ids = _earlier(db)  # S01: ids[0], ids[1]; S02: ids[2], on CONFIG's grid
    other = Session.create(db, "exo-2d-length-duration", "S01")
    other.close()
    with pytest.raises(
        ValueError, match=rf"session {other.id} \(subject S01\) was run on another"
    ) as e:
        Session.create(db, CONFIG, "S03", prior_from=["S01"])
    assert f"named by session id instead: {ids[0]}, {ids[1]})" in str(e.value)
    with pytest.raises(ValueError, match="none of subject S02's sessions was run on this grid"):
        Session.create(db, "exo-2d-length-duration", "S03", prior_from=["S02"])
    with pytest.raises(ValueError, match=r"needs the same$"):  # an id names one: nothing to add
        Session.create(db, "exo-2d-length-duration", "S03", prior_from=[ids[2]])
    made = Session.create(db, CONFIG, "S03", prior_from=ids[:2])  # as the refusal says
    assert [p["session"] for p in made.record.meta["prior_from"]] == ids[:2]
