"""A new session refuses a config key that the config would ignore.

``[safety] risk`` and ``lambda`` set the region of avoidance, which is off without ``avoid``:
a config giving either without ``avoid`` parsed, and the rule it asked for did nothing
(``Safety.avoid == 0``), silently.  So did ``[model] refit_every`` and ``[model.prior]`` with
``fit = "fixed"`` (which never refits), ``[model] hypotheses`` without ``hyper = "average"``,
``max`` of a ``[space.F]`` with ``num = 1`` (its one value is ``min``), the line path's keys
with ``[cospar] subspace = "grid"``, a grid's ``[model] sampler`` on the line path and
gated-eubo's burst and early settings when they are off as given.  Now a new
session (and ``simulate``) refuses each with a ConfigError naming the table and key; a session
stored with one reopens and replays as it was.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref import ConfigError, Session
from gaitpref.cli import app
from gaitpref.config import check_ignored, load_config, parse_config
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive

RATING = '[feedback.rating]\nlabels = ["bad", "okay", "good"]\n\n'


def _text(extra: str) -> str:
    return load_config(CONFIG).text + "\n" + extra


IGNORED = [
    ("[safety]\nrisk = 0.5\n", "risk"),
    ("[safety]\nlambda = 2.0\n", "lambda"),
    (RATING + "[safety]\nrisk = 0.5\n", "risk"),
    (RATING + "[safety]\nlambda = 2.0\nunsafe_radius = 0.1\n", "lambda"),
]


@pytest.mark.parametrize(("extra", "key"), IGNORED)
def test_a_region_setting_without_avoid_is_refused_by_name(extra: str, key: str) -> None:
    config = parse_config(_text(extra))  # a stored config still parses
    assert config.safety.avoid == 0
    with pytest.raises(ConfigError, match=rf"\[safety\]\.{key}: is a setting of the region") as e:
        check_ignored(config)
    assert (e.value.table, e.value.key) == ("safety", key)
    with pytest.raises(ConfigError, match=rf"\[safety\]\.{key}"):
        Session.create(MemoryStorage(), config, "S01")


MODEL_IGNORED = [
    ('fit = "fixed"', 'fit = "fixed"\nrefit_every = 5', "model", "refit_every"),
    (
        'fit = "fixed"',
        'fit = "fixed"\n\n[model.prior]\nsignal_variance = [1, 1]',
        "model.prior",
        None,
    ),
    ('fit = "fixed"', 'fit = "evidence"\nhypotheses = [0.5, 1, 2]', "model", "hypotheses"),
]


@pytest.mark.parametrize(("old", "new", "table", "key"), MODEL_IGNORED)
def test_a_learning_key_the_fit_never_reads_is_refused_by_name(
    old: str, new: str, table: str, key: str | None
) -> None:
    text = load_config(CONFIG).text
    assert text.count(old) == 1
    config = parse_config(text.replace(old, new))  # a stored config still parses
    with pytest.raises(ConfigError, match="would be ignored") as e:
        check_ignored(config)
    assert (e.value.table, e.value.key) == (table, key)
    taken = 'fit = "evidence"\nrefit_every = 5\nhyper = "average"\nhypotheses = [0.5, 1, 2]'
    check_ignored(
        parse_config(text.replace(old, taken + "\n\n[model.prior]\nsignal_variance = [1, 1]"))
    )


GRID = """
[space.a]
min = 0.0
max = 1.0
num = 5

[space.b]
min = 0.5
max = 0.5
num = 1

