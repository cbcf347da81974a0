"""Counted nouns in what the terminal and the commands print."""

from __future__ import annotations

from gaitpref.wording import plural


def test_one_is_singular_and_every_other_count_plural() -> None:
    assert plural(1, "trial") == "1 trial"  # it said "1 trials"
    assert plural(0, "trial") == "0 trials" and plural(2, "comparison") == "2 comparisons"
    assert plural(1, "query", "queries") == "1 query" and plural(3, "query", "queries") == (
        "3 queries"
    )
