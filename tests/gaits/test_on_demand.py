"""Gaits on demand below the sessions: the compass-hzd generator, its content-addressed cache
and the warm start from the nearest gait already made."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import ConfigError
from gaitpref.config import parse_config
from gaitpref.gaits import (
    CachedGait,
    GaitCache,
    GaitCacheWarning,
    GaitGeneratorError,
    GaitRequest,
    OnDemandGaits,
    make_generator,
    optimize_gait,
)


def _same_gait(a: object, b: object) -> bool:
    fields = ("step_length", "step_duration", "cot", "delta_squared", "feasible", "message")
    return all(getattr(a, f) == getattr(b, f) for f in fields) and all(
        np.array_equal(getattr(a, f), getattr(b, f)) for f in ("alpha", "orbit_state")
    )


def test_the_key_is_a_content_address_of_generator_settings_and_parameters() -> None:
    g = make_generator("compass-hzd", ["step_length", "step_width"], {"speed": 0.2})
    key = g.key(np.array([0.12, 0.25]))
    assert len(key) == 64 and key == g.key(np.array([0.12, 0.25]))
    assert g.key(np.array([0.12, 0.30])) == key  # the width is a label: the same gait
    assert g.gait_id(np.array([0.12, 0.30])) == "L0.120-V0.200-W0.300"  # as a library's id
    assert g.key(np.array([0.13, 0.25])) != key
    faster = make_generator("compass-hzd", ["step_length", "step_width"], {"speed": 0.25})
    assert faster.key(np.array([0.12, 0.25])) != key
    timed = make_generator("compass-hzd", ["step_duration", "step_length"])
    assert timed.gait_id(np.array([0.9, 0.12])) == "L0.120-T0.900"  # the library's axis order


@pytest.mark.parametrize(
    ("name", "features", "settings", "problem"),
    [
        ("walker-9000", ["step_length"], {"speed": 0.2}, "no gait generator 'walker-9000'"),
        ("compass-hzd", ["stride"], {"speed": 0.2}, "step_length required"),
        ("compass-hzd", ["step_length"], {}, r"give \[gaits\] speed \(m/s\) or a step_dur"),
        (
            "compass-hzd",
            ["step_length", "step_duration"],
            {"speed": 0.2},
            r"exactly one .*speed = 0.2 has no use: remove \[gaits\] speed",
        ),
        ("compass-hzd", ["step_length"], {"speed": 0.2, "gain": 3}, "max_iterations only"),
    ],
)
def test_generator_errors_name_the_problem(
    name: str, features: list[str], settings: dict[str, float], problem: str
) -> None:
    with pytest.raises(GaitGeneratorError, match=problem):
        make_generator(name, features, settings)


def test_a_gait_made_on_demand_is_warm_started_from_the_nearest_and_cached(
    tmp_path: Path,
) -> None:
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    cache = GaitCache(tmp_path / "gaits")
    gaits = OnDemandGaits(g, cache, [0.1])
    short, new = gaits.get(np.array([0.10]))
    assert new and short.feasible and short.warm_start is None and not short.from_cache
    far, _ = gaits.get(np.array([0.16]))
    near, _ = gaits.get(np.array([0.11]))
    assert near.warm_start == short.key  # 0.10 is nearer than 0.16
    assert _same_gait(near.gait, optimize_gait(GaitRequest(0.11, speed=0.2), warm_start=short.gait))
    assert gaits.get(np.array([0.11])) == (near, False)  # this session has it already
    # a second session finds all three in the folder, as they were made
    files = sorted(p.name for p in (tmp_path / "gaits").glob("*.json"))
    assert files == sorted(f"{m.key}.json" for m in (short, far, near))
    other = OnDemandGaits(g, GaitCache(tmp_path / "gaits"), [0.1])
    found, new = other.get(np.array([0.11]))
    assert new and found.from_cache and found.warm_start == short.key
    assert _same_gait(found.gait, near.gait)


def test_an_unreadable_cache_entry_is_made_again(tmp_path: Path) -> None:
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    made, _ = OnDemandGaits(g, GaitCache(tmp_path), [0.1]).get(np.array([0.12]))
    path = tmp_path / f"{made.key}.json"
    path.write_text(path.read_text()[:100])
    cache = GaitCache(tmp_path)
    assert cache.get(made.key) is None and cache.misses == 1
    again, _ = OnDemandGaits(g, cache, [0.1]).get(np.array([0.12]))
    assert not again.from_cache and _same_gait(again.gait, made.gait)
    assert GaitCache(tmp_path).get(made.key) is not None  # rewritten whole


def _edited(doc: dict[str, Any], how: str) -> str:
    if how == "nested":
        return "[" * 100_000 + "]" * 100_000  # a RecursionError escaped before
    if how == "nan coefficients":
        doc["gait"]["alpha"] = [[None] * 7]  # feasible, and trusted as it was
    elif how == "another step length":
        doc["gait"]["step_length"] = 0.15
    elif how == "another request":
        doc["parameters"] = {"step_length": 0.15}
        doc["gait"]["step_length"] = 0.15
    return json.dumps(doc)


@pytest.mark.parametrize(
    "how", ["nested", "nan coefficients", "another step length", "another request"]
)
def test_a_cache_entry_that_is_not_the_keys_gait_is_made_again(tmp_path: Path, how: str) -> None:
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    made, _ = OnDemandGaits(g, GaitCache(tmp_path), [0.1]).get(np.array([0.12]))
    path = tmp_path / f"{made.key}.json"
    path.write_text(_edited(json.loads(path.read_text()), how))
    cache = GaitCache(tmp_path)
    assert cache.get(made.key) is None and cache.misses == 1
    again, _ = OnDemandGaits(g, cache, [0.1]).get(np.array([0.12]))
    assert not again.from_cache and _same_gait(again.gait, made.gait)
    found = GaitCache(tmp_path).get(made.key)  # rewritten whole
    assert found is not None and _same_gait(found.gait, made.gait)


def test_a_cache_folder_that_cannot_be_written_keeps_its_gaits_in_memory(tmp_path: Path) -> None:
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    blocked = tmp_path / "gaits"
    blocked.write_text("not a folder")  # mkdir fails, as in a read-only folder
    cache = GaitCache(blocked)
    gaits = OnDemandGaits(g, cache, [0.1])
    with pytest.warns(GaitCacheWarning, match=f"gait cache {blocked}: cannot write"):
        made, new = gaits.get(np.array([0.12]))  # an OSError before, the gait lost
    assert new and made.feasible and cache.unwritable is not None
    assert cache.get(made.key) is not None  # in memory
    assert blocked.read_text() == "not a folder"


@pytest.mark.parametrize(
    ("features", "settings", "vector", "why"),
    [
        (["step_length"], {"speed": 0.2}, [2.5], "step_length 2.5 m is not in (0, 2) m"),
        (["step_length"], {"speed": 0.2}, [0.0], "step_length 0 m is not in (0, 2) m"),
        (["step_length", "step_duration"], {}, [0.12, -0.5], "step_duration -0.5 s is not"),
    ],
)
def test_a_point_no_optimisation_can_pose_is_an_infeasible_gait_naming_why(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    features: list[str],
    settings: dict[str, float],
    vector: list[float],
    why: str,
) -> None:
    """A config's [space] may reach such points (step_length min = 0, a typo max = 2.5): the
    session's ask failed with a ValueError or GaitGeneratorError, at that point every time."""

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("optimized a gait that cannot be posed")

    monkeypatch.setattr("gaitpref.gaits.generator.optimize_gait", never)
    g = make_generator("compass-hzd", features, settings)
    made, new = OnDemandGaits(g, GaitCache(tmp_path), [0.1] * len(features)).get(np.array(vector))
    assert new and not made.feasible
    assert made.gait.message.startswith("infeasible: no gait can be posed: " + why)
    cached = GaitCache(tmp_path).get(made.key)  # written and read back (nulls for its numbers)
    assert cached is not None and cached.gait.message == made.gait.message


