"""A new session refuses operator labels holding control, format or line-break characters.

A feature's ``unit`` and ``words`` and the ``[feedback.rating]`` labels are shown to the
operator with each trial (the terminal loop, the console) and written to exports.
``unit = "m\\u001b[2J"`` (ESC: clears the operator's terminal), a newline in a word or a
right-to-left override in a label were taken as they were.  Now a new session (and
``simulate``) refuses them as it refuses such a config name, with a ConfigError naming the
table and key; a session stored with one reopens and replays as it was.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref import ConfigError, Session
from gaitpref.cli import app
from gaitpref.config import check_labels, load_config, parse_config
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive

RATING = '[feedback.rating]\nlabels = ["bad", "okay", "good"]\n\n[cospar]'


def _text(old: str, new: str) -> str:
    text = load_config(CONFIG).text
    assert text.count(old) == 1
    return text.replace(old, new)


BAD = [
    ('unit = "m"', 'unit = "m\\u001b[2J"', "space.step_length", "unit", "U+001B"),
    ('unit = "m"', 'unit = "m\\u0000"', "space.step_length", "unit", "U+0000"),
    (
        'words = ["longer", "shorter"]',
        'words = ["longer\\nS99", "shorter"]',
        "space.step_length",
        "words",
        "U+000A",
    ),
    (
        'words = ["longer", "shorter"]',
        'words = ["longer", "\\u202eshorter"]',
        "space.step_length",
        "words",
        "U+202E RIGHT-TO-LEFT OVERRIDE",
    ),
    (
        "[cospar]",
        '[feedback.rating]\nlabels = ["bad", "ok\\tay", "good"]\n\n[cospar]',
        "feedback.rating",
        "labels",
        "U+0009",
    ),
]


@pytest.mark.parametrize(("old", "new", "table", "key", "first"), BAD)
def test_a_new_session_refuses_hidden_characters_in_labels(
    tmp_path: Path, old: str, new: str, table: str, key: str, first: str
) -> None:
    text = _text(old, new)
    parse_config(text)  # parsing still takes it (stored sessions)
    path = tmp_path / "hidden.toml"
    path.write_text(text, encoding="utf-8")
    db = MemoryStorage()
    for config in (path, parse_config(text)):
        with pytest.raises(ConfigError, match=rf"^\[{table}\]\.{key}: must not hold") as err:
            Session.create(db, config, "S01")
        assert (err.value.table, err.value.key) == (table, key)
        assert f"holds {first}" in str(err.value)
    assert Session.list_sessions(db) == []


def test_printable_labels_are_taken() -> None:
    text = _text('unit = "m"', 'unit = "m/s²"').replace("[cospar]", RATING)
    text = text.replace('words = ["longer", "shorter"]', 'words = ["plus long", "plus court"]')
    config = parse_config(text)
    check_labels(config)
    with Session.create(MemoryStorage(), config, "S01") as s:
        assert s.config.space.features[0].unit == "m/s²"


def test_a_session_stored_with_such_a_label_replays(
    tmp_path: Path, drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gaitpref.config.new

    url = f"sqlite:///{tmp_path / 'old.db'}"
    text = _text('unit = "m"', 'unit = "m\\u001b[2J"')
    with monkeypatch.context() as m:  # as earlier releases took it
        m.setattr(gaitpref.config.new, "check_labels", lambda config: None)
        s = Session.create(url, parse_config(text), "S01", seed=4)
    drive(s, 3)
    mean = s.posterior().mean.copy()
    s.close()
    with Session.open(url, s.id) as again:
        assert again.config.space.features[0].unit == "m\x1b[2J"
        assert (again.posterior().mean == mean).all() and len(again.trials()) == 3
        drive(again, 1)


def test_session_new_and_simulate_refuse_it(tmp_path: Path) -> None:
    path = tmp_path / "hidden.toml"
    path.write_text(_text('unit = "m"', 'unit = "m\\u001b[2J"'), "utf-8")
    db = tmp_path / "lab.db"
    for args in (
        ["session", "new", "--config", str(path), "--subject", "S01", "--db", str(db)],
        ["simulate", str(path), "--objective", "random-gp", "--trials", "1"],
    ):
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 2, result.output
        assert "[space.step_length].unit: must not hold" in " ".join(result.output.split())
        assert "\x1b" not in result.output
    assert not db.exists()


def test_a_new_session_refuses_a_feature_name_longer_than_a_unit() -> None:
    # a 100,000-character feature name was taken (a unit or a word holds at most 200), and every
    # error about the feature echoed it whole in its table's name
    long = "s" * 201
    config = parse_config(
        _text("[space.step_length]", f"[space.{long}]").replace(
            "step_length = 0.03", f"{long} = 0.03"
        )
    )
    with pytest.raises(ConfigError, match=r"^\[space\]: the feature name 'sss") as e:
        check_labels(config)
    assert (e.value.table, e.value.key) == ("space", None)
    assert "201 characters; at most 200" in str(e.value) and long not in str(e.value)
    with pytest.raises(ConfigError, match="feature name"):
        Session.create(MemoryStorage(), config, "S01")
    check_labels(
        parse_config(
            _text("[space.step_length]", f"[space.{long[:200]}]").replace(
                "step_length = 0.03", f"{long[:200]} = 0.03"
            )
        )
    )


@pytest.mark.parametrize("words", ['["more", "more"]', '["Longer", "longer "]'])
def test_a_new_session_refuses_two_words_that_are_the_same(words: str) -> None:
    # the operator was offered "1 more, 2 slightly more, 3 slightly more, 4 more" (labels must
    # differ; words were not checked)
    config = parse_config(_text('words = ["longer", "shorter"]', f"words = {words}"))
    with pytest.raises(
        ConfigError, match=r"^\[space.step_length\].words: must be two different"
    ) as e:
        check_labels(config)
    assert (e.value.table, e.value.key) == ("space.step_length", "words")
    with pytest.raises(ConfigError, match="two different words"):
        Session.create(MemoryStorage(), config, "S01")


@pytest.mark.parametrize(
    ("old", "new", "table", "key", "why"),
    [
        (
            'words = ["longer", "shorter"]',
            'words = ["  ", "shorter"]',
            "space.step_length",
            "words",
            "blank",
        ),
        (
            "[cospar]",
            '[feedback.rating]\nlabels = ["bad", " ", "good"]\n\n[cospar]',
            "feedback.rating",
            "labels",
            "blank",
        ),
        (
            "[cospar]",
            '[feedback.rating]\nlabels = ["bad", "okay", "Bad "]\n\n[cospar]',
            "feedback.rating",
            "labels",
            "must differ",
        ),
    ],
)
def test_a_new_session_refuses_blank_or_alike_words_and_labels(
    old: str, new: str, table: str, key: str, why: str
) -> None:
    config = parse_config(_text(old, new))  # a stored config still parses
    with pytest.raises(ConfigError, match=why) as e:
        check_labels(config)
    assert (e.value.table, e.value.key) == (table, key)
    check_labels(parse_config(_text("[cospar]", RATING)))
