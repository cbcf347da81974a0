"""The ``gaitpref`` command line: thin commands over the public API.

The root app mounts its sub-apps (``session``/``db``, ``bench``, ``gaits``, ``console``) from
modules that import only Typer at load time; every command imports what it needs when it runs, so
``gaitpref --help`` loads no NumPy, SciPy, SQLAlchemy, matplotlib or web framework
(``tests/cli/test_startup.py``, ``benchmarks/bench_startup.py``).
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from typer.core import TyperGroup

from gaitpref import __version__
from gaitpref.cli.console import serve as serve_console
from gaitpref.cli.gaits import app as gaits_app
from gaitpref.cli.output import (
    checked_config,
    console,
    err_console,
    fail,
    guard,
    json_only,
    read_array,
)
from gaitpref.cli.session import db_app, session_app
from gaitpref.cli.simulate import bench_app
from gaitpref.limits import MAX_SEED, MAX_TRIALS
from gaitpref.wording import plural

if TYPE_CHECKING:
    import numpy as np
    from rich.progress import Progress

    from gaitpref.config import ExperimentConfig
    from gaitpref.simulate.run import SimulationResult


class RootGroup(TyperGroup):
    """The root group: an interrupt (Ctrl-C) anywhere exits with status 130, as documented
    (``docs/getting-started.md``, "In scripts: exit statuses and output"), whatever the typer
    release: typer 0.29 does so itself, earlier releases that pyproject allows printed
    ``Aborted!`` and exited with status 1, the status of a check that failed (``db check``)."""

    def invoke(self, ctx: Any) -> Any:  # a click.Context (typer 0.29: its own copy of click)
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt:
            raise typer.Exit(130) from None


app = typer.Typer(
    cls=RootGroup,
    name="gaitpref",
    help="Personalize exoskeleton gaits from user preferences (CoSpar).",
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,
    # a traceback never lists local variables: they hold --db, whose PostgreSQL URL may carry
    # a password (typer >= 0.12 is allowed, and older typer releases listed them by default)
    pretty_exceptions_show_locals=False,
)
# one command, not a group: `gaitpref console --help` lists its options, not `COMMAND [ARGS]`
app.command(
    "console", help="Serve the operator console (a web page) for running sessions at the bench."
)(serve_console)
app.add_typer(session_app, name="session")
app.add_typer(db_app, name="db")
app.add_typer(bench_app, name="bench")
app.add_typer(gaits_app, name="gaits")


def progress_bar(transient: bool = False, shown: bool = True) -> Progress:
    """The Rich progress bar used by long commands (on stderr; ``shown=False``: none).

    A ``transient`` bar is shown on a terminal only: elsewhere (a file, a pipe) it cannot be
    taken back and left an empty line on stderr."""
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeRemainingColumn,
    )

    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=err_console,
        transient=transient,
        disable=not shown or (transient and not err_console.is_terminal),
    )


def _load_config_or_fail(source: str) -> ExperimentConfig:
    """A config for a new run: loaded, and checked as a new session checks it (its name and
    its largest draw), so that a run is refused at once rather than at the first ask."""
    from gaitpref.config import check_new, load_config

    def load() -> ExperimentConfig:
        cfg = load_config(source)
        checked_config(source, cfg, check_new)
        return cfg

    return guard(load)


def _load_objective(path: Path) -> np.ndarray:
    arr: np.ndarray = read_array(path, "objective file")
    return arr


def simulate_once(
    config: ExperimentConfig,
    objective: np.ndarray,
    *,
    trials: int,
    seed: int,
    minimize: bool = False,
    coactive: bool = False,
    show_progress: bool = False,
    rating_quantiles: Sequence[float] = (),
    rating_noise: float = 0.0,
) -> SimulationResult:
    """One simulated experiment with ``config`` against ``objective`` (seeded by ``seed``).

    With ``rating_quantiles`` a simulated subject also rates every executed gait, its category
    boundaries at those quantiles of the objective (``OrdinalRater``, ordinal noise
    ``rating_noise`` on the normalised objective); the rater's generator is a third child of
    ``seed``, so the loop and the user draw the same numbers with or without it.
    """
    import numpy as np

    from gaitpref.errors import NoSafeGaitError
    from gaitpref.simulate.raters import OrdinalRater
    from gaitpref.simulate.run import run_simulation
    from gaitpref.simulate.users import GradientCoactive, SimulatedUser

    loop_seed, user_seed, rater_seed = np.random.SeedSequence(seed).spawn(3)
    loop = config.make_loop(seed=np.random.default_rng(loop_seed))
    user = SimulatedUser(
        config.space, objective, np.random.default_rng(user_seed), minimize=minimize
    )
    helper = GradientCoactive(config.space, objective, minimize=minimize) if coactive else None
    rater = None
    if rating_quantiles:
        rater = OrdinalRater(
            config.space,
            objective,
            tuple(rating_quantiles),
            np.random.default_rng(rater_seed),
            noise=rating_noise,
            minimize=minimize,
        )
    try:
        if not show_progress:
            return run_simulation(loop, user, trials, helper, rater=rater)
        with progress_bar(transient=True) as bar:
            task = bar.add_task("trials", total=trials)
            return run_simulation(
                loop,
                user,
                trials,
                helper,
                progress=lambda done: bar.update(task, completed=done),
                rater=rater,
            )
    except NoSafeGaitError as exc:  # the region of avoidance emptied: say at which trial
        raise NoSafeGaitError(
            f"the simulation stopped after {len(loop.executed)} of {trials} trials: {exc}"
        ) from None


def rating_quantiles_for(config: ExperimentConfig, text: str | None, noise: float) -> list[float]:
    """The ``--rating-quantiles`` of ``simulate``, checked against the config's rating scale.

    Raises ``ValueError`` naming the problem: quantiles that are not numbers increasing inside
    (0, 1), a config without ``[feedback.rating]``, or a count that is not one fewer than its
    labels.
    """
    import itertools
    import math

    if text is None:
        if noise != 0:
            raise ValueError("--rating-noise needs --rating-quantiles (the simulated rater)")
        return []
    parts = text.split(",")
    try:
        if text.strip() and any(not v.strip() for v in parts):  # "0.25,,0.75" was 2 quantiles
            raise ValueError
        q = [float(v) for v in parts if v.strip()]
    except ValueError:
        raise ValueError(
            f"--rating-quantiles must be comma-separated numbers, got {text!r}"
        ) from None
    if not q or any(not 0 < v < 1 for v in q) or any(b <= a for a, b in itertools.pairwise(q)):
        raise ValueError(f"--rating-quantiles must increase strictly inside (0, 1), got {text!r}")
    if not (math.isfinite(noise) and noise >= 0):
        raise ValueError(f"--rating-noise must be a number >= 0, got {noise!r}")
    if config.ordinal is None:
        raise ValueError(
            f"--rating-quantiles: config {config.name!r} has no [feedback.rating] table; give it "
            f"one with {len(q) + 1} labels (one more than the {len(q)} quantiles), worst first"
        )
    if config.ordinal.size != len(q) + 1:
        raise ValueError(
            f"--rating-quantiles: {len(q)} quantiles make {len(q) + 1} categories, but "
            f"[feedback.rating] of config {config.name!r} has {config.ordinal.size} labels "
            f"({', '.join(config.ordinal.categories)}); give one quantile fewer than labels"
        )
    return q


@app.command()
def simulate(
    config: Annotated[
        str, typer.Argument(metavar="CONFIG", help="Config TOML file or shipped config name.")
    ],
    objective: Annotated[
        str,
        typer.Option(
            help=".npy file: one utility per grid point, shaped like the grid; or PATH.py:NAME, "
            "a function of an m x d array of points (features' units) returning m utilities; "
            "or a built-in: hartmann6, random-gp[:SEED]."
        ),
    ],
    minimize: Annotated[
        bool,
        typer.Option(
            help="Lower objective values are better (a .npy objective, or any objective with "
            "--rating-quantiles; refused for a function over points without them: negate it)."
        ),
    ] = False,
    trials: Annotated[
        int, typer.Option(min=1, max=MAX_TRIALS, help="Executed actions to simulate.")
    ] = 150,
    seed: Annotated[
        int | None, typer.Option(min=0, max=MAX_SEED, help="Seed (default: the config's).")
    ] = None,
    coactive: Annotated[bool, typer.Option(help="Simulate coactive suggestions.")] = False,
    rating_quantiles: Annotated[
        str | None,
        typer.Option(
            help="Rate every executed gait: category boundaries at these quantiles of the "
            "objective, e.g. 0.25,0.5,0.75 (the config's [feedback.rating] needs one more label)."
        ),
    ] = None,
    rating_noise: Annotated[
        float,
        typer.Option(
            help="The rater's ordinal noise (>= 0; 0: none), in units of the objective "
            "scaled to run from 0 to 1."
        ),
    ] = 0.0,
    noise: Annotated[
        float,
        typer.Option(
            help="The simulated subject's probit noise (objectives over points, without "
            "--rating-quantiles; refused otherwise)."
        ),
    ] = 0.0,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
) -> None:
    """Run one simulated CoSpar experiment against an objective over the config's grid or, for
    PATH.py:NAME and the built-ins, over points (also on the line path of continuous spaces).

    With --rating-quantiles a simulated subject also rates every executed gait; --json then
    gives the ratings per trial ("ratings", 1 = worst) beside the executed "actions".  --json
    gives the executed points' feature values per query ("points") and the objective there, and
    the final posterior's best point ("best_point", "best_objective").
    """
    from rich.table import Table

    from gaitpref.cli.points import is_grid_objective, load_point_objective, run_command
    from gaitpref.simulate.users import objective_on_grid

    cfg = _load_config_or_fail(config)
    use_seed = cfg.seed if seed is None else seed
    if not is_grid_objective(objective) and rating_quantiles is None:
        if rating_noise != 0:  # there is no rater to take it: it was ignored (nan too)
            fail("--rating-noise needs --rating-quantiles (the simulated rater)")
        if minimize:  # the subject over points prefers higher values: it was ignored
            fail(
                f"--minimize: objective {objective!r} is a function over points, and those are "
                "maximized (higher is better); negate it in PATH.py:NAME instead"
            )
        run_command(cfg, objective, trials, use_seed, coactive, noise, as_json)
        return
    if noise != 0:  # the grid's subject takes no noise here: any value (nan too) was ignored
        fail(
            f"--noise {noise!r}: only a subject over points (PATH.py:NAME, hartmann6, random-gp "
            "without --rating-quantiles) takes a probit noise; leave it out"
        )
    if cfg.subspace == "line":
        if rating_quantiles:
            fail(
                f"--rating-quantiles: config {cfg.name!r} runs on the line path (no grid over "
                "which to take the objective's quantiles); leave it out there"
            )
        fail(
            f"objective {objective!r}: config {cfg.name!r} runs on the line path (no grid to "
            "hold a .npy objective); give PATH.py:NAME, hartmann6 or random-gp"
        )
    if is_grid_objective(objective):
        obj = _load_objective(Path(objective))
    else:  # a function of points, evaluated over the grid: its quantiles are the grid's
        import numpy as np

        shape = tuple(len(f) for f in cfg.space.features)
        with json_only(as_json):  # the function's own prints kept off the JSON
            fn = load_point_objective(objective, cfg)
            obj = guard(lambda: np.asarray(fn(cfg.space.points), dtype=np.float64).reshape(shape))
    try:
        objective_on_grid(cfg.space, obj)
    except ValueError as exc:
        fail(f"objective {str(objective)!r}: {exc}")
    quantiles = guard(lambda: rating_quantiles_for(cfg, rating_quantiles, rating_noise))
    start = time.perf_counter()
    result = guard(  # a region of avoidance left no gait: an error line, not a traceback
        lambda: simulate_once(
            cfg,
            obj,
            trials=trials,
            seed=use_seed,
            minimize=minimize,
            coactive=coactive,
            show_progress=not as_json,
            rating_quantiles=quantiles,
            rating_noise=rating_noise,
        )
    )
    elapsed = time.perf_counter() - start
    if as_json:
        best = result.posterior_argmax
        # per query, as over points (a query's n executed actions; the last query's trials
        # past --trials left out): it was one list per trial, [[p1], [p2], ...], whatever n
        actions = result.actions.tolist()
        queries = [actions[i : i + cfg.n] for i in range(0, len(actions), cfg.n)]
        payload = {
            "config": cfg.name,
            "seed": use_seed,
            "seconds": elapsed,
            **result.to_json(),
            "points": [cfg.space.points_of(q).tolist() for q in queries],
            "objective": [[float(v) for v in obj.reshape(-1)[q]] for q in queries],
            "best_point": cfg.space.points_of([best])[0].tolist(),
            "best_objective": float(obj.reshape(-1)[best]),
        }
        typer.echo(json.dumps(payload))
        return
    score = result.normalized_objective
    table = Table(title=f"{cfg.name}: {plural(trials, 'trial')}, seed {use_seed}")
    table.add_column("trials")
    table.add_column("mean normalized objective", justify="right")
    for lo, hi in [(1, 10), (11, 25), (26, 50), (51, 100), (101, trials)]:
        if lo <= trials:
            table.add_row(f"{lo}-{min(hi, trials)}", f"{score[lo - 1 : hi].mean():.3f}")
    console.print(table)
    if result.ratings is not None and cfg.ordinal is not None:
        counts = [int((result.ratings == k).sum()) for k in range(1, cfg.ordinal.size + 1)]
        given = zip(counts, cfg.ordinal.categories, strict=True)
        console.print("ratings given: " + ", ".join(f"{c} {name!r}" for c, name in given))
    best = result.posterior_argmax
    console.print(
        f"posterior argmax: action {best} ({cfg.space.describe(best)}), normalized objective "
        f"{result.argmax_normalized_objective:.3f}"
    )
    console.print(f"simulated {plural(trials, 'trial')} in {elapsed:.2f} s (wall clock)")


@app.command("configs")
def list_configs(
    as_json: Annotated[
        bool,
        typer.Option(
            "--json",
            help="Print one JSON array, a config per object: name, space, n, b, description.",
        ),
    ] = False,
) -> None:
    """List the shipped experiment configs."""
    from rich.table import Table

    from gaitpref.config import load_config, shipped_configs

    rows: list[dict[str, str | int]] = []
    for name in shipped_configs():
        cfg = load_config(name)
        rows.append(
            {
                "name": name,
                "space": cfg.space.words,
                "n": cfg.n,
                "b": cfg.buffer,
                "description": cfg.description,
            }
        )
    if as_json:  # for scripts: the table is 80 columns wide off a terminal
        typer.echo(json.dumps(rows))
        return
    table = Table(title="shipped configs")
    # a name is what one types: kept whole on one line (at 80 columns, off a terminal,
    # exo-2d-length-duration was cut to "exo-2d-length-durati…"); the other cells fold
    table.add_column("name", no_wrap=True, min_width=max(len(str(r["name"])) for r in rows))
    for col in ("space", "n", "b", "description"):
        table.add_column(col, overflow="fold")
    for row in rows:
        table.add_row(*(str(value) for value in row.values()))
    console.print(table)


@app.command()
def demo(
    out: Annotated[Path, typer.Option(help="Folder for the demo's outputs.")] = Path("out/demo"),
    objective_index: Annotated[
        int, typer.Option("--objective", min=0, max=99, help="Which of the 100 paper objectives.")
    ] = 0,
    trials: Annotated[
        int,
        typer.Option(
            min=1,
            max=MAX_TRIALS,
            help="Executed trials of the simulated experiment (the scripted session after it "
            "answers 20 either way).",
        ),
    ] = 150,
) -> None:
    """A full simulated 2-D experiment on one of the paper's objectives, with figures."""
    from rich.markup import escape

    from gaitpref.cli.simulate import _folder
    from gaitpref.config import load_config
    from gaitpref.data import paper_objectives
    from gaitpref.plots.posterior import posterior_picture, save_posterior_figure

    _folder(out)  # before the run: a file there was a FileExistsError traceback after it
    cfg = load_config("synthetic-2d")
    objective = paper_objectives()[objective_index]
    console.print(
        f"[bold]gaitpref {__version__} demo[/]: CoSpar n={cfg.n}, b={cfg.buffer} with coactive "
        f"feedback on the paper's synthetic objective {objective_index} (30 x 30 grid)",
        markup=True,
    )
    start = time.perf_counter()
    result = simulate_once(
        cfg, objective, trials=trials, seed=cfg.seed, coactive=True, show_progress=True
    )
    elapsed = time.perf_counter() - start
    pic = posterior_picture(
        result.posterior,
        result.actions,
        objective.reshape(-1),
        samples=0,
        title=f"synthetic objective {objective_index}: {plural(trials, 'trial')}, CoSpar n=1, "
        "b=1, coactive",
    )
    figure = save_posterior_figure(pic, out / "posterior.png")
    score = result.normalized_objective
    first, last = min(25, trials), max(1, trials - 24)  # labelled 1-25 and 126-150 whatever ran
    console.print(
        f"{plural(trials, 'trial')} in {elapsed:.2f} s; mean normalized objective over trials "
        f"1-{first}: "
        f"{score[:first].mean():.3f}, {last}-{trials}: {score[last - 1 :].mean():.3f}; "
        f"the posterior's best action scores {_norm(objective, result.posterior_argmax):.3f}"
    )
    console.print(f"figure: [bold]{escape(str(figure))}[/]", markup=True)
    from gaitpref.sessions.demo import print_demo_session

    print_demo_session(out, console)


def _norm(objective: np.ndarray, index: int) -> float:
    flat = objective.reshape(-1)
    return float((flat[index] - flat.min()) / (flat.max() - flat.min()))


def main() -> None:
    """Console-script entry point."""
    app()
