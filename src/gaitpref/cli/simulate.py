"""``gaitpref bench ...``: the paper's simulation studies from the command line.

    gaitpref bench paper-2d [--runs 100] [--trials 150] [--settings n1_b1,n1_b1_coactive]
                            [--backend joblib|ray] [--address ADDR] [--jobs N] [--out DIR]
                            [--resume]
    gaitpref bench compass-gait [--objective poly|hzd] [--library FILE.json] [--runs 100] ...
                                [--resume]
    gaitpref bench population --objectives FILE.npy --trials T [--jobs N] [--json]
                              [--partial FILE.jsonl [--resume]]
    gaitpref bench continuous CONFIG --objective PATH.py:NAME|hartmann6|random-gp [--runs 5] ...
                              [--partial FILE.jsonl [--resume]]

Thin commands over :mod:`gaitpref.simulate` (studies in ``paper2d``/``compass``, execution in
``sweep``, files in ``tables``/``report``/``figures``).  What a command found (a bench's
summary, a study's ``N runs in T s; wrote ...``) goes to stdout, progress bars, notes and
warnings to stderr (``_console``): the summaries were on stderr, and ``> results.txt`` kept
nothing.  A run that fails stops every command
with status 1 and an error naming the run and where the finished runs are (a study's in
``OUT/runs.partial.csv``, a bench's in its ``--partial`` file: :mod:`gaitpref.simulate.partial`).
A study that stopped continues with the same command and ``--resume``: the runs in
``OUT/runs.partial.csv`` are kept and only the others run (:mod:`gaitpref.simulate.resume`);
so do ``bench continuous`` and ``bench population`` from their ``--partial`` file
(:mod:`gaitpref.simulate.resume_lines`).
"""

from __future__ import annotations

import secrets
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, TextIO, TypeVar

import typer

from gaitpref.cli.output import (
    HANDLED,
    checked_config,
    console,
    fail,
    guard,
    json_only,
    read_array,
    report,
)
from gaitpref.cli.output import err_console as _console
from gaitpref.limits import (
    MAX_JOBS,
    MAX_RUNS,
    MAX_SEED,
    MAX_SNAPSHOTS,
    MAX_STUDY_TRIALS,
    MAX_TRIALS,
    PAPER_OBJECTIVES,
)
from gaitpref.wording import plural

if TYPE_CHECKING:
    from gaitpref.config import ExperimentConfig
    from gaitpref.simulate.study import Study
    from gaitpref.simulate.sweep import Backend as SweepBackend
    from gaitpref.simulate.sweep import StudyResult

bench_app = typer.Typer(
    help="Reproduce the paper's simulation studies (sweeps over settings x objectives x seeds).",
    no_args_is_help=True,
)

Backend = Annotated[
    str,
    typer.Option("--backend", help="joblib (local processes) or ray (pip install 'gaitpref[ray]')"),
]
Address = Annotated[
    str | None,
    typer.Option("--address", help="Ray cluster address (default: start a local Ray runtime)"),
]


def _jobs(value: int) -> int:
    """``--jobs``: a count, or -1 for every core.  Below -1, joblib would count back from the
    cores (-2: all but one) and past them give 1, silently: refused, with status 2, as is 0
    (refused later by the run as 'jobs must be ...', not naming the option)."""
    if value < -1 or value == 0:
        raise typer.BadParameter(
            f"{value} is neither a count of processes (1 to {MAX_JOBS}) nor -1 (every core); "
            "give the count you mean",
            param_hint="'--jobs'",
        )
    return value


Jobs = Annotated[
    int,
    typer.Option(
        "--jobs",
        "-j",
        max=MAX_JOBS,
        callback=_jobs,
        help=f"parallel runs (-1: every core; at most {MAX_JOBS})",
    ),
]
Trials = typer.Option(min=1, max=MAX_TRIALS, help="executed actions per run")
Seed = typer.Option(min=0, max=MAX_SEED, help="study seed")
TableFormat = Annotated[str, typer.Option("--table", help="run table file: csv, csv.gz or parquet")]
#: the finished runs of a study that has not finished (in --out): removed when every run has
PARTIAL = "runs.partial.csv"
Resume = Annotated[
    bool,
    typer.Option(
        "--resume",
        help=f"continue the study that stopped, from the finished runs in OUT/{PARTIAL}: "
        "they are kept and the other runs run (give the options that wrote it; a file of "
        "another study is refused)",
    ),
]
Partial = Annotated[
    Path | None,
    typer.Option(
        "--partial",
        help="JSON-lines file each finished run is written to as it finishes, kept when a run "
        "fails (default: a new file in the temporary folder); removed when every run finishes "
        "(bench continuous, population: --resume continues from it)",
    ),
]
BenchResume = Annotated[
    bool,
    typer.Option(
        "--resume",
        help="continue the bench that stopped, from the finished runs in its --partial "
        "file: they are kept and the other runs run (give the options that wrote it; a "
        "file of another bench is refused)",
    ),
]
T = TypeVar("T")


