"""``gaitpref gaits ...``: build, inspect and plot gait libraries (a Typer sub-application).

Thin commands over :mod:`gaitpref.gaits`; ranges are written ``min:max:count`` (inclusive, equally
spaced, as :func:`numpy.linspace`) or as a single value.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from gaitpref.cli.output import check_file_out, console, err_console, reported
from gaitpref.errors import GaitLibraryError, SimulationError

if TYPE_CHECKING:
    from gaitpref.gaits.library import GaitLibrary


def max_gaits() -> int:
    """A library holds at most as many gaits as a config's grid may have actions (read when a
    command runs: the config schema loads the model, which `gaitpref --help` must not)."""
    from gaitpref.config.schema import MAX_ACTIONS

    return MAX_ACTIONS


#: ``plot --steps``: each simulated step takes about 0.15 s a gait.
MAX_PLOT_STEPS = 100

app = typer.Typer(
    help="Compass-gait HZD gaits and gait libraries.", no_args_is_help=True, add_completion=False
)


def parse_range(text: str, option: str) -> tuple[float, ...]:
    """``"0.08:0.18:15"`` -> 15 equally spaced values; ``"0.2"`` -> one value."""
    import numpy as np

    parts = text.split(":")
    try:
        if len(parts) == 1:
            values = np.array([float(parts[0])])
        elif len(parts) == 3:
            lo, hi, num = float(parts[0]), float(parts[1]), int(parts[2])
            if num < 1 or (num > 1 and not hi > lo):
                raise ValueError
            if num > (limit := max_gaits()):
                raise typer.BadParameter(
                    f"{text!r}: at most {limit} values (a config takes at most {limit} gaits)",
                    param_hint=option,
                )
            values = np.linspace(lo, hi, num)
        else:
            raise ValueError
    except ValueError:
        raise typer.BadParameter(
            f"{text!r} is not min:max:count (max > min, count >= 1) or a single number",
            param_hint=option,
        ) from None
    if not np.all(np.isfinite(values)) or np.any(values <= 0):
        raise typer.BadParameter(f"{text!r}: values must be positive", param_hint=option)
    return tuple(float(v) for v in values)


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _load(path: Path) -> GaitLibrary:
    from gaitpref.gaits.library import GaitLibrary

    try:
        return GaitLibrary.load(path, allow_infeasible=True)
    except GaitLibraryError as exc:
        raise typer.BadParameter(str(exc), param_hint="FILE") from None


@app.command()
def build(
    out: Annotated[Path, typer.Option("--out", help="Library file to write (JSON).")],
    step_length: Annotated[
        str, typer.Option(help="Step lengths [m], min:max:count.")
    ] = "0.08:0.18:15",
    step_duration: Annotated[
        str | None, typer.Option(help="Step durations [s], min:max:count.")
    ] = None,
    speed: Annotated[float | None, typer.Option(help="Fixed forward speed [m/s] instead.")] = None,
    step_width: Annotated[
        str | None, typer.Option(help="Step widths [m]: a label only (the model is planar).")
    ] = None,
    degree: Annotated[int, typer.Option(help="Bezier degree of the virtual constraint.")] = 6,
    jobs: Annotated[
        int,
        typer.Option(
            "--jobs",
            "-j",
            help="Parallel processes (no more than the chains: one per step duration, or "
            "per step length at a fixed speed).",
        ),
    ] = 1,
) -> None:
    """Optimize one gait per grid point and write the library; exit 1 if any is infeasible."""
    from joblib import cpu_count
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
    )

    from gaitpref.gaits.build import build_library, check_grid
    from gaitpref.gaits.gait import HZDSettings
    from gaitpref.gaits.library_io import MAX_LIBRARY_BYTES, max_gaits_in_file

    if (step_duration is None) == (speed is None):
        raise typer.BadParameter("give exactly one of --step-duration and --speed")
    if speed is not None and not (math.isfinite(speed) and speed > 0):
        raise typer.BadParameter(f"must be a positive number, got {speed}", param_hint="--speed")
    cpus = cpu_count()
    if not 1 <= jobs <= cpus:  # joblib starts every worker asked for, busy or not
        raise typer.BadParameter(f"must be in 1..{cpus} (the CPUs here)", param_hint="--jobs")
    lengths = parse_range(step_length, "--step-length")
    durations = None if step_duration is None else parse_range(step_duration, "--step-duration")
    widths = None if step_width is None else parse_range(step_width, "--step-width")
    try:
        settings = HZDSettings(degree=degree)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--degree") from None
    size = len(lengths) * len(durations or (0,)) * len(widths or (0,))
    if size > max_gaits():
        raise typer.BadParameter(
            f"the grid has {size} gaits; a config takes at most {max_gaits()}",
            param_hint="--step-length/--step-duration/--step-width",
        )
    if size > (in_file := max_gaits_in_file(degree)):  # hours of work, then a file too large
        raise typer.BadParameter(
            f"the grid has {size:,} gaits; a library file holds at most {in_file:,} of degree "
            f"{degree} (it is read back up to {MAX_LIBRARY_BYTES:,} bytes): build it in parts",
            param_hint="--step-length/--step-duration/--step-width",
        )
    try:  # before the progress bar: it drew '0/1' above the error
        check_grid(lengths, durations, speed, widths)
    except ValueError as exc:  # GaitLibraryError too
        raise typer.BadParameter(
            str(exc), param_hint="--step-length/--step-duration/--step-width"
        ) from None
    check_file_out(out, "--out")
    total = len(lengths) * (len(durations) if durations else 1)
    columns = (
        TextColumn("optimizing gaits"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
    )
    from rich.markup import escape

    with reported(), Progress(*columns, console=err_console) as bar:
        task = bar.add_task("gaits", total=total)
        lib = build_library(  # checks the grid (ids, step lengths) before optimizing
            lengths,
            step_durations=durations,
            speed=speed,
            step_widths=widths,
            settings=settings,
            n_jobs=jobs,
            progress=lambda k: bar.advance(task, k),
        )
    with reported():
        lib.save(out)
    bad = lib.infeasible()
    # on stdout, as `gaits plot`'s and every other command's result (the bar and the
    # infeasible gaits, the reason for status 1, on stderr)
    console.print(f"wrote {out}: {len(lib)} gaits, {len(lib) - len(bad)} feasible")
    if bad:
        for i in bad:
            err_console.print(
                f"[red]infeasible[/red] {escape(lib.gait_id(i))}: {escape(lib.gaits[i].message)}",
                markup=True,
            )
        raise typer.Exit(code=1)


@app.command()
def show(
    file: Annotated[Path, typer.Argument(metavar="FILE", help="Gait library file.")],
    as_json: Annotated[bool, typer.Option("--json", help="One JSON object on stdout.")] = False,
) -> None:
    """List the gaits of a library: parameters, duration, COT, delta^2, feasibility."""
    from rich import box
    from rich.table import Table
    from rich.text import Text

    lib = _load(file)
    if as_json:
        rows = [
            {
                "index": i,
                "id": lib.gait_id(i),
                "parameters": lib.parameters(i),
                "step_duration": _finite(gait.step_duration),
                "cot": _finite(gait.cot) if gait.feasible else None,
                "delta_squared": _finite(gait.delta_squared),
                "feasible": gait.feasible,
                "message": gait.message,
            }
            for i, gait in enumerate(lib.gaits)
        ]
        doc = {
            "file": str(file),
            "speed": lib.speed,
            "axes": {name: list(values) for name, values in lib.axes},
            "n_gaits": len(lib),
            "n_feasible": len(lib) - len(lib.infeasible()),
            "gaits": rows,
        }
        typer.echo(json.dumps(doc, indent=1))
        return
    speed = f", speed {lib.speed:g} m/s" if lib.speed is not None else ""
    feasible = len(lib) - len(lib.infeasible())
    table = Table(
        title=f"{file.name}: {len(lib)} gaits ({feasible} feasible) over "
        f"{' x '.join(lib.names)}{speed}",
        box=box.SIMPLE_HEAD,  # no column rules: 80 columns hold three axes
        pad_edge=False,
        collapse_padding=True,
    )
    # "ok": feasible; the unit in "duration [s]" shows now that markup is off.  A value is never
    # cut: past the width a header wraps, a value folds (a lined table at 80 columns showed the
    # index column empty and 'L0.080-T0.950-W…', '0.0…', 'y…' for two axes or three)
    for col in ("#", "id", *lib.names, "duration [s]", "COT", "delta^2", "ok"):
        table.add_column(
            col,
            justify="left" if col == "id" else "right",
            overflow="fold",
            no_wrap=col in ("#", "id"),
        )
    for i, gait in enumerate(lib.gaits):
        params = [f"{v:.4g}" for v in lib.parameters(i).values()]
        cot = f"{gait.cot:.5f}" if gait.feasible else "-"
        ok = Text("yes") if gait.feasible else Text("no", style="red")
        table.add_row(
            str(i), lib.gait_id(i), *params, f"{gait.step_duration:.4f}", cot,
            f"{gait.delta_squared:.4f}", ok,
        )  # fmt: skip
    console.print(table)


@app.command()
def plot(
    file: Annotated[Path, typer.Argument(metavar="FILE", help="Gait library file.")],
    ids: Annotated[
        list[str] | None,
        typer.Option("--id", help="Gait id to show (repeatable); default: least/median/most COT."),
    ] = None,
    out: Annotated[Path | None, typer.Option(help="PNG to write (default: FILE.png).")] = None,
    steps: Annotated[int, typer.Option(help="Simulated steps per phase diagram.")] = 6,
) -> None:
    """COT over the grid and joint phase diagrams from full-model simulations (as the paper's
    Fig. 7)."""
    if not 1 <= steps <= MAX_PLOT_STEPS:
        raise typer.BadParameter(
            f"must be in 1..{MAX_PLOT_STEPS}, got {steps}", param_hint="--steps"
        )
    lib = _load(file)
    from gaitpref.gaits.figures import (  # matplotlib: lazily
        default_ids,
        figure_target,
        render_library_figure,
    )

    chosen = list(ids) if ids else default_ids(lib)
    for gait_id in chosen:
        try:
            index = lib.index_of_id(gait_id)
        except GaitLibraryError as exc:
            raise typer.BadParameter(str(exc), param_hint="--id") from None
        if not lib.gaits[index].feasible:
            raise typer.BadParameter(f"gait {gait_id} is infeasible", param_hint="--id")
    try:
        target = figure_target(out if out is not None else file.with_suffix(".png"))
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--out") from None
    check_file_out(target, "--out")
    with reported():
        try:
            written = render_library_figure(lib, chosen, target, steps=steps)
        except SimulationError as exc:
            typer.echo(f"simulation failed: {exc}", err=True)
            raise typer.Exit(code=1) from None
    typer.echo(f"wrote {written}")
