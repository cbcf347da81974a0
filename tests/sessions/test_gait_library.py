"""Sessions over a config that names a gait library: gait ids shown, library checked on replay."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from gaitpref import GaitLibrary, ReplayError, Session, load_config
from gaitpref.config import parse_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.sessions.export import export_session, import_session

CONFIG = """
[gaits]
library = "lib/gaits.json"

[model]
lengthscale = { step_length = 0.03 }
signal_variance = 0.005
jitter = 1e-7
noise = 0.02

[cospar]
n = 1
buffer = 1
seed = 4
"""


@pytest.fixture
def study(tmp_path: Path, library: GaitLibrary) -> Path:
    folder = tmp_path / "study"
    (folder / "lib").mkdir(parents=True)
    library.save(folder / "lib" / "gaits.json")
    (folder / "study.toml").write_text(CONFIG)
    return folder / "study.toml"


def _drive(s: Session, n: int) -> None:
    subject = SimulatedSubject(s.config.space, bump_utility(s.config.space), seed=0)
    for _ in range(n):
        q = s.next_query()
        s.answer(q.id, *subject.respond(q))


def test_gait_ids_and_replay_from_another_folder(
    study: Path, library: GaitLibrary, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, study, "S01")
    _drive(s, 5)
    q = s.next_query()
    assert s.gait_id(q.actions[0]) == library.gait_id(q.actions[0])
    assert s.describe(q.actions[0]).endswith(f"[gait {library.gait_id(q.actions[0])}]")
    trials = [e.payload for e in s.events() if e.kind == "trial_executed"]
    assert all(t["gait_id"] == library.gait_id(t["action"]) for t in trials)
    monkeypatch.chdir(tmp_path)  # the relative library path is not taken from here
    again = Session.open(url, s.id)
    np.testing.assert_array_equal(again.posterior().mean, s.posterior().mean)
    assert again.next_query() == q


def test_a_changed_or_missing_library_stops_replay(
    study: Path, library: GaitLibrary, tmp_path: Path
) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, load_config(study), "S01")  # a loaded config works too
    _drive(s, 3)
    export_session(s, tmp_path / "export", "csv")
    lib = study.parent / "lib" / "gaits.json"
    lib.write_text(lib.read_text() + "\n\n")  # another file, same gaits
    with pytest.raises(ReplayError, match="not the one the session was run with"):
        Session.open(url, s.id)
    shutil.rmtree(study.parent / "lib")
    with pytest.raises(ReplayError, match="needs its gait library"):
        Session.open(url, s.id)
    # the export carries a copy: importing it works without the original
    imported = import_session(f"sqlite:///{tmp_path / 'other.db'}", tmp_path / "export")
    assert (tmp_path / "export" / "lib" / "gaits.json").is_file()
    np.testing.assert_array_equal(imported.posterior().mean, s.posterior().mean)
    assert imported.gait_ids == [library.gait_id(a) for a in range(len(library))]
    imported.close()


SPACE = """
[space.step_length]
{grid}
[model]
lengthscale = 0.03
signal_variance = 0.005
noise = 0.02
"""


def test_a_library_given_for_another_grid_is_refused(library: GaitLibrary) -> None:
    """A library of 0.10..0.16 m given to a config of 0.30 and 0.50 m named its actions with
    the library's first two ids (L0.100, L0.120): the operator would walk other gaits."""
    other = parse_config(SPACE.format(grid="values = [0.30, 0.50]"))
    with pytest.raises(ValueError, match=r"grid \(step_length 0.1..0.16 \(4 values\)\) is not"):
        Session.create("sqlite://", other, "S01", library=library)
    same = parse_config(SPACE.format(grid="min = 0.10\nmax = 0.16\nnum = 4"))
    s = Session.create("sqlite://", same, "S01", library=library)
    assert s.gait_ids == [library.gait_id(a) for a in range(4)]
