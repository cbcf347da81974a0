"""A scripted session: a simulated subject answers through the same Session API an operator uses.

The subject prefers step lengths near ``best`` (a smooth bump over the config's grid), compares
each trial with the buffered one(s) like :class:`~gaitpref.simulate.users.SimulatedUser`, gives
the paper's gradient-rule coactive suggestions, and ranks the blind validation gaits by the same
utility.  ``make demo`` runs it into SQLite and draws the session's figure.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.markup import escape

from gaitpref.config import ExperimentConfig, load_config
from gaitpref.feedback import Comparison, Suggestion
from gaitpref.sessions.records import SessionQuery
from gaitpref.sessions.session import Session
from gaitpref.sessions.validation import ValidationPlan, ValidationResult
from gaitpref.simulate.users import GradientCoactive, SimulatedUser
from gaitpref.space import FloatArray, Space
from gaitpref.wording import plural


def bump_utility(space: Space, best: dict[str, float] | None = None) -> FloatArray:
    """A smooth utility over the grid, highest at ``best`` (default: 60% along each feature)."""
    pts = space.points
    out = np.zeros(len(space))
    for k, f in enumerate(space.features):
        centre = (best or {}).get(f.name, f.values[0] + 0.6 * f.span)
        width = 0.35 * f.span if f.span > 0 else 1.0
        out -= ((pts[:, k] - centre) / width) ** 2
    return out


@dataclass
class SimulatedSubject:
    """Answers session queries from a utility over the grid (deterministic given ``seed``)."""

    space: Space
    utility: FloatArray
    seed: int = 0
    coactive: bool = True

    def __post_init__(self) -> None:
        self._user = SimulatedUser(self.space, self.utility, np.random.default_rng(self.seed))
        self._coach = GradientCoactive(self.space, self.utility) if self.coactive else None

    def respond(self, query: SessionQuery) -> tuple[list[Comparison], list[Suggestion]]:
        """The comparisons and coactive suggestions for ``query``."""
        comparisons = self._user.answer(query)  # type: ignore[arg-type]
        suggestions = [] if self._coach is None else self._coach.suggest_all(query.actions)
        return comparisons, suggestions

    def rank(self, plan: ValidationPlan) -> str:
        """The blind ranking, best first, as labels (e.g. ``"BCA"``)."""
        order = sorted(plan.gaits, key=lambda g: -self.utility[g.action])
        return "".join(g.label for g in order)


@dataclass(frozen=True)
class DemoSession:
    """Where the scripted session went and how it ended."""

    database: Path
    session_id: int
    trials: int
    best_action: int | None  # Session.recommended(): None when no gait may be proposed
    best_description: str
    validation: ValidationResult
    figure: Path | None


def run_session(
    session: Session, subject: SimulatedSubject, trials: int, validate: bool = True
) -> ValidationResult | None:
    """Answer queries until ``trials`` trials are in force, then (optionally) validate."""
    while len(session.trials()) < trials:
        query = session.next_query()
        comparisons, suggestions = subject.respond(query)
        session.answer(query.id, comparisons, suggestions)
    if not validate:
        return None
    plan = session.start_validation()
    return session.answer_validation(plan.round, subject.rank(plan))


def demo_session(
    out: Path,
    config: str | ExperimentConfig = "exo-2d-length-width",
    trials: int = 20,
    seed: int = 0,
    figure: bool = True,
) -> DemoSession:
    """The scripted session of ``make demo``: a simulated subject, SQLite, a figure."""
    cfg = config if isinstance(config, ExperimentConfig) else load_config(config)
    out.mkdir(parents=True, exist_ok=True)
    database = (out / "sessions.db").resolve()
    subject = SimulatedSubject(cfg.space, bump_utility(cfg.space), seed=seed)
    with Session.create(f"sqlite:///{database}", cfg, subject="DEMO01", seed=seed) as session:
        session.note("scripted demo session: a simulated subject answers through the Session API")
        result = run_session(session, subject, trials)
        assert result is not None
        session.finish()
        picture = None
        if figure:
            from gaitpref.plots.session import save_session_figure

            picture = save_session_figure(session, out / f"session-{session.id}.png")
        best = session.recommended()  # the best gait that may be walked, as the confidence's
        described = "none may be recommended" if best is None else session.describe(best)
        return DemoSession(database, session.id, trials, best, described, result, picture)


def print_demo_session(out: Path, console: Console) -> DemoSession:
    """Run :func:`demo_session` and tell the operator where everything went (``make demo``)."""
    from gaitpref.sessions.export import export_session
    from gaitpref.sessions.session import Session

    start = time.perf_counter()
    done = demo_session(out)
    with Session.open(f"sqlite:///{done.database}", done.session_id) as session:
        export = export_session(session, out / f"session-{done.session_id}-export", "csv").parent
    v = done.validation
    console.print(
        "[bold]scripted session[/]: a simulated subject answered "
        f"{plural(done.trials, 'trial')} of "
        f"exo-2d-length-width through the Session API in {time.perf_counter() - start:.1f} s; "
        f"best gait {escape(done.best_description)}; blind ranking {escape(''.join(v.ranking))} "
        f"{'agrees' if v.agrees else 'does not agree'} with the posterior "
        f"(Kendall's tau {v.kendall_tau:+.2f})",
        soft_wrap=True,
        markup=True,
    )
    said = f"database: [bold]{escape(str(done.database))}[/] (session {done.session_id})"
    console.print(said, soft_wrap=True, markup=True)
    if done.figure is not None:
        console.print(
            f"session figure: [bold]{escape(str(done.figure))}[/]", soft_wrap=True, markup=True
        )
    console.print(f"export: [bold]{escape(str(export))}[/]", soft_wrap=True, markup=True)
    command = f"gaitpref session show {done.session_id} --db {done.database} --no-figure"
    console.print(f"try: {command}", soft_wrap=True)
    return done
