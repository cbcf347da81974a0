"""A generator reads a point's values as they are: ``compass-hzd`` takes ``step_length`` in
metres and ``step_duration`` in seconds.  A config that declared ``unit = "cm"`` with ``min = 4,
max = 16`` made a session that asked for steps of 4 to 16 m (none can be posed: every proposal
infeasible), showing them as cm; a duration in ms asked for steps of minutes.  A new session or
run now refuses such a unit, naming ``[space.F].unit``; a stored config still parses."""

from __future__ import annotations

import pytest

from gaitpref import Session
from gaitpref.config import ConfigError, parse_config
from gaitpref.config.new import check_new
from gaitpref.storage import MemoryStorage

MODEL = "[model]\nlengthscale = 0.03\nsignal_variance = 0.005\nnoise = 0.02\n"


def _config(length_unit: str, duration_unit: str = "s", width_unit: str = "m") -> str:
    return (
        f'[space.step_length]\nmin = 4\nmax = 16\nunit = "{length_unit}"\n'
        f'[space.step_duration]\nmin = 0.5\nmax = 1.1\nunit = "{duration_unit}"\n'
        f'[space.step_width]\nmin = 10\nmax = 30\nunit = "{width_unit}"\n'
        f'[gaits]\ngenerator = "compass-hzd"\n{MODEL}'
    )


@pytest.mark.parametrize(
    ("units", "feature", "want"),
    [(("cm",), "step_length", "m"), (("m", "ms"), "step_duration", "s")],
)
def test_a_feature_in_another_unit_than_the_generator_reads_is_refused_naming_it(
    units: tuple[str, ...], feature: str, want: str
) -> None:
    config = parse_config(_config(*units))  # parses: a stored session's config reopens
    with pytest.raises(ConfigError) as info:
        check_new(config)
    err = info.value
    assert (err.table, err.key) == (f"space.{feature}", "unit")
    assert str(err).startswith(f"[space.{feature}].unit: [gaits] generator 'compass-hzd' reads")
    assert f"in {want!r}, got {units[-1]!r}" in str(err)
    store = MemoryStorage()
    with pytest.raises(ConfigError, match=r"\.unit: "):
        Session.create(store, config, subject="S01")
    assert store.list_sessions() == []


def test_the_generators_units_or_none_pass_and_a_labels_unit_is_free() -> None:
    """``step_width`` is a label (no effect on the gait): any unit; an empty unit is taken as
    the generator's."""
    check_new(parse_config(_config("m", "s", "cm")))
    check_new(parse_config(_config("", "")))