def _split(values: list[str] | None, option: str) -> list[str] | None:
    """The names given (repeated or comma-separated), None when the option was not given; given
    but naming none (``--settings ,``) is refused, not taken for the default."""
    if not values:
        return None
    names = [v.strip() for item in values for v in item.split(",") if v.strip()]
    if not names:
        given = " ".join(f"{option} {v!r}" for v in values)
        raise ValueError(f"{option} names nothing ({given}); leave it out for the default")
    return names


def _integers(text: str, option: str) -> list[int]:
    try:
        numbers = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ValueError(f"{option} must be comma-separated integers, got {text!r}") from None
    if not numbers:
        raise ValueError(f"{option} must be comma-separated integers, got none in {text!r}")
    return numbers


def _execution(backend: str, jobs: int, address: str | None) -> SweepBackend:
    """``--backend``, checked with ``--jobs`` and ``--address`` before the output folder is made
    (refused by the run itself, they left an empty ``--out`` folder)."""
    from gaitpref.simulate.sweep import BACKENDS, check_backend, probe_address, resolve_jobs

    if backend not in BACKENDS:
        fail(f"--backend must be one of {', '.join(BACKENDS)}, got {backend!r}")

    def check() -> None:
        try:
            check_backend(backend, address)
        except RuntimeError as exc:  # Ray not installed
            fail(f"--backend {backend}: {exc}")
        if backend == "ray" and address is not None:
            try:  # a HOST:PORT where nothing listens
                probe_address(address)
            except RuntimeError as exc:
                fail(f"--address: {exc}")
        resolve_jobs(jobs)

    guard(check)
    return backend


def _run(
    study: Study,
    backend: SweepBackend,
    jobs: int,
    address: str | None,
    out: Path,
    resume: bool = False,
    made: bool = False,
) -> StudyResult:
    """Run ``study``; each finished run is kept in ``OUT/runs.partial.csv`` until every run has
    finished (then the file is removed), so a run that fails loses none of the others;
    ``resume``: the runs already in that file are kept and only the others run; ``made``: this
    command made ``out`` (removed, when still empty, after an interrupt before any run
    finished)."""
    from gaitpref.simulate.sweep import run_study

    partial = out / PARTIAL
    with _warnings_shown():
        return _stopping(
            lambda: run_study(
                study, backend, jobs, address, progress=True, console=_console, partial=partial,
                resume=resume,
            ),
            partial,
            "the same command with --resume continues the study from them",
            out=out,
            made=made,
        )  # fmt: skip


@contextmanager
def _warnings_shown() -> Iterator[None]:
    """A resumed sweep's warnings (lines of its partial file dropped) printed as
    ``warning: ...`` as they come, not as Python's ``file:line: Warning`` lines."""
    import warnings

    from rich.markup import escape

    from gaitpref.simulate.resume import PartialRunsWarning

    shown = warnings.showwarning

    def show(
        message: Warning | str,
        category: type[Warning],
        filename: str,
        lineno: int,
        file: TextIO | None = None,
        line: str | None = None,
    ) -> None:
        if issubclass(category, PartialRunsWarning):
            _console.print(f"[yellow]warning:[/yellow] {escape(str(message))}", markup=True)
        else:
            shown(message, category, filename, lineno, file, line)

    with warnings.catch_warnings():
        warnings.simplefilter("always", PartialRunsWarning)
        warnings.showwarning = show
        yield


