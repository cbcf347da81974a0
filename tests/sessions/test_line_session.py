"""A session on continuous features (issue 13): its lines are logged and it replays exactly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref import ReplayError, Session
from gaitpref.config import parse_config

TEXT = """\
name = "continuous-3d"
[space.step_length]
min = 0.08
max = 0.18
unit = "m"
[space.step_duration]
min = 0.8
max = 1.2
unit = "s"
[space.step_width]
min = 0.1
max = 0.3
num = 5
[model]
lengthscale = { step_length = 0.03, step_duration = 0.1, step_width = 0.08 }
signal_variance = 1.0
noise = 0.05
jitter = 1e-6
refit_every = 4
[cospar]
strategy = "gated-eubo"
line_points = 30
line_direction = "coactive"
"""


def _utility(point: tuple[float, ...]) -> float:
    target = np.array([0.13, 1.05, 0.2])
    scale = np.array([0.1, 0.4, 0.2])
    return float(-np.sum(((np.asarray(point) - target) / scale) ** 2))


def _drive(session: Session, n: int) -> None:
    for k in range(n):
        q = session.next_query()
        a, p = q.actions[0], q.points[0]
        comps = []
        for b in q.buffer:
            if b != a:
                pb = tuple(session.space.points[b])
                comps.append((a, b, "first" if _utility(p) > _utility(pb) else "second"))
        suggestions = [(a, "step_length", "+small" if p[0] < 0.13 else "-small")] if k % 2 else []
        session.answer(q.id, comps, suggestions)


LOCAL = "[cospar.strategy_settings]\nearly_scale = 0.5\n"  # a local challenger early
ONE_LINE = "line_count = 1\n"  # LineCoSpar's one line per query (the default is a star of 4)


CLOUD = "line_cloud = 40\n"  # 40 points around the best point besides the star


@pytest.mark.parametrize(
    "extra", ["", ONE_LINE, LOCAL, CLOUD], ids=["star", "one-line", "local-challenger", "cloud"]
)
def test_a_continuous_session_replays_exactly(tmp_path: Path, extra: str) -> None:
    url = f"sqlite:///{tmp_path / 's.db'}"
    in_cospar = extra in (ONE_LINE, CLOUD)
    cfg = parse_config(
        TEXT.replace("[cospar]\n", "[cospar]\n" + extra) if in_cospar else TEXT + extra
    )
    assert cfg.line.cloud == (40 if extra == CLOUD else 0)
    lines = 1 if extra == ONE_LINE else 4
    assert cfg.line.lines == lines
    assert cfg.subspace == "line" and cfg.space.continuous
    s = Session.create(url, cfg, "S01", seed=11)
    _drive(s, 6)
    s.undo()
    _drive(s, 3)
    s.exclude(s.trials()[2].number, "stumble")
    _drive(s, 2)
    q = s.next_query()
    reopened = Session.open(url, s.id)
    np.testing.assert_array_equal(reopened.posterior().mean, s.posterior().mean)
    np.testing.assert_array_equal(reopened.space.points, s.space.points)
    assert reopened.pending == q and reopened.pending.points == q.points
    assert reopened.describe(q.actions[0]) == s.describe(q.actions[0])
    reopened.answer(q.id, [(q.actions[0], q.buffer[0], "first")])
    s.refresh()
    assert reopened.next_query() == s.next_query()
    events = [e for e in s.events() if e.kind == "query_issued"]
    line = events[-1].payload["line"]
    if lines == 1:  # what every line-path query stored before stars
        assert set(line) == {"seed", "origin", "direction", "points"}
    else:
        assert set(line) == {"seed", "origin", "direction", "points", "others"}
        directions = np.array([line["direction"], *line["others"]])
        assert directions.shape == (lines, 3)
        np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0)
        assert len(line["points"]) > (31 + 40 if extra == CLOUD else 31)  # 30 a line, origin
    assert events[-1].payload["points"][0] in line["points"]
    reopened.close()
    s.close()


def test_other_lines_stop_replay(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    url = f"sqlite:///{tmp_path / 's.db'}"
    s = Session.create(url, parse_config(TEXT), "S01", seed=2)
    _drive(s, 3)
    s.close()
    import gaitpref.loop.line as line_module
    from gaitpref.loop.lines import draw_line as drawn

    def shifted(space, settings, seed, origin, towards=None):  # type: ignore[no-untyped-def]
        return drawn(space, settings, seed + 1, origin, towards)

    monkeypatch.setattr(line_module, "draw_line", shifted)
    with pytest.raises(ReplayError, match="line"):
        Session.open(url, s.id)


def test_session_show_draws_a_continuous_session(tmp_path: Path) -> None:
    """`gaitpref session show` on a space the paper's figures cannot draw: the posterior at the
    trials' points (as the console shows it), not an error."""
    import json

    from typer.testing import CliRunner

    from gaitpref.cli import app

    db = str(tmp_path / "lab.db")
    s = Session.create(db, parse_config(TEXT), "S01", seed=11)
    _drive(s, 5)
    figure = tmp_path / "show.png"
    result = CliRunner().invoke(
        app, ["session", "show", str(s.id), "--json", "--figure", str(figure), "--db", db]
    )
    assert result.exit_code == 0, result.output
    assert json.loads(result.output)["trials"] == 5
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and figure.stat().st_size > 10_000