def test_a_step_too_brief_to_square_is_infeasible_not_an_overflow() -> None:
    gait = optimize_gait(GaitRequest(0.1, step_duration=1e-200), max_iterations=5)
    assert not gait.feasible and gait.message.startswith("infeasible: ")  # an OverflowError


def test_an_infeasible_gait_is_cached_with_its_reason(tmp_path: Path) -> None:
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    made, _ = OnDemandGaits(g, GaitCache(tmp_path), [0.1]).get(np.array([0.02]))
    assert not made.feasible and made.gait.message.startswith("infeasible: ")
    cached = GaitCache(tmp_path).get(made.key)
    assert isinstance(cached, CachedGait) and not cached.gait.feasible
    assert cached.gait.message == made.gait.message


CONFIG = """
[space.step_length]
min = 0.08
max = 0.18
num = 11
[gaits]
generator = "compass-hzd"
speed = 0.2
[model]
lengthscale = 0.03
signal_variance = 1e-4
noise = 0.01
"""


def test_a_config_names_a_generator_with_its_settings() -> None:
    cfg = parse_config(CONFIG)
    assert cfg.generator is not None and cfg.library is None
    settings = {"speed": 0.2, "max_iterations": 60}  # the iteration budget's default
    assert (cfg.generator.name, cfg.generator.settings) == ("compass-hzd", settings)
    assert cfg.generator.avoid_radius == 0.05  # the default
    generator = cfg.generator.make(cfg.space)
    assert generator.gait_id(cfg.space.point(0)) == "L0.080-V0.200"


@pytest.mark.parametrize(
    ("edit", "problem"),
    [
        (("speed = 0.2", 'speed = 0.2\nlibrary = "x.json"'), r"\[gaits\].generator: give either"),
        (('generator = "compass-hzd"', 'generator = "nope"'), r"\[gaits\].generator: no gait gen"),
        (("speed = 0.2", ""), r"\[gaits\].generator: .*fixed speed"),
        (("speed = 0.2", "speed = -1"), r"\[gaits\].speed: must be"),
        (("speed = 0.2", "speed = 0.2\navoid_radius = 2"), r"\[gaits\].avoid_radius: must be"),
        (("speed = 0.2", "speed = 0.2\nmax_iterations = 0"), r"\[gaits\].max_iterations: must"),
        (("num = 11", "num = 400"), r"\[space.step_length\]: values too close"),
        (('generator = "compass-hzd"\nspeed = 0.2', ""), r"\[gaits\]: needs library"),
        (("[space.step_length]", "[space.stride]"), r"step_length required"),
    ],
)
def test_generator_config_errors_name_the_key(edit: tuple[str, str], problem: str) -> None:
    with pytest.raises(ConfigError, match=problem):
        parse_config(CONFIG.replace(*edit))


@pytest.mark.parametrize("key", ["speed = 0.2", "max_iterations = 50"])
def test_a_library_config_takes_no_generator_settings(key: str) -> None:
    text = f'[gaits]\nlibrary = "lib.json"\n{key}\n[model]' + CONFIG.split("[model]")[1]
    name = key.split(" ")[0]
    with pytest.raises(ConfigError, match=rf"\[gaits\].{name}: is a gait generator's setting"):
        parse_config(text)