@contextmanager
def _keeping(result: StudyResult, out: Path) -> Iterator[None]:
    """Write a finished study's files; when one cannot be written (a full disk, a folder made
    at its name meanwhile), keep the run table in ``OUT/runs.partial.csv`` and exit with
    status 1 saying so (a traceback before, and every run's result lost)."""
    from gaitpref.simulate.resume import write_partial

    try:
        yield
    except OSError as exc:
        what = f"{exc.strerror or exc}" + (f": {exc.filename}" if exc.filename else "")
        kept = out / PARTIAL
        try:
            with open(kept, "x", encoding="utf-8"):  # never over an earlier study's runs
                pass
            write_partial(kept, result.study, result.table)  # --resume writes the files
            where = f"the run table is kept in {kept}: the same command with --resume writes them"
        except OSError as again:
            where = f"nor could the run table be kept in {kept} ({again.strerror or again})"
        fail(f"the study finished but its results could not be written ({what}); {where}", 1)


def _stopping(
    sweep: Callable[[], T],
    partial: Path,
    resume: str = "",
    out: Path | None = None,
    made: bool = False,
) -> T:
    """``sweep()``: a run that failed (:class:`~gaitpref.simulate.partial.RunError`, naming the
    run and where the finished runs are) exits with status 1, a computation that could not
    finish; refused input as :func:`report` says; an interrupt (Ctrl-C) after some run finished
    exits with status 130 naming ``partial``, where they are (it said nothing, and a bench's
    file is a new name in the temporary folder), and before any run finished with status 130
    saying that nothing was kept or written (it said nothing); ``out``: the study's folder,
    removed then if this command ``made`` it and it is still empty.  ``resume``: how the
    command continues from ``partial`` (``--resume``), said after either when the file is
    there."""
    from gaitpref.simulate.partial import RunError

    def kept() -> str:
        return f"; {resume}" if resume and partial.is_file() else ""

    try:
        return sweep()
    except KeyboardInterrupt:
        if partial.exists():
            fail(f"interrupted; the runs that finished are in {partial}{kept()}", 130)
        fail(
            f"interrupted before any run finished: nothing was kept or written{_left(out, made)}",
            130,
        )
    except RunError as exc:
        fail(f"{exc}{kept()}", 1)
    except HANDLED as exc:
        report(exc)
    except RuntimeError as exc:  # a Ray runtime that cannot start (before any run)
        removed = "" if partial.exists() else _removed(out, made)
        fail(f"{str(exc).rstrip('.')}{removed}" if removed else str(exc))


def _partial(given: Path | None, command: str, resume: bool = False) -> Path:
    """Where a bench keeps its finished runs: ``--partial``, else a new name in the temporary
    folder (not made until the runs start: a bench refused before leaves no file); ``resume``:
    ``--partial``, a file that exists."""
    if resume:
        if given is None:
            fail("--resume needs --partial FILE: the file the bench that stopped kept its runs in")
        if not given.is_file():
            fail(f"--resume: --partial {str(given)!r} is not a file, no runs to resume from")
        return given
    if given is not None:  # opened for writing, and removed once every run has finished
        if given.exists() or given.is_symlink():  # was truncated, then removed (/dev/null too)
            fail(
                f"--partial {str(given)!r} already exists: give a new file name (the file is "
                "written afresh and removed once every run has finished), or --resume to "
                "continue the bench that stopped (bench continuous, population)"
            )
        if not given.parent.is_dir():
            fail(f"--partial {str(given)!r}: no folder {str(given.parent)!r} to write it in")
        return given
    name = f"gaitpref-bench-{command}-{secrets.token_hex(4)}.partial.jsonl"
    return Path(tempfile.gettempdir()) / name


#: a study's run table in every format ``--table`` writes (a rerun in another format left the
#: earlier table beside the new curves)
RUN_TABLES = ("runs.csv", "runs.csv.gz", "runs.parquet")


