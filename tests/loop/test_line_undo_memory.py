"""What a line-path answer keeps for undo (``loop/cospar.py``, ``_light``): the posterior before
it over a fresh engine, without the table's ``A x A`` matrices that the engine of each table
caches (kept by every answer they grew with the square of the table), and undo then proposes
exactly what a loop that never undid does."""

from __future__ import annotations

import numpy as np

from gaitpref import Feature, Space, SquaredExponential
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import LineSettings
from gaitpref.model.engines import PointEngine

KERNEL = SquaredExponential(0.4, 1.0, 1e-6)
DOMAIN = Space(
    [
        Feature.interval("x", 0.0, 1.0, coactive=(0.05, 0.1)),
        Feature.interval("y", 0.0, 1.0, coactive=(0.05, 0.1)),
        Feature.interval("z", -1.0, 1.0, coactive=(0.05, 0.1)),
    ]
)


def _loop() -> LineCoSpar:
    return LineCoSpar(DOMAIN, KERNEL, 0.05, n=1, buffer=1, seed=3, line=LineSettings(points=12))


def _answer(loop: LineCoSpar, k: int) -> None:
    q = loop.ask()
    a = q.actions[0]
    comps = [(a, b, "first" if k % 3 else "second") for b in q.buffer if b != a]
    loop.tell(q, comps, [(a, "xyz"[k % 3], "+small")])


def _cached_bytes(engine: object) -> int:
    """The arrays an engine holds besides its points: its caches, and the engine it started
    from (with its own)."""
    if not isinstance(engine, PointEngine):
        return 0
    held = [engine.__dict__.get(k) for k in ("plain", "root_t")] + [engine._square]
    size = sum(a.nbytes for a in held if isinstance(a, np.ndarray))
    return size + _cached_bytes(engine._base)


def test_answers_keep_no_table_sized_matrices() -> None:
    loop = _loop()
    for k in range(12):
        _answer(loop, k)
    assert len(loop.space) > 12  # the suggestions' points joined the table
    assert [_cached_bytes(a.posterior_before.engine) for a in loop.answers] == [0] * 12


def test_undo_then_the_same_answer_proposes_what_a_loop_that_never_undid_does() -> None:
    undone, straight = _loop(), _loop()
    for k in range(9):
        _answer(undone, k)
        _answer(straight, k)
    for _ in range(3):
        undone.undo()
    for k in range(6, 9):
        _answer(undone, k)
    for _ in range(3):
        q, r = undone.ask(), straight.ask()
        assert q == r and q.points == r.points
        np.testing.assert_array_equal(undone.space.points, straight.space.points)
        undone.tell(q, [(q.actions[0], q.buffer[0], "first")])
        straight.tell(r, [(r.actions[0], r.buffer[0], "first")])
        np.testing.assert_array_equal(undone.posterior.mean, straight.posterior.mean)
