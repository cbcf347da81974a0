"""CoSpar's constructor names a bad argument (before, some failed at the first ask or deep in
NumPy, and bools passed as numbers)."""

from __future__ import annotations

from typing import Any, cast

import numpy as np
import pytest

from gaitpref import CoSpar, Feature, Learning, Space, SquaredExponential
from gaitpref.loop.line import LineCoSpar

SPACE = Space([Feature.linspace("a", 0, 1, 5), Feature.linspace("b", 0, 1, 4)])
KERNEL = SquaredExponential(0.3, 1.0, 1e-6)


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"n": True}, ValueError, "n .actions per query. must be an integer >= 1, got True"),
        ({"buffer": True}, ValueError, "buffer must be an integer >= 0, got True"),
        # a config's bounds (MAX_QUERY): a buffer of 10**9 kept every trial's actions
        ({"buffer": 10**9}, ValueError, "buffer must be at most 64, got 1000000000"),
        ({"buffer": 65}, ValueError, "buffer must be at most 64, got 65"),
        ({"n": 65}, ValueError, r"n \(actions per query\) must be at most 64, got 65"),
        ({"coactive_weight": True}, ValueError, "coactive_weight must be positive"),
        ({"coactive_weight": "1"}, ValueError, "coactive_weight must be positive"),
        # 0.1 / 1e-300 squared to inf: every suggestion a flat term, silently
        (
            {"coactive_weight": 1e-300},
            ValueError,
            r"a suggestion's noise, noise / coactive_weight = 0.1 / 1e-300, must be positive "
            "with a finite square",
        ),
        ({"seed": None}, ValueError, "seed must be an integer >= 0 or a numpy.random.Generator"),
        ({"seed": -1}, ValueError, "seed must be an integer >= 0"),
        ({"seed": 1.5}, ValueError, "seed must be an integer >= 0"),
        ({"seed": True}, ValueError, "seed must be an integer >= 0"),
        ({"strategy": "eubo"}, TypeError, "strategy must be a Strategy"),
        ({"learning": "evidence"}, TypeError, "learning must be a Learning or None"),
        ({"ordinal": 3}, TypeError, "ordinal must be a Ordinal or None"),
        ({"safety": {"avoid": 1}}, TypeError, "safety must be a Safety or None"),
    ],
)
def test_bad_arguments_are_named(kwargs: dict[str, Any], error: type, message: str) -> None:
    with pytest.raises(error, match=message):
        CoSpar(SPACE, KERNEL, 0.1, **kwargs)


def test_the_line_path_checks_the_same() -> None:
    with pytest.raises(ValueError, match="seed must be an integer >= 0"):
        LineCoSpar(SPACE, KERNEL, 0.1, seed=None)
    with pytest.raises(ValueError, match="buffer must be at most 64, got 65"):
        LineCoSpar(SPACE, KERNEL, 0.1, buffer=65)
    assert LineCoSpar(SPACE, KERNEL, 0.1, n=2, buffer=64).buffer_size == 64


def test_numpy_integers_are_integers() -> None:
    # np.int64(2) was refused as "must be an integer"
    n, buffer, seed = cast(Any, np.int64(2)), cast(Any, np.int32(1)), cast(Any, np.uint32(3))
    loop = CoSpar(SPACE, KERNEL, 0.1, n=n, buffer=buffer, seed=seed)
    assert (loop.n, loop.buffer_size) == (2, 1)
    assert type(loop.n) is int and type(loop.buffer_size) is int
    same = CoSpar(SPACE, KERNEL, 0.1, n=2, buffer=1, seed=3, learning=Learning())
    assert loop.ask().actions == same.ask().actions