def _outputs(
    out: Path, names: tuple[str, ...], rebuilt: tuple[str, ...] = (), resume: bool = False
) -> None:
    """Refuse, before any run, an ``--out`` holding :data:`PARTIAL` (the finished runs of a
    study that stopped: a new study wrote over it, then removed it) unless ``resume``, and
    one without it when ``resume``; a folder where one of the study's files ``names`` or
    ``rebuilt`` goes (the study ran, then died writing it, its results lost), or, unless
    ``resume`` (the stopped study's own files, when it finished but could not write them all),
    an earlier study's results there (``names`` or a run table: written over without a word, a
    quick test with the default ``--out`` replaced a study of hours); ``rebuilt`` files (a gait
    library built from the config) may be made again."""
    kept = out / PARTIAL
    if resume and not kept.is_file():
        fail(
            f"--resume: --out {str(out)!r} holds no {PARTIAL} (the finished runs of a study "
            "that stopped) to resume from; leave --resume out to run the study"
        )
    if not resume and (kept.exists() or kept.is_symlink()):
        fail(
            f"--out {str(out)!r} holds {PARTIAL}, the finished runs of a study that stopped "
            "(gaitpref.simulate.read_table reads it): give --resume (and the options that "
            "wrote it) to continue that study, or move it away or give another --out; a new "
            "study would write over it"
        )
    for name in (*names, *rebuilt):
        if (out / name).is_dir():
            fail(f"--out {str(out)!r}: {name} is a folder, where the study writes its {name}")
    if resume:  # a study that finished but could not write every file (_keeping) wrote some
        return
    earlier = [n for n in dict.fromkeys((*RUN_TABLES, *names)) if (out / n).exists()]
    if earlier:
        fail(
            f"--out {str(out)!r} holds an earlier study's results ({', '.join(earlier)}): give "
            "another --out, or move them away; a new study would write over them"
        )


def _folder(out: Path) -> bool:
    """Make the output folder before any run, or fail naming ``--out`` (a traceback before);
    whether this call made it (it was not there)."""
    if out.exists() and not out.is_dir():
        fail(f"--out {str(out)!r} is a file, not a folder")
    made = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        fail(f"--out {str(out)!r}: cannot make the output folder ({exc.strerror or exc})")
    return made


def _kept(result: StudyResult) -> str:
    """The runs a ``--resume`` kept, which did not run in ``result.seconds``."""
    return f" ({result.kept} kept from {PARTIAL})" if result.kept else ""


def _removed(out: Path | None, made: bool) -> str:
    """After a failure before any run: ``out`` removed if this command ``made`` it and it is
    still empty (``--address auto`` with no cluster left an empty folder), said; else nothing."""
    if out is None or not made:
        return ""
    try:
        out.rmdir()
    except OSError:  # not empty (a gait library built first), or gone
        return ""
    return f"; --out {str(out)!r}, made by this command, was removed"


def _left(out: Path | None, made: bool) -> str:
    """After an interrupt before any run finished: what became of ``out`` (removed if this
    command ``made`` it and it is empty; its parents, made too, are left)."""
    if out is None:
        return ""
    return _removed(out, made) or f"; --out {str(out)!r} is left as it was"


#: The most ``--notes`` a summary takes: read whole, ``/dev/zero`` was a MemoryError traceback.
MAX_NOTES_BYTES = 1_000_000


def _notes(notes: Path | None) -> str:
    """The ``--notes`` file's text (at most :data:`MAX_NOTES_BYTES`; a pipe is read too), or
    fail naming it."""
    if notes is None:
        return ""
    try:
        with notes.open("rb") as file:
            data = file.read(MAX_NOTES_BYTES + 1)
        if len(data) > MAX_NOTES_BYTES:
            fail(f"--notes {str(notes)!r} is larger than {MAX_NOTES_BYTES // 1_000_000} MB")
        return data.decode("utf-8")
    except UnicodeDecodeError:
        fail(f"--notes {str(notes)!r} is not UTF-8 text")
    except OSError as exc:
        fail(f"--notes {str(notes)!r} cannot be read ({exc.strerror or exc})")


def _table_path(out: Path, fmt: str) -> Path:
    from gaitpref.simulate.tables import check_table_path

    if fmt not in ("csv", "csv.gz", "parquet"):
        fail(f"--table must be csv, csv.gz or parquet, got {fmt!r}")
    path = out / f"runs.{fmt}"
    try:  # before the study runs: Parquet without pyarrow failed after it, writing nothing
        check_table_path(path)
    except RuntimeError as exc:
        fail(f"--table {fmt}: {exc}")
    return path


def _bench_config(source: str) -> ExperimentConfig:
    """A bench's config, with a new session's check of its largest draw against the sampling
    budget (``config/draws.py``): refused before any run, naming the key, rather than as every
    run's failure."""
    from gaitpref.config import check_draws, load_config

    cfg = load_config(source)
    checked_config(source, cfg, check_draws)
    return cfg


