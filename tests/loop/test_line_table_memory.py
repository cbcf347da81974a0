"""What the line path keeps of its table per query (``loop/line.py``, ``pointset.py``).

Every query keeps the table right after its ask and the table before it (undo and withdrawals
go back to them).  Each was a copy of every row and of the index of rows: 500 queries on 12
features with a suggestion each held 47 MB of rows and 20 MB of indices.  The tables of a
lineage (each the one before and more) now share one buffer and one index, and the loop
proposes exactly what it did.
"""

from __future__ import annotations

import numpy as np
import pytest

import gaitpref.pointset as pointset_module
from gaitpref import Feature, Space, SquaredExponential
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import LineSettings
from gaitpref.pointset import PointSet, empty_points

DOMAIN = Space([Feature.interval(f"x{k}", 0.0, 1.0, coactive=(0.05, 0.1)) for k in range(6)])
KERNEL = SquaredExponential(0.4, 1.0, 1e-6)


def _run(trials: int) -> tuple[LineCoSpar, list[object]]:
    """A loop with suggestions, undos, an avoided (withdrawn) query and an exclusion; what it
    proposed, and its posterior means, in order."""
    loop = LineCoSpar(
        DOMAIN, KERNEL, 0.05, n=1, buffer=1, seed=5, line=LineSettings(12, "coactive", 2)
    )
    seen: list[object] = []
    for k in range(trials):
        q = loop.ask()
        a = q.actions[0]
        seen.append((q, q.points, q.line.to_json() if q.line else None))
        suggestion = [(a, f"x{k % 6}", "+small" if k % 4 else "-big")] if k % 3 else []
        loop.tell(
            q, [(a, b, "first" if k % 2 else "second") for b in q.buffer if b != a], suggestion
        )
        if k % 9 == 8:
            loop.undo()
            loop.undo()
        if k % 10 == 5:
            loop.avoid(loop.ask().actions[0], 0.05)  # withdraws the pending query
        if k == 12:
            loop.exclude({loop.answers[3].query.id: [0]})
        seen.append(np.asarray(loop.posterior.mean).tobytes())
    seen.append(loop.space.points.tobytes())
    return loop, seen


def _base(points: np.ndarray) -> np.ndarray:
    return points if points.base is None else points.base


def test_the_loop_proposes_what_it_did_with_a_copy_per_table(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    shared_loop, shared = _run(40)
    copied_extended = PointSet.extended

    def copying(self: PointSet, points: object, *, share: bool = False) -> object:
        return copied_extended(self, points)  # type: ignore[arg-type]

    monkeypatch.setattr(pointset_module.PointSet, "extended", copying)
    copied_loop, copied = _run(40)
    assert len(shared) == len(copied)
    for ours, theirs in zip(shared, copied, strict=True):
        assert ours == theirs
    tables = [*copied_loop._tables.values(), *copied_loop._tables_before.values()]
    assert all(t.points.base is None for t in tables if len(t))  # a copy each, as before
    assert len(shared_loop.space) == len(copied_loop.space)


def test_the_tables_kept_share_their_rows() -> None:
    loop, _ = _run(60)
    live = [a.query.id for a in loop.answers]
    tables = [loop._tables[q] for q in live] + [loop._tables_before[q] for q in live]
    final = loop.space
    assert len(final) > 60  # suggestions joined the table
    for table in tables:  # each a prefix of the table now, its rows a view of a shared buffer
        np.testing.assert_array_equal(table.points, final.points[: len(table)])
    buffers = {id(_base(t.points)): _base(t.points).nbytes for t in tables if len(t)}
    assert len(buffers) <= 12  # a few buffers (doubling, and a lineage per undo), not 120
    copies = sum(t.points.nbytes for t in tables)  # what a copy per table held
    assert 4 * sum(buffers.values()) < copies
    assert len({id(t._rows) for t in tables if len(t)}) <= len(buffers)  # type: ignore[attr-defined]


def test_a_shared_extension_is_the_same_set_and_leaves_earlier_sets_as_they_were() -> None:
    rng = np.random.default_rng(0)
    a = empty_points(DOMAIN)
    chain = [a]
    for _ in range(30):
        pts = rng.uniform(size=(3, 6))
        pts[1] = chain[-1].points[0] if len(chain[-1]) else pts[1]  # one already present
        shared, ids = chain[-1].extended(pts, share=True)
        copied, ids_copied = chain[-1].extended(pts)
        assert shared == copied and np.array_equal(ids, ids_copied)
        chain.append(shared)
    middle = chain[10]
    before = middle.points.copy()
    later = chain[-1].points.copy()
    branch, _ = middle.extended(rng.uniform(size=(4, 6)), share=True)  # a new lineage
    assert not np.shares_memory(branch.points, chain[-1].points)
    np.testing.assert_array_equal(middle.points, before)
    np.testing.assert_array_equal(chain[-1].points, later)
    for k, row in enumerate(chain[-1].points):
        assert chain[-1].find(row) == k
        assert middle.find(row) == (k if k < len(middle) else None)
        assert branch.find(row) == (k if k < len(middle) else None)
    for k, row in enumerate(branch.points):
        assert branch.find(row) == k
    grown, _ = branch.extended(rng.uniform(size=(2, 6)), share=True)  # the branch's lineage
    assert np.shares_memory(grown.points, branch.points)
    assert not middle.points.flags.writeable and not grown.points.flags.writeable
    # an unshared extension of a set inside a lineage sees only that set's rows
    tried, ids = middle.extended(chain[-1].points[len(middle) : len(middle) + 2])
    assert list(ids) == [len(middle), len(middle) + 1] and len(tried) == len(middle) + 2


def test_a_shared_extension_refuses_a_point_outside_the_box_as_before() -> None:
    table, _ = empty_points(DOMAIN).extended(np.full((2, 6), 0.5), share=True)
    bad = np.full((1, 6), 0.5)
    bad[0, 2] = 1.5
    with pytest.raises(ValueError, match=r"x2: points must lie in 0 \.\. 1"):
        table.extended(bad, share=True)
    bad[0, 2] = np.nan
    with pytest.raises(ValueError, match="x2: points must be numbers"):
        table.extended(bad, share=True)