[model]
lengthscale = 0.3
signal_variance = 1.0
noise = 0.1
"""


@pytest.mark.parametrize(
    ("old", "new", "table", "key"),
    [
        ("max = 0.5\nnum = 1", "max = 0.9\nnum = 1", "space.b", "num"),
        ("min = 0.5\nmax = 0.5", "min = 0.7\nmax = 0.5", "space.b", "num"),
        ("noise = 0.1", 'noise = 0.1\n[cospar]\nsubspace = "grid"\nline_count = 8', "cospar", None),
        (
            "noise = 0.1",
            'noise = 0.1\n[cospar]\nsubspace = "grid"\nline_points = 9',
            "cospar",
            None,
        ),
    ],
)
def test_a_grid_key_that_is_ignored_is_refused_by_name(
    old: str, new: str, table: str, key: str | None
) -> None:
    config = parse_config(GRID.replace(old, new))  # a stored config still parses
    assert config.subspace == "grid" and config.space.shape == (5, 1)
    with pytest.raises(ConfigError, match="would be ignored") as e:
        check_ignored(config)
    assert e.value.table == table and e.value.key == (key or new.split("\n")[-1].split(" ")[0])
    check_ignored(parse_config(GRID))
    check_ignored(
        parse_config(GRID.replace("noise = 0.1", "noise = 0.1\n[cospar]\nline_count = 8"))
    )


def test_a_grid_sampler_on_the_line_path_is_refused_by_name() -> None:
    # a point set always takes PointEngine: sampler = "dense" on the line path did nothing
    line = GRID.replace("num = 5\n", "")
    for sampler in ("dense", "scalable"):
        config = parse_config(line.replace("noise = 0.1", f'noise = 0.1\nsampler = "{sampler}"'))
        assert config.subspace == "line"
        with pytest.raises(ConfigError, match="would be ignored") as e:
            check_ignored(config)
        assert (e.value.table, e.value.key) == ("model", "sampler")
        grid = parse_config(GRID.replace("noise = 0.1", f'noise = 0.1\nsampler = "{sampler}"'))
        check_ignored(grid)
    check_ignored(parse_config(line.replace("noise = 0.1", 'noise = 0.1\nsampler = "auto"')))


@pytest.mark.parametrize(
    ("settings", "key"),
    [
        ("sparring_from = 5", "sparring_from"),
        ("sparring_from = 10\nsparring_until = 5", "sparring_until"),
        ("sparring_from = 5\nsparring_until = 5", "sparring_until"),
        ("early_trials = 30", "early_trials"),
        ("early_scale = 1.0\nearly_trials = 30", "early_trials"),
        ("early_scale = 0.5\nearly_trials = 0", "early_scale"),
    ],
)
def test_gated_eubo_settings_that_are_off_as_given_are_refused_by_name(
    settings: str, key: str
) -> None:
    text = GRID + '[cospar]\nstrategy = "gated-eubo"\n[cospar.strategy_settings]\n' + settings
    config = parse_config(text)  # a stored config still parses
    with pytest.raises(ConfigError, match="would be ignored") as e:
        check_ignored(config)
    assert (e.value.table, e.value.key) == ("cospar.strategy_settings", key)


@pytest.mark.parametrize(
    "settings",
    [
        "sparring_until = 5",
        "sparring_from = 2\nsparring_until = 5",
        "early_scale = 0.5",
        "early_scale = 1.0",
        "early_scale = 0.5\nearly_trials = 3",
        "gates = 2",
    ],
)
def test_gated_eubo_settings_that_act_are_taken(settings: str) -> None:
    check_ignored(parse_config(GRID + "[cospar.strategy_settings]\n" + settings))


def test_the_settings_with_avoid_are_taken() -> None:
    text = _text(RATING + '[safety]\navoid = ["bad"]\nrisk = 0.5\nunsafe_radius = 0.1\n')
    check_ignored(parse_config(text))
    check_ignored(parse_config(_text("[safety]\nunsafe_radius = 0.1\n")))
    for name in ("exo-1d-step-length", "synthetic-6d", "compass-continuous-3d"):
        check_ignored(load_config(name))


def test_session_new_and_simulate_refuse_it(tmp_path: Path) -> None:
    path = tmp_path / "ignored.toml"
    path.write_text(_text("[safety]\nrisk = 0.5\n"), "utf-8")
    db = tmp_path / "lab.db"
    for args in (
        ["session", "new", "--config", str(path), "--subject", "S01", "--db", str(db)],
        ["simulate", str(path), "--objective", "random-gp", "--trials", "1"],
    ):
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 2, result.output
        assert "[safety].risk: is a setting of the region" in " ".join(result.output.split())
        assert "Traceback" not in result.output
    assert not db.exists()


def test_a_session_stored_with_such_a_key_replays(
    tmp_path: Path, drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gaitpref.config.new

    url = f"sqlite:///{tmp_path / 'old.db'}"
    with monkeypatch.context() as m:  # as earlier releases took it
        m.setattr(gaitpref.config.new, "check_ignored", lambda config: None)
        s = Session.create(url, parse_config(_text("[safety]\nlambda = 2.0\n")), "S01", seed=4)
    drive(s, 3)
    mean = s.posterior().mean.copy()
    s.close()
    with Session.open(url, s.id) as again:
        assert (again.posterior().mean == mean).all() and len(again.trials()) == 3
        drive(again, 1)
