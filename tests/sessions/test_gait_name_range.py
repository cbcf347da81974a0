"""A session names only its own gaits: ``gait_name(-1)`` was ``"G-1"`` (and, with a library,
``gait_id(-1)`` the library's last gait); an action past the space was ``G<action>`` too.  On the
line path an index past the point table was said to be "off the grid", which it has none of."""

from __future__ import annotations

from pathlib import Path

import pytest

from gaitpref import GaitLibrary, Session
from gaitpref.config import parse_config
from tests.sessions.test_gait_library import CONFIG as LIBRARY_CONFIG

MODEL = "[model]\nlengthscale = 0.2\nsignal_variance = 0.005\nnoise = 0.02\n"
GRID = "[space.x]\nmin = 0.0\nmax = 1.0\nnum = 5\n" + MODEL
LINE = (
    "[space.x]\nmin = 0.0\nmax = 1.0\n[space.y]\nmin = 0.0\nmax = 1.0\n"
    '[cospar]\nsubspace = "line"\n'
)


def _session(tmp_path: Path, text: str) -> Session:
    return Session.create(f"sqlite:///{tmp_path / 'lab.db'}", parse_config(text), subject="S01")


@pytest.mark.parametrize("action", [-1, 5, 2**70])
def test_an_action_off_the_grid_has_no_name(tmp_path: Path, action: int) -> None:
    s = _session(tmp_path, GRID)
    assert [s.gait_name(a) for a in range(5)] == ["G0", "G1", "G2", "G3", "G4"]
    with pytest.raises(IndexError, match=rf"^action index {action} is off the grid \(0\.\.4\)$"):
        s.gait_name(action)
    with pytest.raises(IndexError, match="off the grid"):
        s.gait_id(action)


@pytest.mark.parametrize("action", [True, 1.0, "1"])
def test_an_action_that_is_not_an_integer_has_no_name(tmp_path: Path, action: object) -> None:
    s = _session(tmp_path, GRID)
    with pytest.raises(TypeError, match="action index must be an integer"):
        s.gait_name(action)  # type: ignore[arg-type]


def test_a_library_session_does_not_wrap_a_negative_action_to_its_last_gait(
    tmp_path: Path, library: GaitLibrary
) -> None:
    folder = tmp_path / "study"
    (folder / "lib").mkdir(parents=True)
    library.save(folder / "lib" / "gaits.json")
    (folder / "study.toml").write_text(LIBRARY_CONFIG)
    s = Session.create(f"sqlite:///{tmp_path / 'lab.db'}", folder / "study.toml", "S01")
    last = len(library) - 1
    assert s.gait_name(last) == library.gait_id(last)
    with pytest.raises(IndexError, match=rf"action index -1 is off the grid \(0\.\.{last}\)"):
        s.gait_id(-1)
    with pytest.raises(IndexError, match="off the grid"):
        s.gait_name(-1)


def test_the_line_path_names_its_point_table_not_a_grid(tmp_path: Path) -> None:
    s = _session(tmp_path, LINE + MODEL)
    with pytest.raises(IndexError, match=r"^action index 0 is not in the point table \(it has "):
        s.gait_name(0)  # no query yet: no points
    for _ in range(2):
        q = s.next_query()
        s.answer(q.id, [(q.actions[0], q.buffer[0], "first")] if q.buffer else [])
    assert s.gait_name(0) == "G0"
    for action in (-1, 10**6):
        with pytest.raises(IndexError) as info:
            s.gait_name(action)
        text = str(info.value)
        assert text.startswith(f"action index {action} is not in the point table (points 0..")
        assert text.endswith(" so far)") and "grid" not in text