def test_flags_and_safety_take_numbers() -> None:
    from gaitpref.loop.safety import Safety

    loop = CoSpar(SPACE, KERNEL, 0.1)
    # True avoided everything within radius 1 (the whole grid)
    for radius in (True, "0.1", np.nan):
        with pytest.raises(ValueError, match="radius must be in"):
            loop.avoid(0, radius)  # type: ignore[arg-type]
    assert not loop.avoided
    with pytest.raises(TypeError, match="action index must be an integer, got 'x'"):
        loop.unflag_unsafe("x")  # type: ignore[arg-type]
    for key in ("unsafe_radius", "explore", "lam"):
        with pytest.raises(ValueError, match="must be"):
            Safety(**{key: True})  # type: ignore[arg-type]
        with pytest.raises(ValueError, match="must be"):
            Safety(**{key: "0.5"})  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"ties": "model", "tie_band": True}, "tie_band must be positive, got True"),
        ({"ties": "model", "tie_band": "0.1"}, "tie_band must be positive"),
        (
            {"fit": "evidence", "hyper": "average", "hypotheses": (True, 2.0)},
            "hypotheses must be positive numbers",
        ),
    ],
)
def test_learning_numbers_are_numbers(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Learning(**kwargs)


def test_the_parts_are_checked_by_type() -> None:
    from gaitpref.loop.lines import LineSettings
    from gaitpref.loop.safety import Safety

    with pytest.raises(TypeError, match=r"space must be a gaitpref\.Space"):
        CoSpar([1], KERNEL, 0.1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"kernel must be a gaitpref\.SquaredExponential"):
        CoSpar(SPACE, "k", 0.1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"domain must be a gaitpref\.Space"):
        LineCoSpar([1], KERNEL, 0.1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="line must be a LineSettings or None"):
        LineCoSpar(SPACE, KERNEL, 0.1, line=10)  # type: ignore[arg-type]
    assert LineCoSpar(SPACE, KERNEL, 0.1, line=LineSettings(10)).line_settings.points == 10
    with pytest.raises(ValueError, match="every feature has a single value"):
        LineCoSpar(Space([Feature("a", [0.5])]), KERNEL, 0.1)  # failed at the first ask
    with pytest.raises(IndexError, match=r"safety.start\[1\]: action index 99 is off the grid"):
        CoSpar(SPACE, KERNEL, 0.1, safety=Safety(start=(3, 99)))
    # NumPy integers were "not action indices"; a list made the settings unhashable
    safety = Safety(avoid=np.int64(0), start=[np.int64(3), 5])  # type: ignore[arg-type]
    assert safety.start == (3, 5) and type(safety.start[0]) is int and hash(safety)
    assert CoSpar(SPACE, KERNEL, 0.1, safety=safety).ask().actions == (3,)


def test_learning_keeps_its_hypotheses_as_a_tuple_and_checks_its_prior() -> None:
    # a list made Learning unhashable; 5 was a TypeError; prior="x" an AttributeError in CoSpar
    learning = Learning(fit="evidence", hyper="average", hypotheses=[0.5, 1])  # type: ignore[arg-type]
    assert learning.hypotheses == (0.5, 1.0) and hash(learning)
    assert Learning(hypotheses=np.array([0.5, 2.0])).hypotheses == (0.5, 2.0)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="hypotheses must be positive numbers, got 5"):
        Learning(hypotheses=5)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="prior must be a HyperPrior or None"):
        Learning(prior="x")  # type: ignore[arg-type]


def test_learning_hypotheses_have_the_configs_bounds() -> None:
    # any count and factor was taken: a million hypotheses made every tell a million fits
    many = tuple(1.0 + k / 100 for k in range(16))
    with pytest.raises(ValueError, match=r"hypotheses must be 1 to 15 lengthscale factors in "):
        Learning(fit="evidence", hyper="average", hypotheses=many)
    for factor in (0.01, 1e-9, 100.5, 1e300):
        with pytest.raises(ValueError, match=r"factors in \(0.01, 100\], got 2"):
            Learning(hypotheses=(1.0, factor))
    assert Learning(hypotheses=(0.0101, 100.0)).hypotheses == (0.0101, 100.0)
    assert len(Learning(hypotheses=many[:15]).hypotheses) == 15


def test_avoid_all_checks_every_action_first() -> None:
    loop = CoSpar(SPACE, KERNEL, 0.1)
    query = loop.ask()
    # the first was avoided (and the pending query withdrawn) before -1 raised
    with pytest.raises(IndexError, match="action index -1 is off the grid"):
        loop.avoid_all([query.actions[0], -1], 0.1)
    assert not loop.avoided and loop.pending is query
    line = LineCoSpar(SPACE, KERNEL, 0.1)
    line.ask()
    with pytest.raises(ValueError, match="radius must be in"):
        line.avoid(0, True)


def test_numpy_counts_in_line_and_learning_settings() -> None:
    from gaitpref.loop.lines import LineSettings

    # refused before: "a line needs at least 2 points, got points = np.int64(10)"
    line = LineSettings(np.int64(10), lines=np.int32(2))  # type: ignore[arg-type]
    assert (line.points, line.lines) == (10, 2) and type(line.points) is int
    learning = Learning(refit_every=np.int64(5))  # type: ignore[arg-type]
    assert learning.refit_every == 5 and type(learning.refit_every) is int
    with pytest.raises(ValueError, match="a line needs at least 2 points"):
        LineSettings(True)


