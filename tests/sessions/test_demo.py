"""The scripted session of ``make demo``: a simulated subject through the Session API."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitpref import Session
from gaitpref.sessions.demo import demo_session


def test_scripted_session_is_a_real_finished_session(tmp_path: Path) -> None:
    done = demo_session(tmp_path, "exo-1d-step-length", trials=12, seed=3)
    assert done.database == (tmp_path / "sessions.db").resolve()
    assert done.figure is not None and done.figure.read_bytes()[:4] == b"\x89PNG"
    s = Session.open(f"sqlite:///{done.database}", done.session_id)
    assert s.status == "finished" and len(s.trials()) == 12
    assert s.validations() == [done.validation]
    assert done.validation.agrees  # a noiseless subject after 12 trials
    assert s.recommended() == done.best_action == s.confidence().recommended
    assert np.isfinite(s.posterior().mean).all()
    kinds = [e.kind for e in s.events()]
    assert kinds[0] == "created" and kinds[-1] == "finished" and "note" in kinds