@bench_app.command("paper-2d")
def paper_2d(
    runs: Annotated[
        int,
        typer.Option(min=1, max=PAPER_OBJECTIVES, help="runs per setting; run k uses objective k"),
    ] = PAPER_OBJECTIVES,
    trials: Annotated[int, Trials] = 150,
    settings: Annotated[
        list[str] | None,
        typer.Option(help="settings (repeat or comma-separate; default: all six)"),
    ] = None,
    baseline: Annotated[bool, typer.Option(help="add random selection as a floor")] = True,
    backend: Backend = "joblib",
    address: Address = None,
    jobs: Jobs = -1,
    seed: Annotated[int, Seed] = 0,
    out: Annotated[Path, typer.Option(help="output folder")] = Path("out/paper-2d"),
    table: TableFormat = "csv",
    notes: Annotated[
        Path | None, typer.Option(help="markdown file appended to summary.md as Notes")
    ] = None,
    resume: Resume = False,
) -> None:
    """The paper's Figure 4 study on the authors' 100 objectives, beside the published curves."""
    from gaitpref.simulate.paper2d import paper_2d_study, published_curves
    from gaitpref.simulate.report import MachineInfo, load_average, paper_2d_summary
    from gaitpref.simulate.tables import write_curves, write_table

    study = guard(
        lambda: paper_2d_study(runs, trials, _split(settings, "--settings"), baseline, seed)
    )
    note_text = _notes(notes)
    table_path = _table_path(out, table)
    _outputs(out, (table_path.name, "curves.csv", "curves.png", "summary.md"), resume=resume)
    checked = _execution(backend, jobs, address)
    made = _folder(out)
    load_before = load_average()
    result = _run(study, checked, jobs, address, out, resume, made)
    from gaitpref.simulate.figures import plot_paper_2d  # matplotlib: only when drawing

    published = published_curves()
    with _keeping(result, out):
        write_table(result.table, table_path)
        write_curves(result.curves, out / "curves.csv")
        plot_paper_2d(result.curves, published, out / "curves.png")
        summary = paper_2d_summary(result, published, MachineInfo.now(load_before), note_text)
        (out / "summary.md").write_text(summary, encoding="utf-8")
    console.print(
        f"{plural(len(study), 'run')}{_kept(result)} in {result.seconds:.1f} s ({result.backend}, "
        f"{plural(result.jobs, 'job')}); wrote {out}/curves.csv, {table_path.name}, curves.png, "
        "summary.md"
    )


