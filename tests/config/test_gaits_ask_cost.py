"""``[gaits] max_iterations x max_infeasible`` is bounded for a new session or run: each key
alone was, their product (the solver iterations one ask may spend on gaits that cannot be made)
was not, and 10,000 x 1,000 was about a day of solver time for one ask.  A stored config past it
still parses (``gaitpref.config.new``: a session of an earlier release reopens as it ran)."""

from __future__ import annotations

from pathlib import Path

import pytest

from gaitpref import load_config
from gaitpref.config import LIMITS, ConfigError, parse_config
from gaitpref.config.new import check_new
from gaitpref.config.schema import (
    DEFAULT_MAX_INFEASIBLE,
    DEFAULTS_VERSION,
    MAX_ASK_ITERATIONS,
    MAX_GAIT_ITERATIONS,
    MAX_INFEASIBLE,
)

SPACE = "[space.step_length]\nmin = 0.08\nmax = 0.18\nnum = 11\n"
MODEL = "[model]\nlengthscale = 0.03\nsignal_variance = 0.005\nnoise = 0.02\n"


def _config(**gaits: int) -> str:
    keys = "".join(f"{k} = {v}\n" for k, v in gaits.items())
    return f'{SPACE}[gaits]\ngenerator = "compass-hzd"\nspeed = 0.2\n{keys}{MODEL}'


def test_the_bound_lets_either_key_alone_reach_its_own_maximum() -> None:
    """Configs that raise one key alone, as earlier releases allowed, still load."""
    assert MAX_ASK_ITERATIONS == MAX_GAIT_ITERATIONS * DEFAULT_MAX_INFEASIBLE
    assert LIMITS["gait solver iterations an ask (max_iterations x max_infeasible)"] == 200_000
    spec = parse_config(_config(max_iterations=MAX_GAIT_ITERATIONS)).generator
    assert spec is not None and spec.max_infeasible == DEFAULT_MAX_INFEASIBLE
    spec = parse_config(_config(max_infeasible=MAX_INFEASIBLE)).generator  # 60 x 1000
    assert spec is not None and spec.max_infeasible == MAX_INFEASIBLE
    largest = MAX_ASK_ITERATIONS // MAX_INFEASIBLE  # 200 x 1000: exactly at the bound
    check_new(parse_config(_config(max_iterations=largest, max_infeasible=MAX_INFEASIBLE)))
    check_new(parse_config(_config(max_iterations=MAX_GAIT_ITERATIONS)))


@pytest.mark.parametrize(
    ("iterations", "infeasible"),
    [(MAX_GAIT_ITERATIONS, MAX_INFEASIBLE), (201, MAX_INFEASIBLE), (10_000, 21)],
)
def test_a_product_past_the_bound_is_refused_naming_both_keys(
    iterations: int, infeasible: int
) -> None:
    config = parse_config(_config(max_iterations=iterations, max_infeasible=infeasible))
    with pytest.raises(ConfigError) as info:
        check_new(config)
    err = info.value
    assert (err.table, err.key) == ("gaits", "max_infeasible")
    text = str(err)
    assert text.startswith("[gaits].max_infeasible: max_iterations x max_infeasible is ")
    assert f"{iterations * infeasible:,} solver iterations" in text
    assert f"at most {MAX_ASK_ITERATIONS:,}" in text


def test_a_config_file_past_the_bound_loads_but_makes_no_new_session(tmp_path: Path) -> None:
    """A config stored with a session of an earlier release reopens (``load_config`` parses
    it); a new session or run from it is refused, naming the keys, and the file is left as it
    was."""
    path = tmp_path / "exo.toml"
    text = _config(max_iterations=10_000, max_infeasible=1000)
    path.write_text(text, encoding="utf-8")
    config = load_config(path)
    assert config.generator is not None and config.generator.max_infeasible == 1000
    with pytest.raises(ConfigError, match=r"\[gaits\]\.max_infeasible: max_iterations x "):
        check_new(config)
    assert path.read_text(encoding="utf-8") == text


def test_a_session_recorded_without_an_iteration_budget_still_parses() -> None:
    """Defaults before 0.5 give max_iterations = None (no budget, and no max_infeasible key
    then): the product is not checked, so such sessions reopen as they ran."""
    config = parse_config(_config(), defaults="0.4")
    assert config.generator is not None and "max_iterations" not in config.generator.settings
    assert parse_config(_config(), defaults=DEFAULTS_VERSION).generator is not None


def test_a_new_session_is_refused_and_nothing_is_written() -> None:
    from gaitpref import Session
    from gaitpref.storage import MemoryStorage

    store = MemoryStorage()
    config = parse_config(_config(max_iterations=MAX_GAIT_ITERATIONS, max_infeasible=100))
    with pytest.raises(ConfigError, match=r"max_iterations x max_infeasible is 10,000 x 100"):
        Session.create(store, config, subject="S01")
    assert store.list_sessions() == []
