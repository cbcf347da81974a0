"""The session's confidence and its ``[stop]`` rule: blind validation opens when it says so."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from gaitpref import Rating, Session
from gaitpref.config import ExperimentConfig, load_config, parse_config
from gaitpref.errors import ConfigError, NoSafeGaitError
from gaitpref.sessions import StopCheckWarning, export_session
from gaitpref.sessions.demo import SimulatedSubject
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive, state_of


def _config(stop: str) -> ExperimentConfig:
    return parse_config(load_config(CONFIG).text + "\n[stop]\n" + stop, default_name=CONFIG)


def test_max_trials_opens_blind_validation_once_and_replays(drive: Drive) -> None:
    db = MemoryStorage()
    s = Session.create(db, _config("max_trials = 4\n"), "S01")
    drive(s, 3)
    assert s.validation_plan is None and s.stop_reason() is None
    drive(s, 1)
    assert s.stop_reason() == "4 trials reached max_trials = 4"
    plan = s.validation_plan
    assert plan is not None and plan.round == 1
    again = Session.open(db, s.id)
    assert again.validation_plan == plan  # logged, and replayed
    s.answer_validation(1, "ABC")
    drive(s, 2)  # the operator may go on: the rule does not reopen validation
    assert s.validation_plan is None and len(s.validations()) == 1


def test_confidence_rule_opens_validation_when_the_model_is_sure_enough(drive: Drive) -> None:
    s = Session.create(MemoryStorage(), _config("confidence = 0.5\ntolerance = 0.1\n"), "S01")
    for _ in range(40):
        if s.validation_plan is not None:
            break
        before = s.confidence().probability
        assert before < 0.5
        drive(s, 1)
    assert s.validation_plan is not None, "the rule never triggered in 40 answers"
    sure = s.confidence()
    assert sure.probability >= 0.5
    # the reason names the gait as the confidence sentence does (it said "gait 12", not "G12")
    sentence = sure.sentence(s.gait_name(sure.recommended))
    assert s.stop_reason() == f"{sentence} (confidence = 50%)"


def test_confidence_is_reproducible_and_leaves_the_loop_alone(drive: Drive) -> None:
    s = Session.create(MemoryStorage(), CONFIG, "S01")
    drive(s, 5)
    mean, _var, query, rng = state_of(s)
    first, second = s.confidence(), s.confidence()
    assert first == second
    assert state_of(s)[2:] == (query, rng)
    assert first.recommended == int(np.argmax(mean))
    assert first.sentence("G7").endswith("that G7 is within 5% of the best")
    assert s.stop_reason() is None  # no [stop] table, no rule


def test_a_bad_stop_table_names_the_key() -> None:
    with pytest.raises(ConfigError, match=r"\[stop\]\.confidence"):
        _config("confidence = 1.5\n")
    with pytest.raises(ConfigError, match=r"\[stop\]"):
        _config("patience = 3\n")


RATED = """
name = "rated-5"
[space.step_length]
min = 0.08
max = 0.18
num = 5
[model]
lengthscale = 0.2
signal_variance = 0.005
noise = 0.02
[cospar]
seed = 2
strategy = "self-sparring"
[feedback.rating]
labels = ["very bad", "bad", "okay", "good"]
[safety]
avoid = ["very bad"]
cautious = 0
[stop]
confidence = 0.9
"""


def test_an_answer_that_leaves_no_gait_to_recommend_is_written_and_states_no_confidence(
    tmp_path: Path,
) -> None:
    """One 'very bad' on a five-gait grid this smooth puts every gait in the region: the
    answer was written, then the [stop] rule's confidence raised ValueError('no gait is
    allowed') from answer(); the export (the confidence table) failed the same way."""
    from fastapi.testclient import TestClient

    from gaitpref.console import create_app

    url = f"sqlite:///{tmp_path / 's.db'}"
    s = Session.create(url, parse_config(RATED), "S01")
    q = s.next_query()
    s.answer(q.id, [Rating(q.actions[0], "very bad")])
    assert [e.kind for e in s.events()][-1] == "rating_given"
    assert s.stop_reason() is None and s.validation_plan is None
    with pytest.raises(NoSafeGaitError):
        s.next_query()
    with pytest.raises(NoSafeGaitError, match="no gait may be recommended"):
        s.confidence()
    assert s.confidence_history() == []
    export_session(s, tmp_path / "export", fmt="json")
    client = TestClient(create_app(url))
    got = client.get(f"/api/sessions/{s.id}/posterior")
    assert got.status_code == 200 and got.json()["confidence"] is None
    assert client.get(f"/sessions/{s.id}").status_code == 200