@bench_app.command("compass-gait")
def compass_gait(
    objective: Annotated[
        str, typer.Option(help="poly: the authors' COT polynomial; hzd: a gait library's COT")
    ] = "poly",
    library: Annotated[
        Path | None,
        typer.Option(
            help="--objective hzd: a saved gait library (.json) or a .csv/.npz export "
            "(default: build one on the grid at 0.2 m/s, saved as OUT/gait-library.json)"
        ),
    ] = None,
    runs: Annotated[int, typer.Option(help=f"seeded runs per setting (1 to {MAX_RUNS})")] = 100,
    trials: Annotated[int, Trials] = 60,
    iterations: Annotated[
        str, typer.Option(help="iteration counts for the posterior panels")
    ] = "1,5,10,20",
    baseline: Annotated[bool, typer.Option(help="add random selection as a floor")] = True,
    backend: Backend = "joblib",
    address: Address = None,
    jobs: Jobs = -1,
    seed: Annotated[int, Seed] = 0,
    out: Annotated[Path, typer.Option(help="output folder")] = Path("out/compass-gait"),
    table: TableFormat = "csv",
    resume: Resume = False,
) -> None:
    """The paper's Figure 2 study: CoSpar (n = 2, b = 0) finds the step length of lowest COT."""
    from rich.markup import escape

    from gaitpref.simulate.compass import (
        compass_gait_study,
        compass_objective,
        posterior_snapshots,
    )
    from gaitpref.simulate.sweep import resolve_jobs
    from gaitpref.simulate.tables import write_curves, write_table

    table_path = _table_path(out, table)  # before a gait library is built
    rebuilt = ("gait-library.json",) if objective == "hzd" and library is None else ()
    _outputs(out, (table_path.name, "curves.csv", "posterior.png"), rebuilt, resume)
    checked = _execution(backend, jobs, address)
    made = False  # this command made --out (before a gait library is built into it)
    try:
        its = _integers(iterations, "--iterations")
        if len(set(its)) > MAX_SNAPSHOTS or max(its) > MAX_TRIALS:  # a panel each, replayed
            raise ValueError(
                f"--iterations: at most {MAX_SNAPSHOTS} counts, each at most {MAX_TRIALS}, "
                f"got {iterations!r}"
            )
        if min(its) < 0:  # refused by the replay after a gait library was built, unnamed
            raise ValueError(f"--iterations must be counts >= 0, got {iterations!r}")
        if not 1 <= runs <= MAX_RUNS:  # as compass_gait_study says, but before a build
            raise ValueError(f"--runs must be 1 to {MAX_RUNS}, got {runs}")
        arms = 2 if baseline else 1  # the study's settings; refused before a library is built
        if arms * runs * trials > MAX_STUDY_TRIALS:
            raise ValueError(
                f"{arms} settings x --runs {runs} x --trials {trials} is {arms * runs * trials} "
                f"trials, more than {MAX_STUDY_TRIALS}; give fewer runs or trials"
            )
        if objective not in ("poly", "hzd"):
            raise ValueError(f"--objective must be 'poly' or 'hzd', got {objective!r}")
        build = objective == "hzd" and library is None
        if build:
            made = _folder(out)
            _console.print("building HZD gaits at 0.2 m/s on the 24 step lengths ...")
        obj = compass_objective(
            objective,  # type: ignore[arg-type]
            library,
            build_jobs=resolve_jobs(jobs),
            save_library=out / "gait-library.json" if build else None,
        )
        study = compass_gait_study(obj, runs, trials, baseline, seed)
        snapshots = posterior_snapshots(study, its)
    except ValueError as exc:
        report(exc)
    if obj.note:
        _console.print(f"[yellow]note:[/yellow] {escape(obj.note)}", markup=True)
    made = _folder(out) or made
    result = _run(study, checked, jobs, address, out, resume, made)
    from gaitpref.simulate.figures import plot_compass_gait  # matplotlib: only when drawing

    with _keeping(result, out):
        write_table(result.table, table_path)
        write_curves(result.curves, out / "curves.csv")
        plot_compass_gait(
            obj.space.features[0].array,
            obj.cot,
            snapshots,
            out / "posterior.png",
            result.curves,
            obj.label,
        )
    built = ", gait-library.json" if rebuilt else ""  # it was saved, and said nowhere
    console.print(
        f"{plural(len(study), 'run')}{_kept(result)} in {result.seconds:.1f} s ({result.backend}, "
        f"{plural(result.jobs, 'job')}); wrote {out}/curves.csv, {table_path.name}, posterior.png"
        f"{built}"
    )


@bench_app.command("population")
def population(
    objectives: Annotated[
        Path,
        typer.Option(help=".npy file: one utility grid per subject (S x grid), higher is better"),
    ],
    trials: Annotated[
        int, typer.Option(min=1, max=MAX_TRIALS, help="executed trials per subject")
    ] = 20,
    config: Annotated[str, typer.Option(help="config file or shipped name")] = "synthetic-2d",
    jobs: Jobs = 1,
    seed: Annotated[int, Seed] = 0,
    tolerance: Annotated[float, typer.Option(help="'within' as a fraction of the range")] = 0.05,
    user_noise: Annotated[
        float,
        typer.Option(
            min=0.0,
            help="the simulated subjects' probit noise, in the objectives' units (0: noiseless)",
        ),
    ] = 0.0,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    partial: Partial = None,
    resume: BenchResume = False,
) -> None:
    """Each subject held out in turn: cold, then warm-started from the others (same seeds)."""
    import json

    import numpy as np
    from rich.progress import TaskID

    from gaitpref.cli.main import progress_bar
    from gaitpref.cli.points import check_noise
    from gaitpref.simulate.population import population_bench

    guard(lambda: check_noise(user_noise, "--user-noise"))  # inf passed the option's min=0
    arr = read_array(objectives, "objectives file")
    cfg = guard(lambda: _bench_config(config))
    kept = _partial(partial, "population", resume)

    # each subject's cold run, then its warm one: it said nothing till the end (minutes)
    bar = progress_bar(shown=not as_json)
    tasks: list[TaskID] = []

    def shown(done: int) -> None:  # first called once the input is checked: no bar before
        if not tasks:
            bar.start()
            subjects = len(arr)
            tasks.append(bar.add_task(f"{subjects} subjects, cold and warm", total=2 * subjects))
        bar.update(tasks[0], completed=done)

    def run() -> dict[str, object]:
        return population_bench(
            cfg, arr, trials, seed=seed, jobs=jobs, tolerance=tolerance, user_noise=user_noise,
            partial=kept, resume=resume, progress=shown,
        )  # fmt: skip

    try:
        with _warnings_shown():
            result = _stopping(
                run,
                kept,
                f"the same command with --partial {str(kept)!r} --resume continues the bench "
                "from them",
            )
    finally:
        bar.stop()
    if as_json:
        typer.echo(json.dumps(result))
        return
    subjects = result["subjects"]
    assert isinstance(subjects, list)
    parts = [("1-10", (0, 10))] if trials > 10 else []
    for part, (lo, hi) in [*parts, (f"1-{trials}", (0, trials))]:
        cold = np.mean([np.mean(s["cold"][lo:hi]) for s in subjects])
        warm = np.mean([np.mean(s["warm"][lo:hi]) for s in subjects])
        console.print(f"trials {part}: cold {cold:.3f}, warm {warm:.3f} ({warm - cold:+.3f})")


