"""The answer form's layout and reading, without a server."""

from __future__ import annotations

import pytest

from gaitpref.config import load_config
from gaitpref.console import views
from gaitpref.console.errors import InputError

SPACE = load_config("exo-2d-length-duration").space


def g(index: int, trial: int) -> views.GaitView:
    return views.gait_view(SPACE, index, trial=trial)


def test_gaits_read_in_physical_units() -> None:
    view = views.gait_view(SPACE, 17, trial=4, gait_id="L0.087-T1.083")
    assert view.name == "trial 4 (L0.087-T1.083)"
    assert view.text == "step length 0.08714 m, step duration 1.083 s"  # (1, 7) of 15 x 10
    assert views.gait_view(SPACE, 17).gait_id == "G17"


def test_one_new_gait_and_one_buffered_use_this_one_and_previous_one() -> None:
    (group,) = views.comparison_groups([g(5, 2)], [g(9, 1)])
    assert group.field == "cmp-5-9"
    assert [c.label for c in group.choices] == ["this one", "previous one", "no preference"]
    assert [c.key for c in group.choices] == ["1", "2", "0"]
    assert group.choices[1].say == "trial 1 (G9) preferred to trial 2 (G5)"


def test_several_gaits_ask_each_pair_once_and_not_a_gait_against_itself() -> None:
    """Trials 4 and 2 ran G9: the pair (5, 9) is asked once, and G9 is not compared with itself
    (it was asked, 'kept, not modelled'; the terminal never asked it); the page says why."""
    actions, buffer = [g(5, 3), g(9, 4)], [g(9, 2)]
    groups = views.comparison_groups(actions, buffer)
    assert [x.field for x in groups] == ["cmp-5-9"]
    assert (groups[0].first.trial, groups[0].second.trial) == (3, 4)
    assert groups[0].choices[0].label == "trial 3 (G5)"
    assert views.comparison_notes(actions, buffer) == [
        "trial 3 (G5) against trial 2 (G9): the same gaits as trial 3 (G5) against trial 4 (G9), "
        "compared once",
        "trial 4 (G9) and trial 2 (G9) are the same gait: nothing to compare",
    ]


def test_a_new_gait_that_is_the_buffered_one_is_not_compared() -> None:
    """n = 1, b = 1 and the new trial runs the buffered gait: nothing is asked (the console
    asked it, kept and not modelled), as the terminal and the simulated users do."""
    assert views.comparison_groups([g(5, 3)], [g(5, 2)]) == []
    assert views.comparison_notes([g(5, 3)], [g(5, 2)]) == [
        "trial 3 (G5) and trial 2 (G5) are the same gait: nothing to compare"
    ]
    assert views.comparison_notes([g(5, 3)], [g(9, 2)]) == []


def test_suggestion_rows_use_the_features_words_and_keys() -> None:
    rows = views.suggestion_groups(SPACE, [g(5, 2)])
    assert [r.feature for r in rows] == ["step_length", "step_duration"]
    assert [c.label for c in rows[1].choices] == [
        "slower", "slightly slower", "no change", "slightly quicker", "quicker",
    ]  # fmt: skip
    assert "".join(c.key for c in rows[0].choices) == "qwert"
    assert "".join(c.key for c in rows[1].choices) == "asdfg"
    assert [c.value for c in rows[0].choices] == ["+big", "+small", "", "-small", "-big"]


def test_reading_an_answer_form() -> None:
    form = {"query_id": "4", "csrf_token": "x", "cmp-5-9": "second", "sug-5-step_length": "+small",
            "sug-5-step_duration": "", "note": "ok"}  # fmt: skip
    comparisons, suggestions = views.read_answer_form(form)
    assert comparisons == [(5, 9, "second")]
    assert suggestions == [(5, "step_length", "+small")]
    assert views.read_int(form, "query_id") == 4


@pytest.mark.parametrize(
    ("form", "field"),
    [
        ({"cmp-5-9": "left"}, "cmp-5-9"),
        ({"sug-5-step_length": "+lots"}, "sug-5-step_length"),
        ({"cmp-5": "first"}, "cmp-5"),
        ({"sug-5-step length": "+big"}, "sug-5-step length"),
    ],
)
def test_bad_answer_fields_are_named(form: dict[str, str], field: str) -> None:
    with pytest.raises(InputError) as err:
        views.read_answer_form(form)
    assert err.value.field == field


@pytest.mark.parametrize("raw", [None, "", "x", "-1", "1.5", "9" * 30])
def test_bad_integers_are_named(raw: str | None) -> None:
    form = {} if raw is None else {"query_id": raw}
    with pytest.raises(InputError) as err:
        views.read_int(form, "query_id")
    assert err.value.field == "query_id"