def test_a_session_recorded_under_defaults_0_8_replays_with_one_line(tmp_path: Path) -> None:
    """A line session recorded before the star (defaults 0.8: one line per query) reopens and
    goes on with one line, its queries stored as before (no ``others``)."""
    url = f"sqlite:///{tmp_path / 's.db'}"
    old = parse_config(TEXT, defaults="0.8")
    assert old.line.lines == 1
    s = Session.create(url, old, "S01", seed=4)
    _drive(s, 5)
    s.close()
    reopened = Session.open(url, 1)
    _drive(reopened, 2)
    lines = [e.payload["line"] for e in reopened.events() if e.kind == "query_issued"]
    assert len(lines) == 7 and all("others" not in line for line in lines)
    q = reopened.next_query()
    reopened.close()
    again = Session.open(url, 1)  # replays again, exactly, the pending query included
    assert again.next_query() == q
    again.close()


def test_a_line_that_differs_is_shown_at_its_first_difference(tmp_path: Path) -> None:
    """A line-path query's ``line`` holds every point of the star (up to 4,096): a mismatch
    names the first item that differs, not both lines whole (about 100 kB on 12 features)."""
    from gaitpref.sessions.events import describe_mismatch

    url = f"sqlite:///{tmp_path / 's.db'}"
    s = Session.create(url, parse_config(TEXT), "S01", seed=2)
    _drive(s, 2)
    logged = next(e for e in s.events() if e.kind == "query_issued").payload
    s.close()
    derived = {
        **logged,
        "line": {**logged["line"], "points": [list(p) for p in logged["line"]["points"]]},
    }
    derived["line"]["points"][7][1] += 0.25
    message = describe_mismatch(2, "query_issued", logged, derived)
    was, now = logged["line"]["points"][7], derived["line"]["points"][7]
    assert message == (
        f"event 2 (query_issued):\n  line.points[7]: log has {was!r}, replay gives {now!r}"
    )
    fewer = {**logged, "line": {**logged["line"], "points": logged["line"]["points"][:-1]}}
    n = len(logged["line"]["points"])
    assert f"line.points: log has {n} items, replay gives {n - 1} items" in describe_mismatch(
        2, "query_issued", logged, fewer
    )
    short = {**logged, "actions": [99]}  # a short value is shown whole, as before
    assert f"actions: log has {logged['actions']!r}, replay gives [99]" in describe_mismatch(
        2, "query_issued", logged, short
    )


def test_an_unsafe_flag_without_a_radius_says_close_gaits_may_be_proposed(tmp_path: Path) -> None:
    """`gaitpref session unsafe` on a continuous space whose config has no unsafe_radius: only
    the flagged point is removed, and the CLI says so instead of "its gait will not be proposed
    again" alone."""
    from typer.testing import CliRunner

    from gaitpref.cli import app

    db = str(tmp_path / "lab.db")
    s = Session.create(db, parse_config(TEXT), "S01", seed=11)
    assert s.config.safety.unsafe_radius == 0
    _drive(s, 2)
    s.close()
    result = CliRunner().invoke(
        app, ["session", "unsafe", "1", "2", "--reason", "knee gave way", "--db", db]
    )
    assert result.exit_code == 0, result.output
    assert "gaits however close to it may be" in " ".join(result.output.split())


def test_a_validation_too_early_on_the_line_path_names_no_grid(tmp_path: Path) -> None:
    """The line path has no grid: "the grid has 1" said the points so far."""
    from gaitpref import SessionStateError

    s = Session.create(f"sqlite:///{tmp_path / 's.db'}", parse_config(TEXT), "S01", seed=4)
    _drive(s, 1)
    with pytest.raises(SessionStateError) as err:
        s.start_validation()
    assert "needs at least 3 gaits; the model holds 1" in str(err.value)
    assert "grid" not in str(err.value)
    s.close()


@pytest.mark.parametrize("defaults", [None, "0.11"], ids=["new", "recorded-under-0.11"])
def test_an_excluded_trials_suggestion_steers_no_line(tmp_path: Path, defaults: str | None) -> None:
    """``line_direction = "coactive"``: the trial's "longer step" suggestion steered the next
    line although the trial was excluded (its suggestion out of the model).  A new config's
    line no longer follows it (``line_coactive = "kept"``, defaults 0.12); a session recorded
    under 0.11 goes on following it, and replays as it ran."""
    url = f"sqlite:///{tmp_path / 's.db'}"
    cfg = parse_config(TEXT) if defaults is None else parse_config(TEXT, defaults=defaults)
    assert cfg.line.coactive == ("kept" if defaults is None else "recorded")
    s = Session.create(url, cfg, "S01", seed=11)
    _drive(s, 3)
    q = s.next_query()
    a, p = q.actions[0], q.points[0]
    comps = [(a, b, "first") for b in q.buffer if b != a]
    s.answer(q.id, comps, [(a, "step_length", "+small" if p[0] < 0.13 else "-small")])
    s.exclude(q.trials[0], "stumble")
    after = s.next_query()
    issued = [e for e in s.events() if e.kind == "query_issued"]
    direction = np.abs(issued[-1].payload["line"]["direction"])
    along_step_length = bool(np.array_equal(direction, [1.0, 0.0, 0.0]))
    assert along_step_length == (defaults is not None)
    reopened = Session.open(url, s.id)
    assert reopened.pending == after and reopened.pending.points == after.points
    replayed = [e for e in reopened.events() if e.kind == "query_issued"]
    assert [e.payload for e in replayed] == [e.payload for e in issued]
    np.testing.assert_array_equal(reopened.posterior().mean, s.posterior().mean)
    reopened.close()
    s.close()