def test_a_rule_that_says_stop_with_fewer_than_three_gaits_to_show_says_why_it_cannot_act(
    tmp_path: Path,
) -> None:
    """A flag whose radius leaves two gaits: the rule said stop after every answer, and the
    round it tried to open was refused in silence; the session went on as if it had no rule."""
    url = f"sqlite:///{tmp_path / 's.db'}"
    text = "\n[safety]\nunsafe_radius = 0.45\n[stop]\nconfidence = 0.6\n"
    s = Session.create(url, parse_config(load_config(CONFIG).text + text), "S01")

    def answer() -> None:
        q = s.next_query()
        s.answer(q.id, [], [(q.actions[0], "step_length", "+small")])

    for _ in range(3):
        answer()
    assert s.stop_blocked() is None  # the rule does not say stop yet
    s.flag_unsafe(1, "knee")
    allowed = s._state.loop.allowed()
    assert allowed is not None and allowed.sum() == 2
    for _ in range(2):
        answer()
        reason = s.stop_reason()
        assert reason is not None and s.validation_plan is None
        blocked = s.stop_blocked()
        assert blocked is not None
        assert f"the [stop] rule says stop ({reason})" in blocked
        assert "needs at least 3 gaits; 2 may be shown" in blocked
        assert "Finish the session" in blocked
    assert not any(e.kind.startswith("validation") for e in s.events())  # nothing written
    s.withdraw_unsafe(1)  # the gaits are back: a round can be drawn
    assert s.stop_blocked() is None
    answer()  # the rule opens it if it still says stop (the confidence is over 15 gaits again)
    assert (s.validation_plan is not None) == (s.stop_reason() is not None)


def test_max_trials_with_nothing_learnt_says_why_no_round_opens() -> None:
    s = Session.create(MemoryStorage(), _config("max_trials = 1\n"), "S01")
    q = s.next_query()
    s.answer(q.id, [])  # no comparison (no buffer yet), no suggestion: nothing learnt
    # one trial: "1 trial" (it said "1 trials")
    assert s.stop_reason() == "1 trial reached max_trials = 1" and s.validation_plan is None
    blocked = s.stop_blocked()
    assert blocked is not None and "the posterior mean is flat" in blocked
    s.finish()  # the operator decided: nothing left to say
    assert s.stop_blocked() is None


@pytest.mark.parametrize(
    "error",
    [
        FloatingPointError("the confidence's samples are not finite"),
        NoSafeGaitError("no gait may be recommended"),
        KeyboardInterrupt(),
    ],
    ids=["numerical", "no-safe-gait", "ctrl-c"],
)
def test_a_failed_stop_check_after_an_answer_is_a_warning_not_a_failure(
    drive: Drive, monkeypatch: pytest.MonkeyPatch, error: BaseException
) -> None:
    """The [stop] rule runs after the answer is stored: when it raises, the answer is stored
    once and reported as stored (a caller told it failed would answer again), with a
    StopCheckWarning saying why; the rule is checked again after the next answer."""
    db = MemoryStorage()
    s = Session.create(db, _config("max_trials = 4\n"), "S01")
    drive(s, 3)
    q = s.next_query()
    comparisons = [(q.actions[0], q.buffer[0], "first")] if q.buffer else []

    def fails(self: Session) -> None:
        raise error

    with monkeypatch.context() as patch:
        patch.setattr(Session, "_stop_if_sure", fails)
        with pytest.warns(StopCheckWarning, match="could not be checked") as caught:
            answered = s.answer(q.id, comparisons)
    assert answered.query == q.id and answered.trials == q.trials
    assert answered.stop_warning is not None
    assert f"the answer to query {q.id} is stored" in answered.stop_warning
    assert type(error).__name__ in answered.stop_warning
    assert str(caught[0].message) == answered.stop_warning
    walked = [e for e in db.events(s.id) if e.kind == "trial_executed"]
    assert len(walked) == 4 and walked[-1].seq in answered.seqs  # stored, exactly once
    assert s.pending is None and len(s.trials()) == 4
    assert s.validation_plan is None  # the rule did not act: its check failed
    again = Session.open(db, s.id)  # the log replays as written
    assert len(again.trials()) == 4 and again.pending is None
    drive(s, 1)  # the next answer checks the rule again: it opens the round
    plan = s.validation_plan
    assert plan is not None and plan.round == 1


def test_a_stop_check_that_runs_warns_nothing(drive: Drive) -> None:
    s = Session.create(MemoryStorage(), _config("max_trials = 2\n"), "S01")
    drive(s, 1)
    q = s.next_query()
    answered = s.answer(q.id, [(q.actions[0], q.buffer[0], "first")] if q.buffer else [])
    assert answered.stop_warning is None and s.validation_plan is not None


