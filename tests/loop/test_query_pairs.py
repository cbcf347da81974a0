"""Which pairs of a query's members the subject is asked to compare: one rule
(``gaitpref.feedback.comparison_pairs``, ``Query.pairs``, ``SessionQuery.pairs``) for the
terminal, the console and the simulated users.  Each of them had its own: the console asked a
gait against itself, the terminal and the simulated users did not."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import SessionQuery
from gaitpref.feedback import QueryPair, compared_actions, comparison_pairs
from gaitpref.loop import Query
from gaitpref.simulate.users import query_pairs


def _old_simulated_pairs(
    actions: tuple[int, ...], buffer: tuple[int, ...]
) -> list[tuple[int, int]]:
    """The simulated users' rule before it was shared (the paper's runs were made with it)."""
    out: list[tuple[int, int]] = []
    seen: set[tuple[int, int]] = set()
    for i in actions:
        for j in actions + buffer:
            key = (min(i, j), max(i, j))
            if key in seen or i == j:
                continue
            seen.add(key)
            out.append((i, j))
    return out


def test_the_papers_one_new_gait_and_one_buffered_is_one_pair() -> None:
    assert comparison_pairs([5], [9]) == (QueryPair(0, 1),)
    assert compared_actions([5], [9]) == ((5, 9),)
    assert comparison_pairs([5], []) == ()  # the first query: nothing to compare with


def test_a_new_gait_that_is_the_buffered_one_is_not_asked() -> None:
    (pair,) = comparison_pairs([5], [5])
    assert pair.same_gait and not pair.asked and pair.repeats is None
    assert compared_actions([5], [5]) == ()


def test_several_new_gaits_among_themselves_then_with_the_buffer() -> None:
    """n = 3, b = 1, distinct gaits: the paper's n (n - 1) / 2 + n b = 6 pairs, each executed
    gait against every member after it."""
    pairs = comparison_pairs([1, 2, 3], [4])
    assert [(p.first, p.second) for p in pairs] == [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    assert all(p.asked for p in pairs)
    assert compared_actions([1, 2, 3], [4]) == ((1, 2), (1, 3), (1, 4), (2, 3), (2, 4), (3, 4))


def test_a_buffer_of_two_asks_the_new_gait_against_each() -> None:
    assert compared_actions([7], [3, 4]) == ((7, 3), (7, 4))
    assert comparison_pairs([7], [3, 4]) == (QueryPair(0, 1), QueryPair(0, 2))


def test_a_buffer_holding_one_gait_twice_asks_the_pair_once() -> None:
    """b = 2, buffered trials on one gait: the second pair repeats the first (the loop refuses
    a pair compared twice)."""
    first, second = comparison_pairs([7], [3, 3])
    assert first.asked
    assert second == QueryPair(0, 2, repeats=(0, 1)) and not second.asked
    assert compared_actions([7], [3, 3]) == ((7, 3),)


def test_a_gait_proposed_twice_is_not_compared_with_itself_and_its_pairs_are_asked_once() -> None:
    """n = 3, b = 1, the first two trials on one gait."""
    pairs = comparison_pairs([5, 5, 7], [9])
    assert pairs == (
        QueryPair(0, 1, same_gait=True),
        QueryPair(0, 2),
        QueryPair(0, 3),
        QueryPair(1, 2, repeats=(0, 2)),
        QueryPair(1, 3, repeats=(0, 3)),
        QueryPair(2, 3),
    )
    assert compared_actions([5, 5, 7], [9]) == ((5, 7), (5, 9), (7, 9))


def test_an_executed_gait_that_is_also_buffered() -> None:
    """n = 2, b = 1: trial 2 reruns the buffered gait; trial 1's gait is compared with it once."""
    assert comparison_pairs([4, 9], [9]) == (
        QueryPair(0, 1),
        QueryPair(0, 2, repeats=(0, 1)),
        QueryPair(1, 2, same_gait=True),
    )


def test_the_loop_and_the_session_query_give_the_rule() -> None:
    q = Query(3, (5, 5, 7), (9,))
    s = SessionQuery(4, 3, (5, 5, 7), (9,), (6, 7, 8), (5,))
    assert q.pairs == s.pairs == comparison_pairs([5, 5, 7], [9])
    assert q.compared == s.compared == ((5, 7), (5, 9), (7, 9))
    assert query_pairs(q) == list(q.compared)  # the simulated users' pairs


@pytest.mark.parametrize("seed", range(3))
def test_the_simulated_users_pairs_are_unchanged(seed: int) -> None:
    """The shared rule is the simulated users' old one, pair for pair and in order (their
    noisy answers draw from the generator in this order: recorded runs replay the same)."""
    rng = np.random.default_rng(seed)
    for _ in range(300):
        n, b = int(rng.integers(1, 5)), int(rng.integers(0, 4))
        actions = tuple(int(a) for a in rng.integers(0, 4, size=n))
        buffer = tuple(int(a) for a in rng.integers(0, 4, size=b))
        assert query_pairs(Query(1, actions, buffer)) == _old_simulated_pairs(actions, buffer)


def test_the_asked_pairs_are_each_pair_of_distinct_gaits_once() -> None:
    """Every pair of distinct gaits with one executed is asked exactly once."""
    rng = np.random.default_rng(0)
    for _ in range(200):
        actions = tuple(int(a) for a in rng.integers(0, 5, size=int(rng.integers(1, 5))))
        buffer = tuple(int(a) for a in rng.integers(0, 5, size=int(rng.integers(0, 3))))
        asked = [frozenset(p) for p in compared_actions(actions, buffer)]
        want = {frozenset((a, m)) for a in actions for m in actions + buffer if a != m}
        assert len(asked) == len(set(asked)) and set(asked) == want
