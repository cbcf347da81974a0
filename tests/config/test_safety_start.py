"""``[safety] start``: gaits the operator declares safe, by feature values, action index or a
library's gait id, checked against the grid with errors naming the key; and ``reach``."""

from __future__ import annotations

import pytest

from gaitpref import ConfigError
from gaitpref.config import parse_config

BASE = """
[space.x]
min = 0.0
max = 1.0
num = 11
[space.y]
values = [0.0, 0.5, 1.0]
[model]
lengthscale = 0.2
signal_variance = 0.01
noise = 0.02
[feedback.rating]
labels = ["very bad", "bad", "okay", "good"]
[safety]
"""


def test_start_names_grid_gaits_in_order() -> None:
    cfg = parse_config(BASE + "start = [{x = 0.3, y = 1.0}, 4, {y = 0.0, x = 1.0}]\n")
    assert cfg.safety.start == (3 * 3 + 2, 4, 10 * 3 + 0)  # C order: x varies slowest
    assert cfg.space.values_of(11) == {"x": pytest.approx(0.3), "y": 1.0}
    assert parse_config(BASE).safety.start == ()  # absent: none, as before the key
    assert parse_config(BASE + "start = []\n").safety.start == ()
    loop = cfg.make_loop(seed=1)
    assert loop.ask().actions == (11,)  # n = 1: trial 1 walks the first start gait
    cautious = parse_config(BASE + 'avoid = ["very bad"]\nstart = [4]\nreach = 1.5\n').safety
    assert (cautious.start, cautious.reach, cautious.cautious) == ((4,), 1.5, 0.6)


@pytest.mark.parametrize(
    ("start", "message"),
    [
        ("{x = 0.33, y = 1.0}", r"gait 1 .*x = 0.33 is not a grid value \(nearest: 0.3, 0.4\)"),
        ("{x = 0.3}", r"gait 1 .*missing feature 'y' \(features: x, y\)"),
        ("{x = 0.3, y = 0.0, z = 1}", r"gait 1 .*unknown feature 'z'"),
        ("2, 33", r"gait 2 \(33\): the grid's actions are 0..32"),
        ("2, {x = 0.0, y = 1.0}", r"gait 2 .* is the same gait as gait 1"),
        ('"L0.130-T0.950"', r"gait 1 .*: a gait id needs a \[gaits\] library"),
        ("-1", r"must be a list of at most 64 gaits.*; gait 1 is -1"),
        ("true", r"gait 1 is True"),
        ("[1]", r"gait 1 is \[1\]"),
        ('{x = "a", y = 0.0}', r"must be a finite number"),
    ],
)
def test_bad_start_gaits_name_the_key_and_the_gait(start: str, message: str) -> None:
    with pytest.raises(ConfigError, match=r"^\[safety\].start: .*" + message):
        parse_config(BASE + f"start = [{start}]\n")


def test_start_and_reach_errors() -> None:
    with pytest.raises(ConfigError, match=r"\[safety\].start: must be a list"):
        parse_config(BASE + "start = 3\n")
    with pytest.raises(ConfigError, match=r"\[safety\].start: names gaits of a grid; the line"):
        parse_config(BASE + "start = [3]\n[cospar]\nsubspace = 'line'\n")
    with pytest.raises(ConfigError, match=r"\[safety\].reach: is a setting of the cautious"):
        parse_config(BASE + "reach = 1.0\n")
    with pytest.raises(ConfigError, match=r"\[safety\].reach: must be a finite number > 0"):
        parse_config(BASE + 'avoid = ["very bad"]\nreach = 0\n')


def test_frontier_is_read_and_checked() -> None:
    safety = parse_config(BASE + 'avoid = ["very bad"]\nstart = [4]\nfrontier = 0.9\n').safety
    assert (safety.frontier, safety.cautious, safety.reach) == (0.9, 0.6, None)
    assert parse_config(BASE + 'avoid = ["very bad"]\n').safety.frontier is None  # absent: off
    with pytest.raises(ConfigError, match=r"\[safety\].frontier: is a setting of the cautious"):
        parse_config(BASE + "frontier = 0.9\n")
    with pytest.raises(ConfigError, match=r"\[safety\].frontier: is a setting of the cautious"):
        parse_config(BASE + 'avoid = ["very bad"]\ncautious = 0\nfrontier = 0.9\n')
    with pytest.raises(ConfigError, match=r"\[safety\].frontier: must exceed cautious \(0.6\)"):
        parse_config(BASE + 'avoid = ["very bad"]\nfrontier = 0.6\n')
    with pytest.raises(ConfigError, match=r"\[safety\].frontier: must exceed cautious \(0.95\)"):
        parse_config(BASE + 'avoid = ["very bad"]\ncautious = 0.95\nfrontier = 0.9\n')
    for bad in ("0", "1.5", "-0.1", '"a"'):
        with pytest.raises(ConfigError, match=r"\[safety\].frontier: must be"):
            parse_config(BASE + f'avoid = ["very bad"]\nfrontier = {bad}\n')
