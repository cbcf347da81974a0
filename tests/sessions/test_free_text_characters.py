"""A new note, unsafe reason or exclusion detail holding a character a terminal acts on (ESC, a
carriage return, NUL, a bidirectional override, ...) is refused naming the field; newlines and
tabs pass.  They were logged as typed and reached ``session show``, the terminal and exports.
Events stored with one by an earlier release replay (the check is on new text only)."""

from __future__ import annotations

import pytest

import gaitpref.sessions.session as session_module
from gaitpref import Session
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive

BAD = ["clear\x1b[2J", "a\rb", "nul\x00", "rtl\u202eevil", "line\u2028sep", "c1\x85"]


def _answered(drive: Drive) -> Session:
    s = Session.create(MemoryStorage(), CONFIG, "S01", seed=3)
    drive(s, 2)
    return s


@pytest.mark.parametrize("text", BAD)
def test_new_free_text_is_refused_naming_the_field(drive: Drive, text: str) -> None:
    s = _answered(drive)
    before = len(s.events())
    with pytest.raises(ValueError, match=r"the note holds U\+"):
        s.note(text)
    with pytest.raises(ValueError, match=r"the unsafe flag's reason holds U\+"):
        s.flag_unsafe(1, text)
    with pytest.raises(ValueError, match=r"the exclusion's detail holds U\+.*nothing was written"):
        s.exclude(1, "device_fault", text)
    assert len(s.events()) == before and s.unsafe_flags() == {}


def test_newlines_tabs_and_joiners_pass(drive: Drive) -> None:
    s = _answered(drive)
    s.note("line one\nline two\tand a tab; \u0645\u06cc\u200c\u062e\u0648\u0627\u0647\u0645")
    s.flag_unsafe(1, "knee\ngave way")
    s.exclude(2, "device_fault", "strap\tslipped")
    assert s.notes()[-1][1].startswith("line one\n")


def test_events_stored_with_such_text_replay(drive: Drive, monkeypatch: pytest.MonkeyPatch) -> None:
    db = MemoryStorage()
    s = Session.create(db, CONFIG, "S01", seed=3)
    drive(s, 2)
    with monkeypatch.context() as m:  # as an earlier release wrote them
        m.setattr(session_module, "check_printable", lambda text, what: text)
        s.note(BAD[0])
        s.flag_unsafe(1, BAD[1])
        s.exclude(2, "device_fault", BAD[2])
    again = Session.open(db, s.id)
    assert again.notes()[-1][1] == BAD[0] and again.unsafe_flags()[1][1] == BAD[1]