def test_n_is_at_most_the_grid() -> None:
    with pytest.raises(ValueError, match="must be at most the grid's size, 20, got 21"):
        CoSpar(SPACE, KERNEL, 0.1, n=21)  # every ask failed before
    assert len(CoSpar(SPACE, KERNEL, 0.1, n=20).ask().actions) == 20


def test_iterators_are_read_once() -> None:
    loop = CoSpar(SPACE, KERNEL, 0.1, n=2)
    query = loop.ask()
    # the check read the iterator and nothing was avoided
    assert loop.avoid_all(cast(Any, iter(query.actions)), 0.0)
    assert set(loop.avoided) == set(query.actions)
    query = loop.ask()
    a, b = query.actions
    assert a != b  # this seed's second query
    loop.tell(query, [(a, b, "first")])
    loop.exclude({query.id: cast(Any, iter([0]))})
    assert loop.excluded == {query.id: frozenset({0})}


def test_safety_start_gaits_are_read_once_and_named() -> None:
    from gaitpref.loop import Safety

    # a generator was emptied by the check: the loop ran with no start gaits, silently
    safety = Safety(start=cast(Any, (a for a in [3, 7])))
    assert safety.start == (3, 7)
    assert CoSpar(SPACE, KERNEL, 0.1, seed=0, safety=safety).ask().actions == (3,)
    assert Safety(start=cast(Any, np.array([4, 1]))).start == (4, 1)
    for bad in (5, "ab", [1.0], [True]):  # 5 was "'int' object is not iterable"
        with pytest.raises(ValueError, match="start must hold action indices >= 0"):
            Safety(start=cast(Any, bad))


def test_tell_names_an_argument_that_is_not_a_list() -> None:
    from gaitpref import Comparison, FeedbackError, Suggestion

    loop = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=1)
    query = loop.ask()
    a, b = query.actions
    # each was a TypeError from unpacking: "Value after * must be an iterable, not Comparison"
    cases: list[tuple[dict[str, Any], str]] = [
        ({"answers": Comparison(a, b, "first")}, "answers: .* got one Comparison"),
        ({"suggestions": Suggestion(a, "a", "+big")}, "suggestions: .* got one Suggestion"),
        ({"comparisons": Comparison(a, b, "first")}, "comparisons: .* got one Comparison"),
        ({"answers": None}, "answers: expected a list of feedback records, got None"),
        ({"answers": "abc"}, "answers: expected a list of feedback records, got 'abc'"),
    ]
    for kwargs, message in cases:
        with pytest.raises(FeedbackError, match=message):
            loop.tell(query, **kwargs)
    assert loop.pending is query and not loop.answers
    assert loop.tell(query, iter([(a, b, "first")])).comparisons == (Comparison(a, b, "first"),)


class _Fixed:
    """A strategy written outside the package that proposes what it is told to."""

    def __init__(self, picks: tuple[object, ...]) -> None:
        self.picks = picks
        self.name = "fixed"

    def propose(self, context: Any) -> tuple[object, ...]:
        return self.picks


def test_a_strategy_is_held_to_its_protocol() -> None:
    # each was run as proposed: a query of two actions for n = 1, a gait of index -1 (the last),
    # a gait near an unsafe flag
    for picks, message in (
        ((3, 4), "proposed 2 actions; the query asks 1"),
        ((-1,), "proposed -1, not an action"),
        ((1.0,), "proposed 1.0, not an action"),
    ):
        loop = CoSpar(SPACE, KERNEL, 0.1, strategy=_Fixed(picks))  # type: ignore[arg-type]
        with pytest.raises(ValueError, match=message):
            loop.ask()
        assert loop.pending is None
    loop = CoSpar(SPACE, KERNEL, 0.1, strategy=_Fixed((5,)))  # type: ignore[arg-type]
    loop.flag_unsafe(5)
    with pytest.raises(ValueError, match="proposed action 5, which may not be proposed"):
        loop.ask()
    assert CoSpar(SPACE, KERNEL, 0.1, strategy=_Fixed((np.int64(7),))).ask().actions == (7,)  # type: ignore[arg-type]


def test_a_warm_start_is_a_warm_start() -> None:
    loop = CoSpar(SPACE, KERNEL, 0.1)
    with pytest.raises(TypeError, match="warm must be a WarmStart"):  # an AttributeError before
        loop.warm_start({"rho": 0.5})  # type: ignore[arg-type]
    assert loop.warm is None
