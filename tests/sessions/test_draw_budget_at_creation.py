"""A new session (and ``gaitpref simulate``) refuses a config whose asks would pass the sampling
budget, naming the setting to lower.

``[cospar] strategy = "plausible-eubo"`` with ``samples = 4096`` on a 200 x 200 grid parsed and
made a session; its first ask then raised the numerics' ValueError (4096 x 40,000 values, more
than ``SAMPLE_LIMIT_ELEMENTS``), with the subject waiting.  Now ``Session.create`` raises a
ConfigError naming ``[cospar.strategy_settings].samples`` and the most it may be, and writes
nothing.  A session stored with such a config by an earlier release still opens.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import gaitpref.config.draws as draws
from gaitpref import ConfigError, Session
from gaitpref.cli import app
from gaitpref.config import check_draws, draw_size, load_config, parse_config, shipped_configs
from gaitpref.model import SAMPLE_LIMIT_ELEMENTS
from gaitpref.storage import MemoryStorage

BIG = """
name = "big"
[space.a]
min = 0.0
max = 1.0
num = {num}
[space.b]
min = 0.0
max = 1.0
num = {num}
[model]
lengthscale = 0.1
signal_variance = 1.0
noise = 0.1
[cospar]
strategy = "{strategy}"
[cospar.strategy_settings]
{setting} = {count}
"""


def _big(
    num: int = 200, strategy: str = "plausible-eubo", setting: str = "samples", count: int = 4096
) -> str:
    return BIG.format(num=num, strategy=strategy, setting=setting, count=count)


def test_plausible_eubos_samples_past_the_budget_are_named_with_the_most_allowed() -> None:
    config = parse_config(_big())
    assert draw_size(config) == (4096, 40_000, "samples")
    with pytest.raises(ConfigError, match=r"^\[cospar.strategy_settings\].samples: is 4096") as err:
        check_draws(config)
    assert (err.value.table, err.value.key) == ("cospar.strategy_settings", "samples")
    most = SAMPLE_LIMIT_ELEMENTS // 40_000
    assert most == 3355 and f"set samples to at most {most}" in str(err.value)
    assert "163,840,000 values" in str(err.value) and "subspace = 'line'" in str(err.value)
    check_draws(parse_config(_big(count=most)))  # at the budget: taken


def test_gated_eubos_gates_past_the_budget_are_named() -> None:
    config = parse_config(_big(400, "gated-eubo", "gates", 1000))
    with pytest.raises(ConfigError, match=r"^\[cospar.strategy_settings\].gates: is 1000") as err:
        check_draws(config)
    assert err.value.key == "gates" and "at most 838" in str(err.value)


def test_the_querys_n_is_named_when_it_sets_the_draw(monkeypatch: pytest.MonkeyPatch) -> None:
    """No config reaches the budget with n (64 x 10**6 fits): a smaller budget shows the key."""
    monkeypatch.setattr(draws, "SAMPLE_LIMIT_ELEMENTS", 1000)
    text = _big(30, "self-sparring", "", 0).replace("[cospar.strategy_settings]\n = 0\n", "")
    config = parse_config(text.replace("[cospar]\n", "[cospar]\nn = 2\n"))
    assert draw_size(config) == (2, 900, "n")
    with pytest.raises(ConfigError, match=r"^\[cospar\].n: is 2: each ask draws 2") as err:
        check_draws(config)
    assert err.value.key == "n" and "set n to at most 1" in str(err.value)


@pytest.mark.parametrize("name", shipped_configs())
def test_every_shipped_config_is_within_the_budget(name: str) -> None:
    check_draws(load_config(name))


def test_a_new_session_is_refused_before_anything_is_written(tmp_path: Path) -> None:
    db = MemoryStorage()
    path = tmp_path / "big.toml"
    path.write_text(_big(), encoding="utf-8")
    for config in (path, parse_config(_big())):
        with pytest.raises(ConfigError, match="samples: is 4096"):
            Session.create(db, config, "S01")
    assert Session.list_sessions(db) == []


def test_a_session_stored_with_such_a_config_still_opens(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Created as earlier releases did: it opens (its asks fail as they always did)."""
    import gaitpref.config.new

    db = MemoryStorage()
    with monkeypatch.context() as m:
        m.setattr(gaitpref.config.new, "check_draws", lambda config: None)
        made = Session.create(db, parse_config(_big()), "S01")
    with pytest.raises(ValueError, match="more than the sampling budget"):
        made.next_query()  # what the operator met at the first ask
    again = Session.open(db, made.id)
    assert again.status == "active" and again.config.strategy_settings == {"samples": 4096}


def test_gaitpref_simulate_refuses_it_at_once(tmp_path: Path) -> None:
    path = tmp_path / "big.toml"
    path.write_text(_big(), encoding="utf-8")
    objective = tmp_path / "objective.npy"
    np.save(objective, np.zeros((200, 200)))
    args = ["simulate", str(path), "--objective", str(objective), "--trials", "2"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "samples: is 4096" in result.output and "at most 3355" in result.output
