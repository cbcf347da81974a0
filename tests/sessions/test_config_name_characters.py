"""A new session refuses a config name holding control or format characters.

A name is printed by ``gaitpref session list`` and the terminal, put in the console's pages and
written to exports.  ``name = "lab\\u001b[2J"`` (ESC: an escape sequence that clears the
operator's terminal), a newline (a forged second line in a listing), NUL or a right-to-left
override were taken as they were.  Now a new session refuses control (``Cc``), format (``Cf``),
surrogate (``Cs``) and line or paragraph separator (``Zl``, ``Zp``) characters with a
ConfigError naming ``name``; private-use and unassigned code points pass (whether a code point
is assigned depends on the Python version); a session stored with one by an earlier release
reopens and replays as it was.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref import ConfigError, Session
from gaitpref.cli import app
from gaitpref.config import check_name, load_config, parse_config
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive

#: Control (Cc) and format (Cf) characters a TOML basic string can hold through its escapes
HIDDEN = [
    ("lab\u001b[2J", "U+001B"),  # ESC: clears a terminal
    ("lab\nS99 forged", "U+000A"),  # a newline: a second line in a listing
    ("lab\u0000", "U+0000"),  # NUL
    ("lab\u007f", "U+007F"),  # DEL
    ("lab\u0085x", "U+0085"),  # NEL (C1 control)
    ("lab\u202egnp.exe", "U+202E RIGHT-TO-LEFT OVERRIDE"),  # Cf: reorders the text shown
    ("lab\u200bx", "U+200B ZERO WIDTH SPACE"),  # Cf: invisible
    ("lab\tx", "U+0009"),  # a tab inside a name that is not blank
    ("lab\u2028x", "U+2028 LINE SEPARATOR"),  # Zl: a line break in many renderers
]


def _text(name: str) -> str:
    named = f"name = {json.dumps(name)}"  # a TOML basic string: escapes as JSON's
    text = load_config(CONFIG).text
    assert 'name = "exo-1d-step-length"' in text
    return text.replace('name = "exo-1d-step-length"', named)


@pytest.mark.parametrize(("name", "first"), HIDDEN)
def test_a_new_session_refuses_control_and_format_characters_in_the_name(
    tmp_path: Path, name: str, first: str
) -> None:
    text = _text(name)
    assert parse_config(text).name == name  # parsing still takes it (stored sessions)
    path = tmp_path / "hidden.toml"
    path.write_text(text, encoding="utf-8")
    db = MemoryStorage()
    for config in (path, parse_config(text)):
        with pytest.raises(
            ConfigError, match=r"^name: must not hold control, format or line-break"
        ) as err:
            Session.create(db, config, "S01")
        assert err.value.key == "name"
        assert f"the first {first} at character 4" in str(err.value)
        assert name not in str(err.value)  # the message shows it escaped, never raw
    assert Session.list_sessions(db) == []


@pytest.mark.parametrize(
    "name", ["exo 1d (café, ☃)", "Übung-2 – 步长", "a b", "lab \ue000 private", "lab \u0378"]
)
def test_printable_names_are_taken(name: str) -> None:
    config = parse_config(_text(name))
    check_name(config)
    with Session.create(MemoryStorage(), config, "S01") as s:
        assert s.config.name == name


def test_a_file_name_with_a_newline_is_refused_as_the_default_name(tmp_path: Path) -> None:
    """Without a ``name`` key the config takes the file's name, which may hold a newline."""
    text = load_config(CONFIG).text.replace('name = "exo-1d-step-length"\n', "")
    path = tmp_path / "two\nlines.toml"
    path.write_text(text, encoding="utf-8")
    assert load_config(path).name == "two\nlines"
    with pytest.raises(ConfigError, match=r"^name: must not hold") as err:
        Session.create(MemoryStorage(), path, "S01")
    assert err.value.key == "name"


def test_a_session_stored_with_a_control_character_in_its_name_reopens_and_replays(
    tmp_path: Path, drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gaitpref.config.new

    url = f"sqlite:///{tmp_path / 'old.db'}"
    name = "lab\u001b[2J\n"
    with monkeypatch.context() as m:  # as earlier releases took it
        m.setattr(gaitpref.config.new, "check_name", lambda config: None)
        s = Session.create(url, parse_config(_text(name)), "S01", seed=4)
    drive(s, 3)
    mean = s.posterior().mean.copy()
    s.close()
    with Session.open(url, s.id) as again:
        assert again.config.name == name and again.record.config_name == name
        assert (again.posterior().mean == mean).all() and len(again.trials()) == 3
        drive(again, 1)  # and it goes on


def test_session_new_refuses_it_by_name(tmp_path: Path) -> None:
    path = tmp_path / "hidden.toml"
    path.write_text(_text("lab\u001b[2J"), "utf-8")
    db = str(tmp_path / "lab.db")
    args = ["session", "new", "--config", str(path), "--subject", "S01", "--db", db]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "name: must not hold control" in result.output
    assert "\u001b" not in result.output  # the terminal never gets the escape itself


def test_the_console_refuses_it_naming_the_config() -> None:
    """The console creates sessions through Session.create: a 422 at ``config`` whose message
    names ``name`` (and shows the character escaped); nothing is written."""
    pytest.importorskip("fastapi")
    from fastapi.testclient import TestClient

    from gaitpref.console import create_app

    with TestClient(create_app("sqlite:///:memory:")) as client:
        body = {"config": _text("lab\u001b[2J"), "subject": "S01"}
        r = client.post("/api/sessions", json=body)
        assert r.status_code == 422, r.text
        detail = r.json()["detail"][0]
        assert detail["loc"] == ["body", "config"]
        assert detail["msg"].startswith("name: must not hold control") and "\u001b" not in r.text
        assert client.get("/api/sessions").json() == []
