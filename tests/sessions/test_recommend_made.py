"""Gaits made on demand, defaults 0.13 (``[gaits] recommend = "made"``): the recommendation is the
best gait the session made, not the model's best point, which on a continuous space is often a
point only a coactive suggestion named (its gait was never made and may not exist).  The
confidence, the ``[stop]`` rule, blind validation and the export's confidence table read that
gait; a session recorded under earlier defaults recommends the best point as it did; a config
without a generator is unchanged.

The sessions: :data:`~tests.sessions.gaitkit.CONTINUOUS` (the stand-in generator, the line path)
with three answers: each new gait preferred to the one before, then "longer" from the third, a
point whose gait is not made and which the model ranks highest."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref import Session
from gaitpref.cli import app
from gaitpref.config import DEFAULTS_VERSION, ConfigError, parse_config, shipped_configs
from gaitpref.config.schema import EARLIER_DEFAULTS
from gaitpref.loop.stopping import confidence
from gaitpref.sessions.confidence import CONFIDENCE_STREAM
from gaitpref.sessions.gaits import NOT_MADE
from gaitpref.sessions.stored_config import library_meta
from gaitpref.storage import MemoryStorage
from tests.sessions.gaitkit import CONFIG, CONTINUOUS

runner = CliRunner()
OLD = "0.12"  # the defaults before recommend = "made"


def _drive(s: Session, stop: bool = False) -> list[str | None]:
    """Three answers: each new gait preferred, then "longer" from the third (see the module)."""
    answered = []
    for k in range(3):
        q = s.next_query()
        a, b = q.actions[0], q.buffer[0] if q.buffer else None
        comparisons = [] if b is None or a == b else [(a, b, "first")]
        suggestions = [(a, "step_length", "+big")] if k == 2 else []
        answered.append(s.answer(q.id, comparisons, suggestions).stopped)
    return answered


def _session(db: object, defaults: str = DEFAULTS_VERSION, text: str = CONTINUOUS) -> Session:
    return Session.create(db, parse_config(text, defaults=defaults), "S01")  # type: ignore[arg-type]


def _made(s: Session) -> list[int]:
    return [a for a in range(len(s.space)) if s.gait_made(a)]


def test_the_best_made_gait_is_recommended_not_a_point_only_suggested() -> None:
    with _session(MemoryStorage()) as s:
        _drive(s)
        mean = np.asarray(s.posterior().mean)
        top = int(np.argmax(mean))
        assert s.gait_made(top) is False  # the suggested point: the model's best, not made
        made = _made(s)
        assert len(made) == 3 and top not in made
        rec = s.recommended()
        assert rec == made[int(np.argmax(mean[made]))] and rec != top
        assert s.gait_made(rec) is True
        assert s.no_recommendation() is None
        sure = s.confidence()
        assert sure.recommended == rec
        # "the best" is still sought over every point, made or not: exploring more may pay
        post = s.posterior()
        among = np.zeros(len(s.space), dtype=bool)
        among[made] = True

        def rng() -> np.random.Generator:
            seq = np.random.SeedSequence(s.seed, spawn_key=(CONFIDENCE_STREAM, 3))
            return np.random.default_rng(seq)

        assert sure == confidence(post, rng(), among=among)
        unrestricted = confidence(post, rng())
        assert unrestricted.recommended == top
        assert sure.probability < unrestricted.probability


def test_old_defaults_recommend_the_best_point_as_before(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with _session(url, OLD) as s:
        assert s.record.meta["config_defaults"] == OLD
        _drive(s)
        top = int(np.argmax(np.asarray(s.posterior().mean)))
        assert s.recommended() == top and s.gait_made(top) is False
        sure, history, sid = s.confidence(), s.confidence_history(), s.id
        # the numbers of the rule before defaults 0.13: every point, made or not
        seq = np.random.SeedSequence(s.seed, spawn_key=(CONFIDENCE_STREAM, 3))
        assert sure == confidence(s.posterior(), np.random.default_rng(seq))
    with Session.open(url, sid) as again:  # replayed with the defaults it was recorded with
        assert again.config.generator is not None and again.config.generator.recommend == "any"
        assert again.recommended() == top
        assert again.confidence() == sure and again.confidence_history() == history


def test_a_new_session_replays_with_the_made_rule(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with _session(url) as s:
        assert s.record.meta["config_defaults"] == DEFAULTS_VERSION
        _drive(s)
        rec, sure, history, sid = s.recommended(), s.confidence(), s.confidence_history(), s.id
    with Session.open(url, sid) as again:
        assert again.recommended() == rec and again.confidence() == sure
        assert again.confidence_history() == history


def test_every_earlier_defaults_version_recommends_any_point() -> None:
    for version in EARLIER_DEFAULTS:  # a session with no config_defaults replays under "0.1"
        spec = parse_config(CONTINUOUS, defaults=version).generator
        assert spec is not None and spec.recommend == "any", version
    spec = parse_config(CONTINUOUS).generator
    assert spec is not None and spec.recommend == "made" and DEFAULTS_VERSION == "0.13"
    given = CONTINUOUS.replace("avoid_radius = 0.1\n", 'avoid_radius = 0.1\nrecommend = "any"\n')
    spec = parse_config(given).generator  # set explicitly: the earlier rule, any defaults
    assert spec is not None and spec.recommend == "any"
    assert "gaits.recommend" not in parse_config(given).defaulted


def test_the_export_table_and_the_stop_rule_read_the_made_gait() -> None:
    stop = "\n[stop]\nconfidence = 0.5\n"  # made: about 0.2, below; any point: about 0.67
    with _session(MemoryStorage(), text=CONTINUOUS + stop) as s:
        assert _drive(s) == [None, None, None]
        assert s.validation_plan is None and s.stop_reason() is None
        made = set(_made(s))
        rows = [r for r in s.confidence_history() if r["learned"]]
        assert rows and all(r["action"] in made and r["made"] is True for r in rows)
    with _session(MemoryStorage(), OLD, CONTINUOUS + stop) as s:
        stopped = _drive(s)
        assert stopped[-1] is not None  # the rule opened blind validation at the third answer
        top = s.recommended()
        said = stopped[-1]
        assert said is not None  # the rule opened blind validation at the third answer
        assert top is not None and s.gait_made(top) is False and s.gait_name(top) in said
        last = s.confidence_history()[-1]
        assert last["action"] == top and last["made"] is False


def test_the_stop_rule_names_the_made_gait_and_validation_shows_it_as_max() -> None:
    stop = "\n[stop]\nconfidence = 0.15\n"
    with _session(MemoryStorage(), text=CONTINUOUS + stop) as s:
        stopped = _drive(s)
        rec = s.recommended()
        assert rec is not None and s.gait_made(rec) is True
        said = stopped[-1]
        assert said is not None and s.gait_name(rec) in said
        started = [e for e in s.events() if e.kind == "validation_started"]
        assert len(started) == 1
        roles = {g["role"]: g["action"] for g in started[0].payload["gaits"]}
        assert roles["max"] == rec


def test_no_gait_made_yet_is_said_rather_than_a_recommendation(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with _session(url, text=CONFIG) as s:  # a grid: the posterior has its points at once
        assert s.recommended() is None
        why = s.no_recommendation()
        assert why is not None and "no gait has been made yet" in why
        q = s.next_query()
        s.answer(q.id, [], [(q.actions[0], "step_length", "+big")])
        assert s.recommended() == q.actions[0] and s.no_recommendation() is None
        s.flag_unsafe(q.trials[0], "stumbled")  # the only gait made may not be walked now
        assert s.recommended() is None
        why = s.no_recommendation()
        assert why is not None and "every gait made so far" in why
        sid = s.id
    out = runner.invoke(app, ["session", "show", str(sid), "--no-figure", "--db", url])
    assert out.exit_code == 0, out.output
    assert f"best so far: none may be recommended ({why})" in " ".join(out.output.split())
    from fastapi.testclient import TestClient

    from gaitpref.console.app import create_app

    with TestClient(create_app(url)) as client:
        post = client.get(f"/api/sessions/{sid}/posterior").json()
    assert post["recommended"] is None and post["no_recommendation"] == why
    with _session(MemoryStorage(), OLD, CONFIG) as s:  # before: the flat prior's first gait
        assert s.recommended() == 0 and s.no_recommendation() is None


@pytest.mark.parametrize("name", shipped_configs())
def test_configs_without_a_generator_are_unchanged(name: str) -> None:
    from gaitpref.config import load_config

    new = load_config(name)
    if new.generator is not None:
        assert new.generator.recommend == "made"
        return
    old = parse_config(new.text, name, base_dir=new.base_dir, defaults=OLD)
    assert dataclasses.replace(old, defaults_version=DEFAULTS_VERSION) == new
    assert old.defaulted == new.defaulted and "gaits.recommend" not in new.defaulted
    meta = library_meta(new)
    assert meta.get("config_defaults", DEFAULTS_VERSION) == DEFAULTS_VERSION
    assert library_meta(old).get("config_defaults", OLD) == OLD


def test_a_library_takes_no_recommend_key() -> None:
    text = (
        '[gaits]\nlibrary = "gaits.json"\nrecommend = "made"\n'
        "[model]\nlengthscale = 0.1\nsignal_variance = 0.005\nnoise = 0.02\n"
    )
    with pytest.raises(ConfigError, match=r"\[gaits\]\.recommend: is a gait generator's setting"):
        parse_config(text)
    with pytest.raises(ConfigError, match="recommend"):
        parse_config(CONTINUOUS.replace("avoid_radius = 0.1\n", 'recommend = "best"\n'))


def test_a_generator_spec_checks_recommend() -> None:
    from gaitpref.config.generator import GeneratorSpec

    assert GeneratorSpec("x", recommend="any").recommends_made is False
    assert GeneratorSpec("x").recommends_made is True
    with pytest.raises(ValueError, match="recommend must be one of made, any, got 'best'"):
        GeneratorSpec("x", recommend="best")


def test_among_must_name_a_gait() -> None:
    with _session(MemoryStorage()) as s:
        _drive(s)
        post, size = s.posterior(), len(s.space)
        with pytest.raises(ValueError, match="among names no gait"):
            confidence(post, np.random.default_rng(5), among=np.zeros(size, dtype=bool))
        with pytest.raises(ValueError, match="among must be None or a boolean mask"):
            confidence(post, np.random.default_rng(5), among=np.ones(size + 1, dtype=bool))
        allowed = np.ones(size, dtype=bool)
        allowed[0] = False
        only_first = np.zeros(size, dtype=bool)
        only_first[0] = True
        with pytest.raises(ValueError, match="no gait of among is allowed"):
            confidence(post, np.random.default_rng(5), allowed=allowed, among=only_first)


def test_session_show_and_the_console_name_the_made_gait(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with _session(url) as s:
        _drive(s)
        rec = s.recommended()
        top = int(np.argmax(np.asarray(s.posterior().mean)))
        assert rec is not None and rec != top
        sid, name, unmade = s.id, s.gait_name(rec), s.gait_name(top)
    out = runner.invoke(app, ["session", "show", str(sid), "--no-figure", "--db", url])
    assert out.exit_code == 0, out.output
    text = " ".join(out.output.split())
    assert f"best so far: {name} (action {rec}:" in text
    assert f"the highest posterior mean, {unmade} (action {top}), is a point whose gait" in text
    assert NOT_MADE not in text
    out = runner.invoke(app, ["session", "show", str(sid), "--no-figure", "--json", "--db", url])
    assert out.exit_code == 0, out.output
    shown = json.loads(out.output)["posterior"]
    assert shown["recommended"] == rec and shown["recommended_made"] is True
    assert shown["argmax"] == top and shown["argmax_made"] is False
    from fastapi.testclient import TestClient

    from gaitpref.console.app import create_app

    with TestClient(create_app(url)) as client:
        page = " ".join(client.get(f"/sessions/{sid}").text.split())
    assert "among the gaits made so far that may be proposed" in page
    assert "best-not-made" not in page
