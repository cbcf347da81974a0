from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref import ConfigError, load_config, shipped_configs
from gaitpref.config import parse_config
from gaitpref.space import Move

GOOD = """
[space.step_length]
min = 0.08
max = 0.18
num = 15
unit = "m"
coactive = [0.1, 0.2]

[model]
lengthscale = { step_length = 0.03 }
signal_variance = 0.005
jitter = 1e-7
noise = 0.02

[cospar]
n = 1
buffer = 1
coactive_weight = 1.0
seed = 0
"""


def test_issue_example_parses() -> None:
    cfg = parse_config(GOOD)
    assert cfg.space.shape == (15,)
    assert cfg.space.features[0].unit == "m"
    assert np.allclose(cfg.space.features[0].array, np.linspace(0.08, 0.18, 15))
    assert cfg.kernel.lengthscale == (0.03,) and cfg.kernel.variance == 0.005
    assert (cfg.noise, cfg.n, cfg.buffer, cfg.coactive_weight, cfg.seed) == (0.02, 1, 1, 1.0, 0)
    assert len(cfg.sha256) == 64


@pytest.mark.parametrize(
    ("name", "shape", "lengthscale", "variance", "jitter", "noise", "n", "b"),
    [
        ("exo-1d-step-length", (15,), (0.03,), 0.005, 1e-7, 0.02, 1, 1),
        ("exo-2d-length-duration", (15, 10), (0.03, 0.08), 0.005, 1e-7, 0.02, 1, 1),
        ("exo-2d-length-width", (15, 6), (0.03, 0.03), 0.005, 1e-7, 0.02, 1, 1),
        ("exo-2d-rated", (15, 6), (0.03, 0.03), 0.005, 1e-7, 0.02, 1, 1),  # and ratings
        ("compass-gait", (24,), (0.025,), 1e-4, 1e-8, 0.01, 2, 0),
        ("synthetic-2d", (30, 30), (0.15, 0.15), 1e-4, 1e-5, 0.01, 1, 1),
    ],
)
def test_shipped_configs_carry_the_papers_settings(
    name: str,
    shape: tuple[int, ...],
    lengthscale: tuple[float, ...],
    variance: float,
    jitter: float,
    noise: float,
    n: int,
    b: int,
) -> None:
    assert name in shipped_configs()
    cfg = load_config(name)
    assert cfg.space.shape == shape
    assert cfg.kernel.lengthscale == lengthscale
    assert (cfg.kernel.variance, cfg.kernel.jitter, cfg.noise) == (variance, jitter, noise)
    assert (cfg.n, cfg.buffer) == (n, b)


def test_exo_coactive_fractions() -> None:
    width = load_config("exo-2d-length-width").space.features[1]
    assert width.coactive == (0.2, 0.4) and width.unit == "m"
    duration = load_config("exo-2d-length-duration").space.features[1]
    assert duration.coactive == (0.1, 0.2) and np.isclose(duration.values[-1], 1.15)


def test_load_from_path(tmp_path: Path) -> None:
    p = tmp_path / "mine.toml"
    p.write_text(GOOD)
    cfg = load_config(p)
    assert cfg.name == "mine" and cfg.text == GOOD


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda t: t.replace("num = 15", "num = 0"),
            r"\[space.step_length\].num: must be an integer >= 1",
        ),
        (
            lambda t: t.replace("noise = 0.02", "noise = -1"),
            r"\[model\].noise: must be a finite number >= 1e-12 and <= 1e\+12, got -1",
        ),
        (lambda t: t.replace("noise = 0.02", ""), r"\[model\].noise: missing"),
        (lambda t: t.replace("seed = 0", "seed = 'a'"), r"\[cospar\].seed: must be an integer"),
        (
            lambda t: t.replace("seed = 0", "sead = 0"),
            r"\[cospar\]: unknown key 'sead' \(allowed: n, buffer, coactive_weight, seed,",
        ),
        (
            lambda t: t.replace('unit = "m"', 'units = "m"'),
            r"\[space.step_length\]: unknown key 'units'",
        ),
        (
            lambda t: t.replace("{ step_length = 0.03 }", "{ length = 0.03 }"),
            r"\[model.lengthscale\]: unknown key 'length' \(allowed: step_length\)",
        ),
        (
            lambda t: t.replace("max = 0.18", "max = 0.01"),
            r"\[space.step_length\].max: must be greater than min \(0.08\), got 0.01",
        ),
        (
            lambda t: t.replace("coactive = [0.1, 0.2]", "coactive = [0.5, 0.2]"),
            r"\[space.step_length\].coactive: must be \[small, big\] with 0 < small <= big",
        ),
        (
            lambda t: t.replace("min = 0.08", "values = [0.1]\nmin = 0.08"),
            "either values or min/max/num",
        ),
        (lambda t: t + "\n[extra]\n", "top level: unknown key 'extra'"),
        (lambda t: t.replace("[model]", "[modle]"), r"top level: unknown key 'modle'"),
        (lambda t: t.replace("[space.step_length]", "[space.step_length"), "not valid TOML"),
    ],
)
def test_config_errors_name_the_key(edit, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ConfigError, match=message):
        parse_config(edit(GOOD))


