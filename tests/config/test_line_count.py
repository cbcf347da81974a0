"""``[cospar] line_count``: a star of lines per query on the line path since defaults 0.10, one
line (LineCoSpar's) for sessions recorded before; a grid config does not rely on it."""

from __future__ import annotations

import pytest

from gaitpref import ConfigError
from gaitpref.config import parse_config
from gaitpref.loop import LineSettings
from gaitpref.sessions.stored_config import config_of, library_meta
from tests.config.records import stored_record

LINE = """
[space.step_length]
min = 0.08
max = 0.18
[space.step_duration]
min = 0.8
max = 1.2
[model]
lengthscale = 0.05
signal_variance = 1.0
noise = 0.05
jitter = 1e-6
"""
GRID = LINE.replace("max = 0.18\n", "max = 0.18\nnum = 11\n").replace(
    "max = 1.2\n", "max = 1.2\nnum = 9\n"
)
# every [model] default changed since 0.5, given: only [cospar] line_count is left to change
EXPLICIT = 'share = "average"\nwarm_first = "recommended"\n'


def test_a_line_config_draws_a_star_of_four_lines_and_records_it() -> None:
    cfg = parse_config(LINE + EXPLICIT)
    assert cfg.subspace == "line" and cfg.line.lines == 4
    assert cfg.relies_on_changed_defaults and library_meta(cfg) == {"config_defaults": "0.13"}
    assert config_of(stored_record(LINE + EXPLICIT, library_meta(cfg))).line.lines == 4


def test_sessions_recorded_before_0_10_replay_with_one_line() -> None:
    for version in ("0.1", "0.5", "0.8"):
        assert parse_config(LINE + EXPLICIT, defaults=version).line.lines == 1
    # a 0.8 session that relied on no changed default stored no version: it reads as 0.1's
    assert config_of(stored_record(LINE + EXPLICIT, {})).line.lines == 1
    given = LINE + EXPLICIT + '[cospar]\nbuffer = 1\nline_count = 2\nline_boundary = "fold"\n'
    given += 'line_coactive = "kept"\n'  # no default left that changed since
    assert parse_config(given, defaults="0.8").line.lines == 2  # a value given is kept
    assert not parse_config(given).relies_on_changed_defaults


def test_a_grid_config_does_not_rely_on_the_line_keys() -> None:
    cfg = parse_config(GRID + EXPLICIT + "[cospar]\nbuffer = 1\n")
    assert cfg.subspace == "grid" and not cfg.relies_on_changed_defaults
    # a grid draws no lines: its line keys are read, and no star is built or checked
    wide = parse_config(GRID + "[cospar]\nline_points = 2000\n")
    assert wide.subspace == "grid" and wide.line.points == 2000 and wide.line.lines == 1


def test_0_9_is_not_a_defaults_version() -> None:
    with pytest.raises(ConfigError, match=r"unknown config defaults version '0\.9'"):
        parse_config(LINE, defaults="0.9")


@pytest.mark.parametrize("bad", ["0", "65", "2.5", "true"])
def test_a_bad_line_count_names_the_key(bad: str) -> None:
    with pytest.raises(ConfigError, match=r"cospar.*line_count"):
        parse_config(LINE + f"[cospar]\nline_count = {bad}\n")


def test_a_star_past_the_points_limit_names_the_key_and_what_to_lower() -> None:
    with pytest.raises(ConfigError, match=r"cospar.*line_count.*4 lines of line_points = 2000"):
        parse_config(LINE + "[cospar]\nline_points = 2000\n")  # the default 4 lines
    assert parse_config(LINE + "[cospar]\nline_points = 2000\nline_count = 2\n").line.lines == 2
    with pytest.raises(ValueError, match="8 lines of 1000 points are 8000 points a query"):
        LineSettings(1000, "random", 8)
