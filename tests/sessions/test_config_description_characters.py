"""A new session refuses a config description holding terminal controls or bidi overrides.

The description is printed by ``gaitpref configs`` and kept in the config text that sessions,
the console and exports carry.  ``description = "x\\u001b[2J"`` (ESC: clears the operator's
terminal), NUL, a lone carriage return (overwrites the line shown) or a right-to-left override
were taken as they were.  Now a new session (and ``simulate``, which checks a config as a new
session does) refuses control characters other than newline and tab, surrogates, line
and paragraph separators and the bidirectional formatting characters with a ConfigError naming
``description``.  Newlines and tabs pass (a description may run over lines), and so do other
format characters (a zero width non-joiner, which Persian text needs).  A session stored with
such a description by an earlier release reopens and replays as it was.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref import ConfigError, Session
from gaitpref.cli import app
from gaitpref.config import check_description, load_config, parse_config
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive

HIDDEN = [
    ("lab\u001b[2J", "U+001B"),  # ESC: clears a terminal
    ("lab\u0000", "U+0000"),  # NUL
    ("lab\rforged", "U+000D"),  # a lone CR: the rest overwrites the line shown
    ("lab\u0007", "U+0007"),  # BEL
    ("lab\u007f", "U+007F"),  # DEL
    ("lab\u009b2J", "U+009B"),  # CSI (a C1 control)
    ("lab\u202egnp.exe", "U+202E RIGHT-TO-LEFT OVERRIDE"),
    ("lab\u2066x\u2069", "U+2066 LEFT-TO-RIGHT ISOLATE"),
    ("lab\u200fx", "U+200F RIGHT-TO-LEFT MARK"),
    ("lab\u2028x", "U+2028 LINE SEPARATOR"),
]


def _text(description: str) -> str:
    text = load_config(CONFIG).text
    old = [line for line in text.splitlines() if line.startswith("description = ")]
    assert len(old) == 1
    return text.replace(old[0], f"description = {json.dumps(description)}")


@pytest.mark.parametrize(("description", "first"), HIDDEN)
def test_a_new_session_refuses_control_and_bidi_characters_in_the_description(
    tmp_path: Path, description: str, first: str
) -> None:
    text = _text(description)
    assert parse_config(text).description == description  # parsing takes it (stored sessions)
    path = tmp_path / "hidden.toml"
    path.write_text(text, encoding="utf-8")
    db = MemoryStorage()
    for config in (path, parse_config(text)):
        with pytest.raises(ConfigError, match=r"^description: must not hold control") as err:
            Session.create(db, config, "S01")
        assert err.value.key == "description"
        assert f"the first {first} at character 4" in str(err.value)
        assert description not in str(err.value)  # shown escaped, never raw
    assert Session.list_sessions(db) == []


@pytest.mark.parametrize(
    "description",
    [
        "line one\nline two\n\tindented",
        "exo 1d (café, ☃) – 步长",
        "می\u200cخواهم",  # a zero width non-joiner: Persian spelling needs it
        "",
    ],
)
def test_newlines_tabs_and_printable_text_are_taken(description: str) -> None:
    config = parse_config(_text(description))
    check_description(config)
    with Session.create(MemoryStorage(), config, "S01") as s:
        assert s.config.description == description


def test_a_session_stored_with_a_control_character_in_its_description_replays(
    tmp_path: Path, drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gaitpref.config.new

    url = f"sqlite:///{tmp_path / 'old.db'}"
    description = "lab\u001b[2J\u202e"
    with monkeypatch.context() as m:  # as earlier releases took it
        m.setattr(gaitpref.config.new, "check_description", lambda config: None)
        s = Session.create(url, parse_config(_text(description)), "S01", seed=4)
    drive(s, 3)
    mean = s.posterior().mean.copy()
    s.close()
    with Session.open(url, s.id) as again:
        assert again.config.description == description
        assert (again.posterior().mean == mean).all() and len(again.trials()) == 3
        drive(again, 1)


@pytest.mark.parametrize(
    "command",
    [
        ["session", "new", "--subject", "S01"],
        ["simulate", "--objective", "hartmann6", "--trials", "1"],
    ],
)
def test_the_cli_refuses_it_by_name(tmp_path: Path, command: list[str]) -> None:
    path = tmp_path / "hidden.toml"
    path.write_text(_text("lab\u001b[2J"), "utf-8")
    db = tmp_path / "lab.db"
    if command[0] == "session":
        args = [*command, "--config", str(path), "--db", str(db)]
    else:
        args = [command[0], str(path), *command[1:]]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "description: must not hold control" in result.output
    assert "\u001b" not in result.output
    assert not db.exists()