def test_missing_config_file_names_it() -> None:
    with pytest.raises(ConfigError, match=r"'nope\.toml': no such file; shipped configs are"):
        load_config("nope.toml")


def test_a_folder_for_a_config_is_named_a_folder(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="is a folder") as info:
        load_config(tmp_path)
    assert str(tmp_path) in str(info.value) and "no such file" not in str(info.value)


def test_a_config_file_that_is_not_toml_is_named(tmp_path: Path) -> None:
    path = tmp_path / "exo.toml"
    path.write_text("x = [\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="is not valid TOML") as info:
        load_config(path)
    assert str(info.value).startswith(f"config {str(path)!r} is not valid TOML: ")


def test_a_config_file_with_a_bad_key_is_named_with_the_key(tmp_path: Path) -> None:
    """A sweep or a session names several configs: '[model]: unknown key' did not say whose."""
    path = tmp_path / "exo.toml"
    path.write_text(GOOD.replace("[model]", "[model]\njiter = 1"), encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value).startswith(f"config {str(path)!r}: [model]: unknown key 'jiter'")
    assert info.value.table == "model"  # where, as parse_config says it


def test_n1_b0_is_allowed_and_learns_from_suggestions_only() -> None:
    cfg = parse_config(GOOD.replace("buffer = 1", "buffer = 0"))
    loop = cfg.make_loop(seed=0)
    q = loop.ask()
    assert q.buffer == ()
    a = q.actions[0]
    move: Move = "+big" if cfg.space.point(a)[0] < 0.13 else "-big"
    loop.tell(q, [], [(a, "step_length", move)])
    target = cfg.space.coactive_move(a, "step_length", move)
    assert target is not None
    assert loop.posterior.mean[target] > loop.posterior.mean[a]


def test_a_config_file_with_a_byte_order_mark_is_named(tmp_path: Path) -> None:
    # Notepad's "UTF-8 with BOM": was "Invalid statement (at line 1, column 1)"
    path = tmp_path / "bom.toml"
    path.write_text(load_config("exo-1d-step-length").text, encoding="utf-8-sig")
    with pytest.raises(
        ConfigError,
        match=r"^config '.*bom.toml' is not valid TOML: it starts "
        r"with a byte order mark \(U\+FEFF",
    ):
        load_config(path)


def test_the_rated_example_config_rates_and_avoids() -> None:
    """No shipped config had [feedback.rating] or [safety] avoid: a lab wrote its own."""
    from gaitpref.config import check_new

    cfg = load_config("exo-2d-rated")
    check_new(cfg)  # a new session takes it
    assert cfg.ordinal is not None
    assert cfg.ordinal.categories == ("very bad", "bad", "okay", "good")
    assert cfg.safety.avoid == 1 and cfg.safety.unsafe_radius == 0.1
    assert cfg.safety.risk == 0.35  # the default its comment works out: 1/4 + 0.1
    # as its comment says: a flag takes out the gait and its step-length neighbours alone
    from gaitpref.loop.safety import near

    middle = 7 * 6 + 3  # step length 8 of 15, step width 4 of 6
    assert np.flatnonzero(near(cfg.space, [middle], 0.1)).tolist() == [39, 45, 51]
    base = load_config("exo-2d-length-width")  # built on it: the same space, model and loop
    assert cfg.space.shape == base.space.shape and cfg.kernel == base.kernel
    assert (cfg.n, cfg.buffer, cfg.strategy) == (base.n, base.buffer, base.strategy)