def test_the_terminal_says_a_failed_stop_check_after_saved(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The terminal says the answer is saved, then why the rule could not be checked (not as a
    Python warning), and goes on to the next trial."""
    from io import StringIO

    from rich.console import Console

    from gaitpref.terminal import Terminal

    def fails(self: Session) -> None:
        raise FloatingPointError("the confidence's samples are not finite")

    monkeypatch.setattr(Session, "_stop_if_sure", fails)
    s = Session.create(MemoryStorage(), _config("max_trials = 1\n"), "S01")
    out = StringIO()
    keys = ["2", "y"]  # trial 1: "slightly longer", write it; then q
    with warnings.catch_warnings():
        warnings.simplefilter("error", StopCheckWarning)  # the terminal says it itself
        Terminal(s, Console(file=out, width=400), read=lambda _: keys.pop(0) if keys else "q").run()
    text = out.getvalue()
    said = "saved: trial 1\n  warning: the answer to query "
    assert said in text and "could not be checked after it (FloatingPointError" in text
    assert "Trial 2: run" in text and len(s.trials()) == 1


def test_the_answer_after_which_the_rule_opens_validation_says_why(
    subject: SimulatedSubject,
) -> None:
    """The rule opened blind validation after an answer and nothing said so, or why: the
    terminal showed a round straight after the saved answer, the console an open round."""
    s = Session.create(MemoryStorage(), _config("max_trials = 3\n"), "S01")
    said = []
    for _ in range(4):
        if s.validation_plan is not None:
            break
        q = s.next_query()
        said.append(s.answer(q.id, *subject.respond(q)).stopped)
    assert said == [None, None, "3 trials reached max_trials = 3"]
    s.answer_validation(1, "ABC")
    q = s.next_query()  # the rule does not reopen it: nothing to say
    assert s.answer(q.id, *subject.respond(q)).stopped is None
    cold = Session.create(MemoryStorage(), CONFIG, "S01")  # no rule: never
    q = cold.next_query()
    assert cold.answer(q.id, *subject.respond(q)).stopped is None


def test_the_confidence_sentence_never_shows_a_threshold_it_has_not_reached() -> None:
    """The probability was rounded to the nearest percent: 0.897 read "90%" while a
    ``confidence = 0.9`` rule went on, and a tolerance of 0.025 read "within 2%" (2.5% used),
    a ``confidence = 0.999`` "(confidence = 100%)"."""
    from gaitpref.loop.stopping import Confidence, StopRule

    def sure(p: float, tol: float = 0.05) -> Confidence:
        return Confidence(3, p, 0.1, 0.1, tol, 2000)

    assert sure(0.897).sentence("G3") == "89% that G3 is within 5% of the best"
    assert StopRule(confidence=0.9).reason(5, sure(0.897)) is None
    assert sure(0.9).sentence("G3").startswith("90% ")
    assert sure(0.29).sentence("G3").startswith("29% ")  # 28.999... in floating point
    assert sure(0.9995).sentence("G3").startswith("99% ") and sure(1.0).sentence("G3")[:4] == "100%"
    assert sure(0.5, 0.025).sentence("G3") == "50% that G3 is within 2.5% of the best"
    assert StopRule(confidence=0.999).reason(5, sure(0.9995), "G3") == (
        "99% that G3 is within 5% of the best (confidence = 99.9%)"
    )
    assert StopRule(confidence=0.9).reason(5, sure(0.9), "G3") == (
        "90% that G3 is within 5% of the best (confidence = 90%)"
    )


def test_the_rule_reads_the_confidence_the_session_keeps(
    drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``stop_reason()`` drew the samples again after ``confidence()`` on the same state (the
    console's page with an open round asks both: about 1 s each on a large grid)."""
    from gaitpref.sessions import confidence as module
    from gaitpref.sessions import session as session_module

    s = Session.create(MemoryStorage(), _config("confidence = 0.99\n"), "S01")
    drive(s, 3)
    calls = []
    real = module.session_confidence

    def counted(*args: object, **kwargs: object) -> object:
        calls.append(1)
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(module, "session_confidence", counted)
    monkeypatch.setattr(session_module, "session_confidence", counted)
    sure = s.confidence()  # kept since the answer's own stop check, or drawn now
    drawn = len(calls)
    assert drawn <= 1
    assert s.stop_reason() is None and s.stop_reason() is None
    assert len(calls) == drawn and s.confidence() is sure


def test_the_confidence_rule_does_not_act_before_a_preference_is_learned() -> None:
    """After an answer that taught nothing the rule said stop on the flat posterior's
    confidence ("23% that G0 ...": the first gait, for no reason), and stop_blocked reported it
    after the answer, where no confidence is shown."""
    s = Session.create(MemoryStorage(), _config("confidence = 0.2\n"), "S01")
    q = s.next_query()
    s.answer(q.id, [], [])  # a first trial with no suggestion: nothing learnt
    assert np.ptp(s.posterior().mean) == 0.0
    assert s.stop_reason() is None and s.stop_blocked() is None
    both = Session.create(MemoryStorage(), _config("confidence = 0.2\nmax_trials = 1\n"), "S01")
    q = both.next_query()
    both.answer(q.id, [], [])  # max_trials still counts: said, and why no round can open
    assert both.stop_reason() == "1 trial reached max_trials = 1"
    blocked = both.stop_blocked()
    assert blocked is not None and "posterior mean is flat" in blocked
