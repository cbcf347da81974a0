"""The ``gaitpref`` command line: thin commands over the public API.

The root app mounts its sub-apps (``session``/``db``, ``bench``, ``gaits``, ``console``) from
modules that import only Typer at load time; every command imports what it needs when it runs, so
``gaitpref --help`` loads no NumPy, SciPy, SQLAlchemy, matplotlib or web framework
(``tests/cli/test_startup.py``, ``benchmarks/bench_startup.py``).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from gaitpref import __version__
from gaitpref.cli.console import serve as serve_console
from gaitpref.cli.gaits import app as gaits_app
from gaitpref.cli.output import console, err_console, fail, guard
from gaitpref.cli.session import db_app, session_app
from gaitpref.cli.simulate import bench_app

if TYPE_CHECKING:
    import numpy as np
    from rich.progress import Progress

    from gaitpref.config import ExperimentConfig
    from gaitpref.simulate.run import SimulationResult

app = typer.Typer(
    name="gaitpref",
    help="Personalize exoskeleton gaits from user preferences (CoSpar).",
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,
)
# one command, not a group: `gaitpref console --help` lists its options, not `COMMAND [ARGS]`
app.command(
    "console", help="Serve the operator console (a web page) for running sessions at the bench."
)(serve_console)
app.add_typer(session_app, name="session")
app.add_typer(db_app, name="db")
app.add_typer(bench_app, name="bench")
app.add_typer(gaits_app, name="gaits")


def progress_bar(transient: bool = False) -> Progress:
    """The Rich progress bar used by long commands."""
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
    )


def _load_config_or_fail(source: str) -> ExperimentConfig:
    from gaitpref.config import load_config

    return guard(lambda: load_config(source))


def _load_objective(path: Path) -> np.ndarray:
    import numpy as np

    if not path.is_file():
        fail(f"objective file {str(path)!r} does not exist")
    try:
        arr: np.ndarray = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        fail(f"objective file {str(path)!r} is not a readable .npy array: {exc}")
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
) -> SimulationResult:
    """One simulated experiment with ``config`` against ``objective`` (seeded by ``seed``)."""
    import numpy as np

    from gaitpref.simulate.run import run_simulation
    from gaitpref.simulate.users import GradientCoactive, SimulatedUser

    loop_seed, user_seed = np.random.SeedSequence(seed).spawn(2)
    loop = config.make_loop(seed=np.random.default_rng(loop_seed))
    user = SimulatedUser(
        config.space, objective, np.random.default_rng(user_seed), minimize=minimize
    )
    helper = GradientCoactive(config.space, objective, minimize=minimize) if coactive else None
    if not show_progress:
        return run_simulation(loop, user, trials, helper)
    with progress_bar(transient=True) as bar:
        task = bar.add_task("trials", total=trials)
        return run_simulation(
            loop, user, trials, helper, progress=lambda done: bar.update(task, completed=done)
        )


@app.command()
def simulate(
    config: Annotated[
        str, typer.Argument(metavar="CONFIG", help="Config TOML file or shipped config name.")
    ],
    objective: Annotated[
        Path, typer.Option(help=".npy file: one utility per grid point, shaped like the grid.")
    ],
    minimize: Annotated[bool, typer.Option(help="Lower objective values are better.")] = False,
    trials: Annotated[int, typer.Option(min=1, help="Executed actions to simulate.")] = 150,
    seed: Annotated[int | None, typer.Option(help="Seed (default: the config's).")] = None,
    coactive: Annotated[bool, typer.Option(help="Simulate coactive suggestions.")] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
) -> None:
    """Run one simulated CoSpar experiment against an objective over the config's grid."""
    from rich.table import Table

    from gaitpref.simulate.users import objective_on_grid

    cfg = _load_config_or_fail(config)
    obj = _load_objective(objective)
    try:
        objective_on_grid(cfg.space, obj)
    except ValueError as exc:
        fail(f"objective {str(objective)!r}: {exc}")
    use_seed = cfg.seed if seed is None else seed
    start = time.perf_counter()
    result = simulate_once(
        cfg,
        obj,
        trials=trials,
        seed=use_seed,
        minimize=minimize,
        coactive=coactive,
        show_progress=not as_json,
    )
    elapsed = time.perf_counter() - start
    if as_json:
        payload = {"config": cfg.name, "seed": use_seed, "seconds": elapsed, **result.to_json()}
        typer.echo(json.dumps(payload))
        return
    score = result.normalized_objective
    table = Table(title=f"{cfg.name}: {trials} trials, seed {use_seed}")
    table.add_column("trials")
    table.add_column("mean normalized objective", justify="right")
    for lo, hi in [(1, 10), (11, 25), (26, 50), (51, 100), (101, trials)]:
        if lo <= trials:
            table.add_row(f"{lo}-{min(hi, trials)}", f"{score[lo - 1 : hi].mean():.3f}")
    console.print(table)
    best = result.posterior_argmax
    console.print(
        f"posterior argmax: action {best} ({cfg.space.describe(best)}), normalized objective "
        f"{result.argmax_normalized_objective:.3f}"
    )
    console.print(f"simulated {trials} trials in {elapsed:.2f} s (wall clock)")


@app.command("configs")
def list_configs() -> None:
    """List the shipped experiment configs."""
    from rich.table import Table

    from gaitpref.config import load_config, shipped_configs

    table = Table(title="shipped configs")
    for col in ("name", "grid", "n", "b", "description"):
        table.add_column(col)
    for name in shipped_configs():
        cfg = load_config(name)
        grid = " x ".join(str(s) for s in cfg.space.shape)
        table.add_row(name, grid, str(cfg.n), str(cfg.buffer), cfg.description)
    console.print(table)


@app.command()
def demo(
    out: Annotated[Path, typer.Option(help="Folder for the demo's outputs.")] = Path("out/demo"),
    objective_index: Annotated[
        int, typer.Option("--objective", min=0, max=99, help="Which of the 100 paper objectives.")
    ] = 0,
    trials: Annotated[int, typer.Option(min=1)] = 150,
) -> None:
    """A full simulated 2-D experiment on one of the paper's objectives, with figures."""
    from gaitpref.config import load_config
    from gaitpref.data import paper_objectives
    from gaitpref.plots.posterior import posterior_picture, save_posterior_figure

    cfg = load_config("synthetic-2d")
    objective = paper_objectives()[objective_index]
    console.print(
        f"[bold]gaitpref {__version__} demo[/]: CoSpar n={cfg.n}, b={cfg.buffer} with coactive "
        f"feedback on the paper's synthetic objective {objective_index} (30 x 30 grid)"
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
        title=f"synthetic objective {objective_index}: {trials} trials, CoSpar n=1, b=1, coactive",
    )
    figure = save_posterior_figure(pic, out / "posterior.png")
    score = result.normalized_objective
    console.print(
        f"{trials} trials in {elapsed:.2f} s; mean normalized objective over trials 1-25: "
        f"{score[:25].mean():.3f}, 126-150: {score[-25:].mean():.3f}; "
        f"the posterior's best action scores {_norm(objective, result.posterior_argmax):.3f}"
    )
    console.print(f"figure: [bold]{figure}[/]")
    from gaitpref.sessions.demo import print_demo_session

    print_demo_session(out, console)


def _norm(objective: np.ndarray, index: int) -> float:
    flat = objective.reshape(-1)
    return float((flat[index] - flat.min()) / (flat.max() - flat.min()))


def main() -> None:
    """Console-script entry point."""
    app()
