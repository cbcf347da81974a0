""" "Best so far" names a gait that may be walked: the highest posterior mean among the gaits that
may be proposed (``Session.recommended``, the gait the confidence recommends), never one flagged
unsafe, near one, or in the region of avoidance; ``argmax`` stays the unrestricted highest."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from gaitpref import Session
from gaitpref.cli import app
from gaitpref.config import parse_config
from gaitpref.loop.safety import near
from gaitpref.sessions import posterior_summary, preference_learned
from tests.sessions.unsafekit import unsafe_config

runner = CliRunner()


def _show(url: str, sid: int) -> tuple[str, dict[str, object]]:
    text = runner.invoke(app, ["session", "show", str(sid), "--no-figure", "--db", url])
    assert text.exit_code == 0, text.output
    out = runner.invoke(app, ["session", "show", str(sid), "--json", "--no-figure", "--db", url])
    assert out.exit_code == 0, out.output
    return text.output, json.loads(out.output)


def _session_with_a_walked_argmax(url: str, radius: float) -> tuple[Session, int]:
    """A session whose posterior argmax is a gait walked in trial ``number`` (returned): the
    subject prefers the longer step each time."""
    s = Session.create(url, parse_config(unsafe_config("best-1d", radius)), "S01")
    for _ in range(12):
        q = s.next_query()
        a, b = q.actions[0], q.buffer[0] if q.buffer else q.actions[0]
        if a != b:
            s.answer(q.id, [(a, b, "first" if a > b else "second")])
        else:
            s.answer(q.id, [])
        best = s.posterior().argmax
        walked = [t.number for t in s.trials() if t.action == best]
        if walked and s.posterior().mean[best] > np.median(s.posterior().mean):
            return s, walked[-1]
    raise AssertionError("the posterior's argmax was never a walked gait")


def test_a_gait_flagged_unsafe_at_the_argmax_is_not_the_best_so_far(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'b.db'}"
    s, number = _session_with_a_walked_argmax(url, 0.1)
    best = s.posterior().argmax
    assert s.recommended() == best  # nothing flagged yet: the same gait
    s.flag_unsafe(number, "knee gave way")
    banned = near(s.space, {best}, 0.1)
    rec = s.recommended()
    assert rec is not None and rec != best and not banned[rec]
    mean = np.asarray(s.posterior().mean)
    assert mean[rec] == mean[~banned].max()
    assert rec == s.confidence().recommended  # what the confidence sentence names
    summary = posterior_summary(s)
    assert summary["argmax"] == best  # unchanged: the export's import check compares it
    assert summary["recommended"] == rec
    assert summary["recommended_values"] == s.space.values_of(rec)
    assert summary["mean_at_recommended"] == float(mean[rec])
    sid = s.id
    s.close()
    text, info = _show(url, sid)
    posterior = info["posterior"]
    assert isinstance(posterior, dict)
    assert posterior["argmax"] == best and posterior["recommended"] == rec
    assert f"best so far: G{rec} (action {rec}: " in text
    assert f"(action {best}: " not in text
    assert f"G{best} (action {best}), may not be proposed" in text


def test_no_best_so_far_when_no_gait_may_be_proposed(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'b.db'}"
    s, number = _session_with_a_walked_argmax(url, 1.0)  # a flag bans the whole line
    s.flag_unsafe(number, "knee gave way")
    assert s.recommended() is None
    summary = posterior_summary(s)
    assert summary["argmax"] == s.posterior().argmax
    assert all(
        summary[k] is None
        for k in (
            "recommended",
            "recommended_values",
            "recommended_gait_id",
            "mean_at_recommended",
            "sd_at_recommended",
        )
    )
    sid = s.id
    s.close()
    text, info = _show(url, sid)
    posterior = info["posterior"]
    assert isinstance(posterior, dict) and posterior["recommended"] is None
    assert "best so far: none may be recommended" in text
    assert "(action " not in text


def test_no_best_so_far_before_a_preference_is_learned(tmp_path: Path) -> None:
    """0 trials: the flat prior's argmax is the first gait for no reason; ``session show`` says
    what the console says (the same condition), and ``--json`` keeps its documented fields."""
    url = f"sqlite:///{tmp_path / 'b.db'}"
    s = Session.create(url, parse_config(unsafe_config("best-1d", 0.1)), "S01")
    assert not preference_learned(s.posterior().mean) and not s.trials()
    sid = s.id
    s.close()
    text, info = _show(url, sid)
    assert "no preference learned yet: every gait is as likely to be the best" in text
    assert "(action " not in text and "posterior mean 0" not in text
    posterior = info["posterior"]
    assert isinstance(posterior, dict)
    assert posterior["recommended"] == 0 and posterior["argmax"] == 0  # as documented
    assert posterior["trials_in_force"] == 0
    assert posterior["learned"] is False  # what tells a client that 0 is no recommendation


def test_learned_turns_true_with_the_first_preference_and_agrees_with_the_text(
    tmp_path: Path,
) -> None:
    """``--json``'s ``learned`` is False exactly while the text says "none yet": before any
    answer, and after a tie (the mean stays flat); one strict preference makes both name a
    gait."""
    url = f"sqlite:///{tmp_path / 'b.db'}"
    s = Session.create(url, parse_config(unsafe_config("best-1d", 0.1)), "S01")
    sid = s.id
    q = s.next_query()
    assert not q.buffer  # the first trial has nothing to be compared with
    s.answer(q.id, [])
    assert s.trials() and posterior_summary(s)["learned"] is False  # a trial, no preference
    q = s.next_query()
    a, b = q.actions[0], q.buffer[0]
    assert a != b
    s.answer(q.id, [(a, b, "none")])  # a tie: nothing told apart
    assert not preference_learned(s.posterior().mean)
    assert posterior_summary(s)["learned"] is False
    s.close()
    text, info = _show(url, sid)
    posterior = info["posterior"]
    assert isinstance(posterior, dict) and posterior["learned"] is False
    assert posterior["recommended"] == 0 and posterior["trials_in_force"] == 2  # kept as it was
    assert "best so far: none yet (no preference learned yet" in text
    s = Session.open(url, sid)
    q = s.next_query()
    a, b = q.actions[0], q.buffer[0]
    assert a != b
    s.answer(q.id, [(a, b, "first")])  # one preference
    assert preference_learned(s.posterior().mean)
    summary = posterior_summary(s)
    assert summary["learned"] is True and summary["recommended"] == s.recommended()
    s.close()
    text, info = _show(url, sid)
    posterior = info["posterior"]
    assert isinstance(posterior, dict) and posterior["learned"] is True
    assert "none yet" not in text
    rec = posterior["recommended"]
    assert f"best so far: G{rec} (action {rec}: " in text


def test_the_console_and_show_share_the_learned_condition() -> None:
    assert not preference_learned(np.zeros(4)) and not preference_learned(np.zeros(0))
    assert preference_learned(np.array([0.0, 0.1, 0.0]))