@bench_app.command("continuous")
def continuous(
    config: Annotated[str, typer.Argument(metavar="CONFIG", help="config file or shipped name")],
    objective: Annotated[
        str,
        typer.Option(
            help="PATH.py:NAME (a function of an m x d array of points returning m utilities), "
            "hartmann6 or random-gp[:SEED] (random-gp alone: run k draws objective k)"
        ),
    ],
    runs: Annotated[int, typer.Option(min=1, max=MAX_RUNS, help="runs (seeds 0..runs-1)")] = 5,
    trials: Annotated[
        int, typer.Option(min=1, max=MAX_TRIALS, help="executed trials per run")
    ] = 150,
    coactive: Annotated[bool, typer.Option(help="simulate coactive suggestions")] = False,
    noise: Annotated[float, typer.Option(help="the subject's probit noise")] = 0.0,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    partial: Partial = None,
    resume: BenchResume = False,
) -> None:
    """A sweep over seeds against an objective over points (on the grid or the line path):
    the learning curve and the final best point's objective, mean and standard error."""
    import json

    import numpy as np

    from gaitpref.cli.main import progress_bar
    from gaitpref.cli.points import bench_points, check_bench_points, run_record

    cfg = guard(lambda: _bench_config(config))
    kept = _partial(partial, "continuous", resume)
    # refused before the bar shows; the objective's own prints kept off the JSON
    with json_only(as_json):
        checked = guard(
            lambda: check_bench_points(cfg, objective, runs, trials=trials, noise=noise)
        )
    with (
        json_only(as_json),
        progress_bar(shown=not as_json) as bar,  # it said nothing till the end
        _warnings_shown(),
    ):
        task = bar.add_task(plural(runs, "run"), total=runs * trials)
        results = _stopping(
            lambda: bench_points(
                cfg, objective, runs, trials=trials, coactive=coactive, noise=noise,
                progress=lambda done: bar.update(task, completed=done),
                partial=kept, checked=checked, resume=resume,
            ),
            kept,
            f"the same command with --partial {str(kept)!r} --resume continues the bench from "
            "them",
        )  # fmt: skip
    curves = np.array([r.curve[:trials] for r in results])
    best = np.array([r.best_objective for r in results])
    out = {
        "config": cfg.name,
        "objective": objective,
        "path": cfg.subspace,
        "runs": [run_record(k, r) for k, r in enumerate(results)],
        "mean_curve": curves.mean(axis=0).tolist(),
        "best_objective_mean": float(best.mean()),
        "best_objective_se": float(best.std(ddof=1) / np.sqrt(runs)) if runs > 1 else 0.0,
    }
    if as_json:
        typer.echo(json.dumps(out))
        return
    for lo, hi in [(1, 10), (11, 50), (51, 100), (101, trials)]:
        if lo <= trials:
            console.print(f"trials {lo}-{min(hi, trials)}: {curves[:, lo - 1 : hi].mean():.4g}")
    console.print(
        f"final best point's objective: {out['best_objective_mean']:.4g} "
        f"+- {out['best_objective_se']:.2g} (SE, {plural(runs, 'run')}, {cfg.subspace} path)"
    )


if __name__ == "__main__":  # python -m gaitpref.cli.simulate
    bench_app()
