"""The terminal with a ``[stop]`` rule: the confidence after every answer, then validation."""

from __future__ import annotations

from pathlib import Path

import pexpect

from gaitpref import Session
from gaitpref.config import load_config
from tests.sessions.sessionkit import CONFIG
from tests.sessions.test_terminal import _answer, _spawn


def test_the_terminal_shows_the_confidence_and_moves_to_validation(tmp_path: Path) -> None:
    config = tmp_path / "stop.toml"
    config.write_text(load_config(CONFIG).text + "\n[stop]\nmax_trials = 2\n", encoding="utf-8")
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(url, config, "S01", seed=3).close()
    child = _spawn("session", "run", "1", "--db", url)
    child.expect(r"Trial 1: run G\d+")
    _answer(child, None, "2")
    child.expect("saved: trial 1")
    child.expect(r"\d+% that G\d+ is within 5% of the best")
    child.expect(r"Trial 2: run G\d+")
    _answer(child, "1", "0")
    child.expect("saved: trial 2")
    child.expect(r"\d+% that G\d+ is within 5% of the best")
    # the rule says why it opens the round (nothing did: the round followed the saved answer)
    child.expect_exact(
        "the [stop] rule says stop (2 trials reached max_trials = 2): blind validation opens"
    )
    child.expect("Blind validation, round 1")  # max_trials = 2: the rule opened it
    child.sendline("q")
    child.expect(pexpect.EOF)
    child = _spawn("session", "run", "1", "--db", url)  # resumed at the round: says why too
    child.expect("2 trials so far")
    child.expect_exact("the [stop] rule says stop (2 trials reached max_trials = 2)")
    child.expect("Blind validation, round 1")
    child.sendline("q")
    child.expect(pexpect.EOF)


def test_without_a_rule_the_terminal_still_shows_the_confidence(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(url, CONFIG, "S01", seed=3).close()
    child = _spawn("session", "run", "1", "--db", url)
    child.expect(r"Trial 1: run G\d+")
    _answer(child, None, "2")  # a suggestion: something learnt
    child.expect("saved: trial 1")
    child.expect(r"\d+% that G\d+ is within 5% of the best")
    child.expect(r"Trial 2: run G\d+")
    child.sendline("q")
    child.expect(pexpect.EOF)


def test_the_terminal_goes_on_when_an_answer_leaves_no_gait_to_recommend(tmp_path: Path) -> None:
    """A 'very bad' that puts every gait in the region: the terminal crashed with a ValueError
    traceback ('no gait is allowed') after the answer was written."""
    from tests.sessions.test_stopping import RATED

    config = tmp_path / "rated.toml"
    config.write_text(RATED, encoding="utf-8")
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(url, config, "S01").close()
    child = _spawn("session", "run", "1", "--db", url)
    child.expect(r"Trial 1: run G\d+")
    child.expect(r"Rating of trial 1: 1 very bad")
    child.sendline("1")
    child.expect(r"Suggestion for step_length")
    child.sendline("0")
    child.expect(r"Write: .*y yes, n re-enter")
    child.sendline("y")
    child.expect("saved: trial 1")
    child.expect("no gait may be proposed")
    child.expect(pexpect.EOF)
    assert "Traceback" not in (child.before or "")


def test_with_a_rule_the_terminal_states_no_confidence_before_anything_is_learnt(
    tmp_path: Path,
) -> None:
    """With a ``[stop]`` rule the terminal stated the confidence after an answer that taught
    nothing ("23% that G0 is within 5% of the best": the first gait, for no reason), where the
    console and ``session show`` say no preference is learned yet."""
    config = tmp_path / "stop.toml"
    config.write_text(load_config(CONFIG).text + "\n[stop]\nmax_trials = 5\n", encoding="utf-8")
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(url, config, "S01", seed=3).close()
    child = _spawn("session", "run", "1", "--db", url)
    child.expect(r"Trial 1: run G\d+")
    _answer(child, None, "0")  # no suggestion: nothing learnt
    child.expect("saved: trial 1")
    child.expect(r"Trial 2: run G\d+")
    assert "% that G" not in child.before
    _answer(child, "1", "0")  # a preference: learnt
    child.expect("saved: trial 2")
    child.expect(r"\d+% that G\d+ is within 5% of the best")
    child.sendline("q")
    child.expect(pexpect.EOF)
