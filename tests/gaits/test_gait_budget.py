"""The iteration budget of a gait made on demand (``[gaits] max_iterations``): a far-infeasible
request stops within it and says so, a gait found within it is the one found without it, the
budget is part of a gait's key only when set, and configs recorded before it keep no budget."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from tests.config.records import stored_record
from tests.sessions.gaitkit import COMPASS

from gaitpref.config import DEFAULTS_VERSION, parse_config
from gaitpref.gaits import GaitRequest, make_generator, optimize_gait
from gaitpref.gaits import optimize as optimize_module
from gaitpref.sessions.stored_config import config_of, library_meta

#: the key of the 0.12 m gait at 0.2 m/s as gaitpref wrote it before the budget existed
KEY_BEFORE_THE_BUDGET = "83df89346fa9dea1831605abd4b780b7a19dd9f362833c9e1139cde50bf04a6d"


@pytest.fixture
def spent(monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, int]]:
    """Each SLSQP run's (iteration limit, iterations taken)."""
    runs: list[tuple[int, int]] = []
    from scipy.optimize import minimize as real  # what optimize.py calls

    def counting(*args: Any, **kwargs: Any) -> Any:
        res = real(*args, **kwargs)
        runs.append((int(kwargs["options"]["maxiter"]), int(res.nit)))
        return res

    monkeypatch.setattr(optimize_module, "minimize", counting)
    return runs


def test_a_far_infeasible_gait_stops_within_its_budget(spent: list[tuple[int, int]]) -> None:
    warm = optimize_gait(GaitRequest(0.12, speed=0.2))  # a neighbour, as a session has one
    spent.clear()
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2, "max_iterations": 10})
    gait = g.make(np.array([0.40]), warm)  # a 0.40 m step at 0.2 m/s: no gait
    assert not gait.feasible
    assert gait.message.startswith("infeasible: no feasible gait within 10 iterations (warm start")
    assert "no periodic orbit" in gait.message  # and what was still violated
    assert spent[0][0] == 10 and sum(n for _, n in spent) <= 10


def test_without_a_budget_each_start_has_the_formulations_limit(
    spent: list[tuple[int, int]],
) -> None:
    warm = optimize_gait(GaitRequest(0.12, speed=0.2))
    spent.clear()
    old = make_generator("compass-hzd", ["step_length"], {"speed": 0.2}).make(
        np.array([0.02]), warm
    )
    assert [limit for limit, _ in spent] == [300, 300]  # HZDSettings.max_iterations per start
    first = spent[0][1]
    spent.clear()
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2, "max_iterations": 60})
    new = g.make(np.array([0.02]), warm)
    # within the budget: both starts run (the second with what the first left), and the reason
    # is the solver's, not the budget's
    assert [limit for limit, _ in spent] == [60, 60 - first]
    assert not new.feasible and new.message == old.message
    assert "iterations" not in new.message.split(";")[0]


def test_a_gait_found_within_the_budget_is_the_one_found_without_it() -> None:
    request = GaitRequest(0.12, speed=0.2)
    free, bounded = optimize_gait(request), optimize_gait(request, max_iterations=60)
    assert free.feasible and bounded.feasible and free.message == bounded.message
    assert np.array_equal(free.alpha, bounded.alpha) and free.cot == bounded.cot


@pytest.mark.parametrize("bad", [0, -3, 2.5, True])
def test_a_bad_budget_is_refused_naming_it(bad: Any) -> None:
    with pytest.raises(ValueError, match="max_iterations must be an integer >= 1"):
        optimize_gait(GaitRequest(0.12, speed=0.2), max_iterations=bad)


def test_the_budget_is_in_the_key_only_when_set() -> None:
    point = np.array([0.12])
    free = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    bounded = make_generator("compass-hzd", ["step_length"], {"speed": 0.2, "max_iterations": 60})
    assert free.key(point) == KEY_BEFORE_THE_BUDGET  # gaits made before it keep their keys
    assert bounded.key(point) != free.key(point)
    assert bounded.settings()["max_iterations"] == 60 and "max_iterations" not in free.settings()


CONFIG = COMPASS.replace("[cospar]\n", "[cospar]\nbuffer = 1\n")  # no default but the budget


def test_a_config_left_to_the_defaults_records_the_budgets_version() -> None:
    cfg = parse_config(CONFIG)
    assert cfg.generator is not None and cfg.generator.settings["max_iterations"] == 60
    assert cfg.relies_on_changed_defaults
    assert library_meta(cfg) == {"config_defaults": DEFAULTS_VERSION}  # 0.5 or later
    again = config_of(stored_record(CONFIG, library_meta(cfg)))
    assert again.generator == cfg.generator
    given = CONFIG.replace("speed = 0.2", 'speed = 0.2\nmax_iterations = 40\nrecommend = "made"')
    assert "jitter = 0.0" in given  # COMPASS gives its jitter; share, warm_first: the others
    model = '[model]\nshare = "average"\nwarm_first = "recommended"\n'
    explicit = parse_config(given.replace("[model]\n", model))
    assert explicit.generator is not None and explicit.generator.settings["max_iterations"] == 40
    assert not explicit.relies_on_changed_defaults and library_meta(explicit) == {}


@pytest.mark.parametrize("meta", [{}, {"config_defaults": "0.4"}, {"config_defaults": "0.1"}])
def test_a_session_recorded_before_the_budget_replays_without_it(
    meta: dict[str, object],
) -> None:
    cfg = config_of(stored_record(CONFIG, meta))
    assert cfg.generator is not None and "max_iterations" not in cfg.generator.settings
    generator = cfg.generator.make(cfg.space)
    assert generator.key(np.array([0.12])) == KEY_BEFORE_THE_BUDGET
