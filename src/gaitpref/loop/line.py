"""The line path: CoSpar whose every query is chosen along a one-dimensional subspace.

LineCoSpar (Tucker, Cheng et al., IROS 2020, Algorithm 1) for spaces that no grid holds:
continuous features, or a grid too large to enumerate (issue 13).  Each ask draws a line through
the current best point (the posterior mean's argmax over the points so far; a random point
first) with the direction rule of :class:`~gaitpref.loop.lines.LineSettings`, discretised into
a fixed number of points (``loop/lines.py``).  The posterior lives on a
:class:`~gaitpref.pointset.PointSet`: the *table* of points executed or suggested so far, plus
the current line while a query is chosen.  Since the Laplace fit depends only on the visited
points, the posterior over the table and the line is the same Gaussian as the full model's
restricted to those points (``tests/loop/test_line.py`` checks it against the full grid).  The
query strategy (self-sparring, EUBO, gated EUBO, information gain) runs unchanged on that
posterior with ``allowed`` set to the line's points, so it chooses along the line.  When no
point of the line may be proposed (every one avoided, near a gait flagged unsafe, or in the
region of avoidance) the ask draws another line, up to ``LINE_DRAWS`` (``loop/lines.py``), and
raises :class:`~gaitpref.errors.NoSafeGaitError` only when none of them has such a point
(:class:`~gaitpref.errors.ShortLinesError` when some had, but each such line held fewer than the
query's ``n`` points with the table).

Actions are rows of the table: they keep their index for the whole session, and a point seen
twice (a line through a visited point, a coactive suggestion landing on one) is one action.
A coactive suggestion adds the point it names to the table before the answer is fitted.  Every
line takes a seed from the loop's generator; the query carries the line it was chosen along
(seed, origin, direction, points), which a session logs and checks on replay (the lines drawn
before it follow from the same generator).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Hashable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np
from numpy.typing import NDArray

from gaitpref.checks import is_count
from gaitpref.errors import NoSafeGaitError, QueryError, ShortLinesError
from gaitpref.feedback import FeedbackKind, Suggestion
from gaitpref.loop.cospar import Answer, CoSpar, Query, check_radius, proposed
from gaitpref.loop.lines import (
    LINE_DRAWS,
    Line,
    LineSettings,
    draw_line,
    normalised,
    redraw_rule,
)
from gaitpref.loop.safety import Safety
from gaitpref.loop.warm import WarmStart
from gaitpref.model.engines import PointEngine
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.posterior import Posterior
from gaitpref.model.threads import one_blas_thread
from gaitpref.pointset import PointSet, empty_points
from gaitpref.space import FloatArray, Space
from gaitpref.strategies.base import AskContext


def on_points(posterior: Posterior, space: PointSet) -> Posterior:
    """The same posterior read over ``space``, whose first rows are ``posterior``'s points (the
    fit on the visited points is unchanged; only where it is read changes)."""
    if posterior.space is space:
        return posterior
    base = posterior.engine if isinstance(posterior.engine, PointEngine) else None
    engine = PointEngine(space, posterior.kernel, base)
    return dataclasses.replace(posterior, space=space, engine=engine)


class LineCoSpar(CoSpar):
    """CoSpar on the line path over ``domain`` (any :class:`Space`: continuous features, or a
    grid too large to enumerate); ``line`` sets the points per line and the direction rule.
    The other arguments are :class:`CoSpar`'s."""

    space: PointSet

    def __init__(
        self,
        domain: Space,
        kernel: SquaredExponential,
        noise: float,
        *,
        line: LineSettings | None = None,
        **settings: Any,
    ) -> None:
        if isinstance(domain, PointSet):
            raise TypeError("the line path takes the features' space, not a point set")
        if not isinstance(domain, Space):
            raise TypeError(f"domain must be a gaitpref.Space, got {domain!r}")
        if line is not None and not isinstance(line, LineSettings):
            raise TypeError(f"line must be a LineSettings or None, got {line!r}")
        if all(f.span == 0 for f in domain.features):  # failed at the first ask before
            raise ValueError(
                "every feature has a single value: there is no line to draw (give some "
                "feature a range)"
            )
        n = settings.get("n", 1)
        if domain.grid_size is not None and is_count(n) and n > domain.grid_size:
            raise ValueError(
                f"n (actions per query) must be at most the grid's size, {domain.grid_size}, "
                f"got {n}"
            )
        safety = settings.get("safety")
        if isinstance(safety, Safety) and safety.start:
            raise ValueError("the line path takes no start gaits (safety.start): a grid does")
        super().__init__(empty_points(domain), kernel, noise, **settings)
        self.domain = domain
        self.line_settings = LineSettings() if line is None else line
        self._tables: dict[int, PointSet] = {}  # query id -> the table right after its ask
        self._table_before_pending: PointSet = self.space
        self._tables_before: dict[int, PointSet] = {}  # query id -> the table before its ask
        self._avoided_points: list[tuple[FloatArray, float]] = []  # (point, radius): avoid

    # -- the table ---------------------------------------------------------------------------
    def _use_table(self, table: PointSet) -> None:
        if table is not self.space:
            self.space = table
            self.gp = self._gp(self.hyper)
        self.posterior = on_points(self.posterior, table)
        engine = self.posterior.engine
        if (
            "engine" not in self.gp.__dict__
            and isinstance(engine, PointEngine)
            and engine.space is table
            and engine.kernel == self.gp.kernel
        ):  # the model's fits read the K its posterior's engine has from the table before
            self.gp.engine = engine

    def best_point(self) -> FloatArray | None:
        """The posterior mean's argmax over the table (None before the first query)."""
        if len(self.space) == 0:
            return None
        out: FloatArray = self.space.points[self.posterior.argmax].copy()
        return out

    def _towards(self) -> FloatArray | None:
        """The last answer's coactive direction (normalised), if it had suggestions: those the
        model keeps (``line_settings.coactive = "kept"``; none when its trial was excluded, and
        the direction is random), or every one recorded (``"recorded"``, as before defaults
        0.12: an excluded trial's too)."""
        if not self.answers:
            return None
        last = self.answers[-1]
        kept = self._kept(last) if self.line_settings.coactive == "kept" else last.preferences
        moves = [
            self.space.points[p.winner] - self.space.points[p.loser]
            for p in kept
            if p.source == "coactive"
        ]
        if not moves:
            return None
        return normalised(self.domain, np.sum(moves, axis=0))

    # -- ask / tell --------------------------------------------------------------------------
    def ask(self) -> Query:
        """The next query, chosen along a fresh line through the current best point; while every
        point of the lines drawn is excluded (avoided, near a gait flagged unsafe, in the region
        of avoidance), along another, at most :data:`~gaitpref.loop.lines.LINE_DRAWS` in all
        (:func:`~gaitpref.loop.lines.redraw_rule`), each from its own seed of the generator."""
        if self.pending is not None:
            return self.pending
        state = self.rng.bit_generator.state
        origin, towards = self.best_point(), self._towards()
        short = False  # some line drawn had a point to propose but fewer than n points
        with one_blas_thread():
            for draw in range(LINE_DRAWS):
                seed = int(self.rng.integers(2**63 - 1))
                rule, through_best = redraw_rule(self.line_settings, draw)
                start = origin if through_best else None  # None: a random point of the seed's
                line = draw_line(self.domain, rule, seed, start, towards if draw == 0 else None)
                space, allowed = self._on_line(line)
                # a line snapped to few grid values (through a corner, say) may hold fewer
                # points with the table than the query's n: another is drawn (the strategy's
                # context refused it, and the ask failed, before)
                short |= bool(allowed.any()) and len(space) < self.n
                if allowed.any() and len(space) >= self.n:
                    break
            else:  # nothing drawn, nothing logged: the generator goes back as it was
                self.rng.bit_generator.state = state
                if short:
                    raise ShortLinesError(
                        f"none of the {LINE_DRAWS} lines tried holds n = {self.n} points with the "
                        "gaits so far: lower n, or give the discrete features more values"
                    )
                through = "random points" if origin is None else "the best point, then random ones"
                tried = f"{LINE_DRAWS} line" + ("s" if LINE_DRAWS != 1 else "")
                raise NoSafeGaitError(
                    f"no gait may be proposed on any of the {tried} tried (through {through}): "
                    "every point of each is in the region of avoidance, near a gait "
                    f"flagged unsafe ({len(self.unsafe)} flagged) or avoided "
                    f"({len(self._avoided_points)}, e.g. gaits that cannot be made); nothing was "
                    "proposed"
                )
            posterior = on_points(self.posterior, space)

            def rescaled(factor: float) -> Posterior:  # the answers refitted, read on the line
                return on_points(self._rescaled(factor), space)

            context = AskContext(
                posterior, self.n, self._buffer, len(self.executed), self.rng, allowed, rescaled
            )
            chosen = list(proposed(self.strategy, context))
        self._rng_before_pending = state
        self._table_before_pending = self.space
        table, actions = self.space.extended(space.points[chosen], share=True)
        self._use_table(table)
        points = tuple(tuple(row) for row in table.points[actions].tolist())
        query = Query(self._next_id, tuple(int(a) for a in actions), self._buffer, points, line)
        self._tables[query.id] = table
        self._tables_before[query.id] = self._table_before_pending
        self.pending = query
        self._next_id += 1
        return query

    def _on_line(self, line: Line) -> tuple[PointSet, NDArray[np.bool_]]:
        """The table extended by ``line``'s points, and which of them may be proposed: on the
        line, not avoided, and allowed by the safety rules (``loop/safety.py``)."""
        space, line_ids = self.space.extended(line.points)
        allowed = np.zeros(len(space), dtype=bool)
        allowed[line_ids] = True
        if self._avoided_points:
            allowed &= ~self._avoided_on(space)
        posterior = on_points(self.posterior, space)
        safe = self.safety.allowed(posterior, self.gp.ordinal, self.unsafe, allowed)
        if safe is not None:
            allowed &= safe
        return space, allowed

    @contextmanager
    def _all_or_nothing(self) -> Iterator[None]:
        """A :meth:`tell` that raises leaves the table (and so the model) as it was: the points
        its coactive suggestions added go again."""
        saved = (self.space, self.gp, self.posterior)
        try:
            yield
        except BaseException:
            self.space, self.gp, self.posterior = saved
            raise

    def _parse(
        self, query: Query, answers: Iterable[object], suggestions: Iterable[object]
    ) -> list[tuple[FeedbackKind[Any], Hashable]]:
        records = super()._parse(query, answers, suggestions)
        targets = [
            self.space.move_target(r.action, r.feature, r.move)
            for _, r in records
            if isinstance(r, Suggestion)
        ]
        found = [t for t in targets if t is not None]
        if found:
            self._use_table(self.space.extended(np.array(found), share=True)[0])
        return records

    def _take_back(self) -> Answer:
        """As :meth:`CoSpar.undo`; the table goes back to right after the query's ask (and to
        before it, should the query be withdrawn).  Refused while an unsafe flag names a point
        that the query's ask added (the flag would outlive its point): take it back first."""
        if self.answers:
            before = len(self._tables_before[self.answers[-1].query.id])
            leaving = sorted(a for a in self.unsafe if a >= before)
            if leaving:
                raise QueryError(
                    f"point {leaving[0]}, flagged unsafe, was added by the last answer's query: "
                    "take the flag back before undoing the answer"
                )
        answer = super()._take_back()
        self._use_table(self._tables[answer.query.id])
        self._table_before_pending = self._tables_before[answer.query.id]
        return answer

    def _hard_banned(self) -> NDArray[np.bool_]:
        banned = super()._hard_banned()
        if self._avoided_points:
            banned |= self._avoided_on(self.space)
        return banned

    def _not_proposable_now(self) -> NDArray[np.bool_]:
        """As :meth:`CoSpar._not_proposable_now`, read along the line the pending query was
        chosen on, as its ask read it (``_on_line``: the table with the line's points; the
        cautious level weighs a gait against the known-safe gaits of that line): the table's
        rows its ask could not propose now."""
        pending = self.pending
        if pending is None or pending.line is None:
            return super()._not_proposable_now()
        with one_blas_thread():
            _, allowed = self._on_line(pending.line)
        out: NDArray[np.bool_] = ~allowed[: len(self.space)] | self._hard_banned()
        return out

    def _withdraw_if(self, banned_now: Callable[[], NDArray[np.bool_]]) -> bool:
        """As :meth:`CoSpar._withdraw_if`; a withdrawn query's points leave the table."""
        withdrawn = super()._withdraw_if(banned_now)
        if withdrawn:
            self._use_table(self._table_before_pending)
        return withdrawn

    def avoid(self, action: int, radius: float) -> bool:
        """As :meth:`CoSpar.avoid` (never propose ``action`` nor the points within ``radius``,
        a fraction of each feature's range); on the line path the neighbourhood, kept by its
        point (a withdrawn query's points leave the table), is taken out of every later line."""
        return self.avoid_all([action], radius)

    def avoid_all(self, actions: Sequence[int], radius: float) -> bool:
        """As :meth:`avoid` for each of ``actions``, all read in the table as it is now: the
        withdrawal that the first would cause takes the pending query's rows out of the table,
        so one at a time the next row would name another point, or none."""
        check_radius(radius)
        indices = [self.space.check_index(a) for a in actions]
        for index in indices:
            self.avoided[index] = max(float(radius), self.avoided.get(index, 0.0))
            self._avoided_points.append((self.space.points[index].copy(), float(radius)))
        return self._withdraw_if(lambda: self._avoided_on(self.space))

    def _avoided_on(self, space: PointSet) -> NDArray[np.bool_]:
        """The points of ``space`` within an avoided point's radius (features scaled by their
        ranges)."""
        span = np.array([f.span if f.span > 0 else 1.0 for f in self.domain.features])
        scaled = space.points / span
        out = np.zeros(len(space), dtype=bool)
        for centre, radius in self._avoided_points:
            d2 = np.sum((scaled - centre / span) ** 2, axis=1)
            out |= d2 <= radius**2 * (1 + 1e-12)
        return out

    def warm_start(self, warm: WarmStart) -> None:
        raise QueryError("warm starts from earlier subjects need the full grid, not the line path")


__all__ = ["LineCoSpar", "LineSettings", "on_points"]
