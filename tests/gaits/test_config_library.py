"""An experiment config that names a gait library takes its space from the library's axes."""

from __future__ import annotations

from pathlib import Path

import pytest

from gaitpref import ConfigError, GaitLibrary, load_config
from gaitpref.config import check_ignored

CONFIG = """
[gaits]
library = "lib.json"

[model]
lengthscale = { step_length = 0.03, step_duration = 0.08 }
signal_variance = 0.005
jitter = 1e-7
noise = 0.02

[cospar]
n = 1
buffer = 1
"""


def test_config_space_and_gait_ids_come_from_the_library(
    duration_library: GaitLibrary, tmp_path: Path
) -> None:
    duration_library.save(tmp_path / "lib.json")
    (tmp_path / "study.toml").write_text(CONFIG)
    cfg = load_config(tmp_path / "study.toml")
    assert cfg.space.shape == duration_library.shape == (3, 2)
    assert cfg.space.names == ("step_length", "step_duration")
    assert cfg.library_path == str((tmp_path / "lib.json").resolve())
    assert cfg.library_sha256 is not None and len(cfg.library_sha256) == 64
    loop = cfg.make_loop(seed=0)
    query = loop.ask()
    a = query.actions[0]
    assert cfg.gait_id(a) == duration_library.gait_id(a)
    assert duration_library.parameters(a) == pytest.approx(cfg.space.values_of(a))


def test_config_library_errors(tmp_path: Path) -> None:
    (tmp_path / "study.toml").write_text(CONFIG)
    with pytest.raises(ConfigError, match=r"\[gaits\].library: .*no such gait library file"):
        load_config(tmp_path / "study.toml")
    both = CONFIG + "\n[space.x]\nvalues = [0.0, 1.0]\n"
    (tmp_path / "both.toml").write_text(both)
    with pytest.raises(ConfigError, match=r"either \[space\] or \[gaits\].library"):
        load_config(tmp_path / "both.toml")
    (tmp_path / "typo.toml").write_text(CONFIG.replace("library =", "libary ="))
    with pytest.raises(ConfigError, match=r"\[gaits\]: unknown key 'libary'"):
        load_config(tmp_path / "typo.toml")


def test_safety_start_names_a_library_gait_by_its_id(
    duration_library: GaitLibrary, tmp_path: Path
) -> None:
    duration_library.save(tmp_path / "lib.json")
    gait = duration_library.gait_id(4)
    text = f"""
[gaits]
library = "lib.json"
[model]
lengthscale = {{ step_length = 0.03, step_duration = 0.08 }}
signal_variance = 0.005
jitter = 1e-7
noise = 0.02
[safety]
start = ["{gait}"]
"""
    (tmp_path / "study.toml").write_text(text)
    cfg = load_config(tmp_path / "study.toml")
    assert cfg.safety.start == (4,) and cfg.make_loop(seed=0).ask().actions == (4,)
    (tmp_path / "bad.toml").write_text(text.replace(gait, "L9.999-T9.999"))
    with pytest.raises(ConfigError, match=r"\[safety\].start: gait 1 .*no gait with id"):
        load_config(tmp_path / "bad.toml")


def test_a_library_config_on_the_line_path_is_refused_by_name(
    duration_library: GaitLibrary, tmp_path: Path
) -> None:
    # the docs say a library cannot be named for a line-path config: it parsed, `simulate` ran
    # it on lines and `session new` refused it with a ValueError naming no key
    duration_library.save(tmp_path / "lib.json")
    (tmp_path / "line.toml").write_text(CONFIG + "subspace = 'line'\n")
    with pytest.raises(ConfigError, match=r"\[cospar\].subspace: runs on the line path, but") as e:
        load_config(tmp_path / "line.toml")
    assert (e.value.table, e.value.key) == ("cospar", "subspace")
    (tmp_path / "grid.toml").write_text(CONFIG + "subspace = 'grid'\n")
    assert load_config(tmp_path / "grid.toml").subspace == "grid"


def test_a_line_key_in_a_library_config_is_refused_by_name(
    duration_library: GaitLibrary, tmp_path: Path
) -> None:
    # a library config runs on its grid: line_count was taken and did nothing
    duration_library.save(tmp_path / "lib.json")
    (tmp_path / "c.toml").write_text(CONFIG + "line_count = 8\n")
    config = load_config(tmp_path / "c.toml")
    assert config.subspace == "grid"
    with pytest.raises(ConfigError, match=r"\[cospar\].line_count: is a setting of the line") as e:
        check_ignored(config)
    assert (e.value.table, e.value.key) == ("cospar", "line_count")
    (tmp_path / "c.toml").write_text(CONFIG)
    check_ignored(load_config(tmp_path / "c.toml"))
