"""A config naming its gait library outside its own folder: ``library = "../libs/x.json"``, an
absolute path, or a path through a symbolic link.  ``session new`` refused the first and the last
("cannot tell which folder the config's gait library path ... is relative to; load the config
from its file", for a config loaded from its file): the folder was guessed back from the
library's resolved path, which ``..`` and links do not allow."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref import GaitLibrary, Session, load_config
from gaitpref.cli import app
from gaitpref.sessions.demo import SimulatedSubject, bump_utility

CONFIG = """
[gaits]
library = "{library}"

[model]
lengthscale = {{ step_length = 0.03 }}
signal_variance = 0.005
jitter = 1e-7
noise = 0.02

[cospar]
n = 1
buffer = 1
seed = 4
"""


@pytest.fixture(scope="module")
def library() -> GaitLibrary:
    from gaitpref.gaits.build import build_library

    return build_library([0.10, 0.12, 0.14, 0.16], speed=0.2, n_jobs=1)


def lab(root: Path, library: GaitLibrary, named: str | None = None) -> Path:
    """``root/configs/c.toml`` naming ``root/libs/x.json`` by ``named`` (default ``../libs/x.json``;
    ``{abs}`` stands for the library's absolute path); returns the config's path."""
    (root / "configs").mkdir(parents=True)
    (root / "libs").mkdir()
    library.save(root / "libs" / "x.json")
    given = (named or "../libs/x.json").replace("{abs}", str(root / "libs" / "x.json"))
    (root / "configs" / "c.toml").write_text(CONFIG.format(library=given))
    return root / "configs" / "c.toml"


def drive(s: Session, n: int) -> None:
    subject = SimulatedSubject(s.config.space, bump_utility(s.config.space), seed=0)
    for _ in range(n):
        q = s.next_query()
        s.answer(q.id, *subject.respond(q))


def test_a_library_up_a_folder_starts_and_replays(
    tmp_path: Path, library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    config = lab(tmp_path / "study", library)
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, config, "S01")
    assert s.record.meta["config_dir"] == str((tmp_path / "study" / "configs").resolve())
    assert s.record.meta["library_path"] == str((tmp_path / "study" / "libs" / "x.json").resolve())
    assert s.gait_ids == [library.gait_id(a) for a in range(len(library))]
    drive(s, 4)
    monkeypatch.chdir(tmp_path)  # replay takes the path from the config's folder, not from here
    again = Session.open(url, s.id)
    np.testing.assert_array_equal(again.posterior().mean, s.posterior().mean)
    assert again.next_query() == s.next_query()
    # a loaded config works too
    assert Session.create(url, load_config(config), "S02").gait_ids == s.gait_ids


def test_session_new_with_a_library_up_a_folder(
    tmp_path: Path, library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    lab(tmp_path, library)
    monkeypatch.chdir(tmp_path)
    db = str(tmp_path / "lab.db")
    result = CliRunner().invoke(
        app, ["session", "new", "--config", "configs/c.toml", "--subject", "S01", "--db", db]
    )
    assert result.exit_code == 0, result.output
    assert "session 1" in result.output
    assert Session.open(db, 1).gait_ids == [library.gait_id(a) for a in range(len(library))]


@pytest.mark.skipif(not hasattr(os, "symlink"), reason="no symbolic links")
def test_a_library_reached_through_a_link(tmp_path: Path, library: GaitLibrary) -> None:
    config = lab(tmp_path, library, "lib/x.json")
    (config.parent / "lib").mkdir()
    (config.parent / "lib" / "x.json").symlink_to(tmp_path / "libs" / "x.json")
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, config, "S01")
    drive(s, 2)
    assert Session.open(url, s.id).gait_ids == s.gait_ids


def test_an_absolute_library_path(tmp_path: Path, library: GaitLibrary) -> None:
    config = lab(tmp_path, library, "{abs}")
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, config, "S01")
    drive(s, 2)
    assert Session.open(url, s.id).gait_ids == s.gait_ids
