"""The coactive line direction and excluded trials (``[cospar] line_coactive``, defaults 0.12).

With ``line_direction = "coactive"`` a line runs towards the point the last answer's coactive
suggestions name.  An exclusion takes a trial's suggestions out of the model, but the direction
was read from every suggestion recorded with the answer: the next line still followed the
excluded trial's "longer step".  ``line_coactive = "kept"`` (new configs) reads the suggestions
the model keeps; ``"recorded"`` (every config of defaults 0.11 or earlier) reads them all, so
that sessions recorded before replay as they ran.
"""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import ConfigError, Feature, Space, SquaredExponential
from gaitpref.config import check_ignored, parse_config
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import LineSettings, draw_line
from gaitpref.sessions.stored_config import config_of, library_meta
from tests.config.records import stored_record

BOX = Space([Feature(f"x{k}", (0.0, 1.0), continuous=True) for k in range(3)])
KERNEL = SquaredExponential((0.3, 0.3, 0.3), 1.0, 1e-6)


def _loop(coactive: str) -> tuple[LineCoSpar, int]:
    """A coactive-direction loop whose last answer suggested a bigger x1 (query id returned)."""
    settings = LineSettings(20, "coactive", coactive=coactive)  # type: ignore[arg-type]
    loop = LineCoSpar(BOX, KERNEL, 0.05, n=1, buffer=1, seed=3, line=settings)
    q = loop.ask()
    loop.tell(q, [])
    q = loop.ask()
    a = q.actions[0]
    loop.tell(q, [(a, q.buffer[0], "first")], [(a, "x1", "+big")])
    return loop, q.id


def _sources(loop: LineCoSpar, qid: int, source: str) -> list[int]:
    answer = next(a for a in loop.answers if a.query.id == qid)
    return [k for k, p in enumerate(answer.preferences) if p.source == source]


def test_an_answers_suggestion_steers_the_next_line() -> None:
    for coactive in ("kept", "recorded"):
        loop, _ = _loop(coactive)
        assert loop.ask().line.direction == (0.0, 1.0, 0.0)  # type: ignore[union-attr]


def test_an_excluded_suggestion_no_longer_steers_the_line() -> None:
    loop, qid = _loop("kept")
    loop.exclude({qid: _sources(loop, qid, "coactive")})
    q = loop.ask()
    assert q.line is not None and q.line.direction != (0.0, 1.0, 0.0)
    # the line the random rule draws from the same seed: as after an answer without suggestions
    random = draw_line(BOX, LineSettings(20, "random"), q.line.seed, np.array(q.line.origin))
    assert q.line.direction == random.direction
    np.testing.assert_array_equal(q.line.points, random.points)


def test_a_suggestion_kept_in_the_model_still_steers_it() -> None:
    loop, qid = _loop("kept")
    loop.exclude({qid: _sources(loop, qid, "comparison")})  # only the comparison goes
    assert loop.ask().line.direction == (0.0, 1.0, 0.0)  # type: ignore[union-attr]


def test_recorded_follows_the_excluded_suggestion_as_before_0_12() -> None:
    loop, qid = _loop("recorded")
    loop.exclude({qid: _sources(loop, qid, "coactive")})
    assert loop.ask().line.direction == (0.0, 1.0, 0.0)  # type: ignore[union-attr]


def test_line_settings_name_a_bad_coactive_source() -> None:
    with pytest.raises(ValueError, match="line coactive source must be one of kept, recorded"):
        LineSettings(coactive="all")  # type: ignore[arg-type]


TEXT = "\n".join(
    ["[model]", "lengthscale = 0.3", "signal_variance = 1.0", "noise = 0.05", "jitter = 1e-6"]
    + [f"[space.x{k}]\nmin = 0.0\nmax = 1.0" for k in range(3)]
    + ["[cospar]", 'subspace = "line"', 'line_direction = "coactive"']
)


@pytest.mark.parametrize("version", ["0.1", "0.8", "0.10", "0.11"])
def test_sessions_recorded_before_0_12_replay_with_every_suggestion(version: str) -> None:
    assert parse_config(TEXT, defaults=version).line.coactive == "recorded"
    stored = config_of(stored_record(TEXT, {"config_defaults": version}))
    assert stored.line.coactive == "recorded"


def test_a_new_config_reads_the_kept_suggestions_and_records_it() -> None:
    assert config_of(stored_record(TEXT, {})).line.coactive == "recorded"  # no version: 0.1's
    new = parse_config(TEXT)
    assert new.line.coactive == "kept" and new.relies_on_changed_defaults
    assert library_meta(new) == {"config_defaults": "0.13"}
    assert config_of(stored_record(TEXT, library_meta(new))).line.coactive == "kept"
    given = parse_config(TEXT + '\nline_coactive = "recorded"')
    assert given.line.coactive == "recorded"
    check_ignored(given)


def test_line_coactive_without_the_coactive_direction_is_refused_by_name() -> None:
    text = TEXT.replace('line_direction = "coactive"', 'line_coactive = "kept"')
    config = parse_config(text)  # a stored config still parses
    assert config.line.direction == "random" and config.line.coactive == "kept"
    with pytest.raises(ConfigError, match="would be ignored") as e:
        check_ignored(config)
    assert (e.value.table, e.value.key) == ("cospar", "line_coactive")
