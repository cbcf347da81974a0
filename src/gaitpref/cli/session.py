"""``gaitpref session ...`` and ``gaitpref db ...``: thin commands over the Session API.

Every command takes ``--db URL`` (default: ``$GAITPREF_DB``, else ``sqlite:///gaitpref.db`` in the
working directory; a bare path means a SQLite file).  Errors name the problem and exit with
status 2; nothing is written when a command fails, but for one case, which exits with status 1:
an undo (``session undo``, ``session validate --withdraw --undo``) that is written, whose query,
withdrawn (it proposed a gait flagged unsafe since), could not be replaced (the database failed
to write the new query, ...): the command says what was written, then the error.
"""

from __future__ import annotations

import json
import shlex
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn

import typer

from gaitpref.cli.output import (
    HANDLED,
    check_file_out,
    console,
    err_console,
    fail,
    guard,
    report,
    reported,
)
from gaitpref.limits import MAX_SEED
from gaitpref.wording import plural

if TYPE_CHECKING:
    from gaitpref.sessions import Session
    from gaitpref.sessions.records import SessionQuery, Trial
    from gaitpref.storage import SessionRecord

session_app = typer.Typer(
    name="session", help="Experiment sessions with real subjects.", no_args_is_help=True
)
db_app = typer.Typer(name="db", help="The session database.", no_args_is_help=True)


def _kept_db(db: str | None) -> str | None:
    """``--db`` (or ``$GAITPREF_DB``), refused naming the option when it is an in-memory
    database (``memory://``, ``sqlite:///:memory:``, and ``sqlite://`` or ``sqlite:///`` with no
    path, as ``sqlite:///$UNSET`` gives): every command runs in a process of its own, so what it
    wrote was gone when it ended, though ``session new`` printed the id and how to run it."""
    from sqlalchemy.engine import make_url
    from sqlalchemy.exc import ArgumentError

    from gaitpref.storage import resolve_url

    url = resolve_url(db)
    memory = url == "memory://"
    if not memory:
        try:
            parsed = make_url(url)
        except (ArgumentError, ValueError):  # refused, naming it, when the command opens it
            # ValueError: a port that is not a number (a traceback, before)
            return db
        memory = parsed.get_backend_name() == "sqlite" and parsed.database in (None, "", ":memory:")
    if memory:
        given = "--db" if db else "$GAITPREF_DB"
        raise typer.BadParameter(
            f"{url!r} is an in-memory database: what the command writes would be gone when it "
            "ends; give a database file (e.g. --db lab.db or sqlite:///lab/gaitpref.db)",
            param_hint=f"'{given}'",
        )
    return db


DbOption = Annotated[
    str | None,
    typer.Option(
        "--db",
        help="Database URL or SQLite path (default: $GAITPREF_DB, else ./gaitpref.db).",
        callback=_kept_db,
    ),
]
IdArgument = Annotated[
    int, typer.Argument(metavar="ID", help="The session's id (see `gaitpref session list`).")
]
YesOption = Annotated[
    bool, typer.Option("--yes", "-y", help="Do not ask for confirmation (for scripts).")
]


@contextmanager
def _opened(db: str | None, session_id: int) -> Iterator[Session]:
    from gaitpref.sessions import Session

    session = guard(lambda: Session.open(db, session_id))
    try:
        yield session
    finally:
        session.close()


def _confirm(question: str, yes: bool) -> None:
    """Ask ``question`` (y/N) unless ``--yes`` was given; exit 1 with nothing done on no.

    The question and the answer's outcome go to stderr: on stdout a script capturing the
    output (``out=$(gaitpref session finish 3)``) hid the question, and the command seemed to
    hang.  A stdin that ends before an answer (``</dev/null``, a closed pipe) is a no, said so
    with how to skip the question (it printed click's bare ``Aborted!``)."""
    if yes:
        return
    import sys

    while True:  # the question on stderr, as typed (typer.confirm put its last space on stdout)
        typer.echo(f"{question} [y/N]: ", nl=False, err=True)
        try:
            line, typed = sys.stdin.readline(), sys.stdin.isatty()
        except (AttributeError, OSError, ValueError):  # no stdin at all (closed: `<&-`)
            line, typed = "", False
        if not line or not typed:  # a typed answer ended the line; a piped one did not
            typer.echo(err=True)
        if not line:  # the end of stdin: no answer will come
            err_console.print(
                "no answer (stdin ended): nothing done; give --yes to skip the question"
            )
            raise typer.Exit(1)
        answer = line.strip().lower()
        if answer in ("y", "yes", "n", "no", ""):
            break
        typer.echo("answer y or n", err=True)
    if answer not in ("y", "yes"):
        err_console.print("nothing done")
        raise typer.Exit(1)


def _shown_db(db: str) -> str:
    """``db`` for a command printed to be typed again, shell-quoted, its password (if any)
    shown as ``***``: the hints of ``session new`` and the terminal runner printed the
    PostgreSQL password in the URL as it was given."""
    from gaitpref.storage.sql import masked_url

    return shlex.quote(masked_url(db) if "://" in db else db)


def _resume_hint(session_id: int, db: str | None) -> str:
    return f"gaitpref session run {session_id}" + (f" --db {_shown_db(db)}" if db else "")


def _flag_hint(session_id: int, db: str | None) -> Callable[[int, str], str]:
    """The command that flags a trial unsafe, given its number and the reason (shell-quoted)."""

    def command(trial: int, reason: str) -> str:
        where = f" --db {_shown_db(db)}" if db else ""
        return f"gaitpref session unsafe {session_id} {trial} --reason {shlex.quote(reason)}{where}"

    return command


# -- db ----------------------------------------------------------------------------------------
@db_app.command("upgrade")
def db_upgrade(
    db: DbOption = None,
    no_backup: Annotated[
        bool,
        typer.Option(
            "--no-backup",
            help="Do not first back a SQLite file that needs migrating up beside it "
            "(NAME.before-REVISION.bak).",
        ),
    ] = False,
) -> None:
    """Create the database, or migrate it to the schema this gaitpref writes."""
    from gaitpref.storage import migrate, resolve_url
    from gaitpref.storage.sql import backup_before_upgrade, upgrade_database

    url = resolve_url(db)  # not in memory (refused by --db's check)
    if not no_backup:
        saved = guard(lambda: backup_before_upgrade(url))
        if saved is not None:
            console.print(
                f"backed up to {saved.path} before migrating (schema revision {saved.revision}, "
                f"{plural(saved.sessions, 'session')}, {plural(saved.events, 'event')})"
            )
    shown = guard(lambda: upgrade_database(url))
    console.print(f"{shown}: schema revision {migrate.head_revision()} (the newest)")


@db_app.command("status")
def db_status(db: DbOption = None) -> None:
    """Show the database's URL, schema revision and number of sessions."""
    from gaitpref.storage import resolve_url
    from gaitpref.storage.sql import database_status

    # missing, interrupted upgrade, needs upgrade, newer, or its revision and counts
    console.print(guard(lambda: database_status(resolve_url(db))))


@db_app.command("backup")
def db_backup(
    out: Annotated[Path, typer.Argument(metavar="OUT", help="The copy: a new file.")],
    db: DbOption = None,
) -> None:
    """Copy a SQLite database to OUT, consistently even while it is written, and verify it."""
    from gaitpref.storage import resolve_url
    from gaitpref.storage.sql import backup_database

    saved = guard(lambda: backup_database(resolve_url(db), out))
    console.print(
        f"backed up to {saved.path}: schema revision {saved.revision}, "
        f"{plural(saved.sessions, 'session')}, {plural(saved.events, 'event')} (verified)"
    )


@db_app.command("check")
def db_check(
    as_json: Annotated[
        bool,
        typer.Option(
            "--json",
            help="One JSON object per session and line: id, subject, config, events, status, "
            "ok, error, error_type.",
        ),
    ] = False,
    db: DbOption = None,
) -> None:
    """Replay every session with this gaitpref, writing nothing; exit 1 if any fails.

    Run it after upgrading gaitpref or restoring a backup, before the next subject walks.
    """
    from gaitpref.cli.main import progress_bar
    from gaitpref.sessions.check import check_database
    from gaitpref.storage import resolve_url

    failed = total = 0
    with reported(), progress_bar(transient=True) as bar:
        task = bar.add_task("replaying sessions", total=None)
        for result in check_database(resolve_url(db), lambda n: bar.update(task, total=n)):
            total += 1
            failed += not result.ok
            bar.advance(task)
            if as_json:
                typer.echo(json.dumps(result.as_json()))
                continue
            line = (
                f"session {result.id}: subject {result.subject}, {result.config}, "
                f"{plural(result.events, 'event')}, {result.status}: "
            )
            console.print(line + ("OK" if result.ok else f"FAILED ({result.error_type})"))
            if not result.ok:
                console.print(f"  {result.error}".replace("\n", "\n  "))
    if failed:
        err_console.print(
            f"{failed} of {total} sessions do not replay"
            if total != 1
            else "the one session does not replay"
        )
        raise typer.Exit(1)
    if not as_json:
        said = {0: "no sessions to check", 1: "the one session replays"}
        console.print(said.get(total, f"all {total} sessions replay"))


# -- session -----------------------------------------------------------------------------------
@session_app.command("new")
def new(
    config: Annotated[str, typer.Option(help="Config TOML file or shipped config name.")],
    subject: Annotated[str, typer.Option(help="Pseudonymous subject code, e.g. S01.")],
    seed: Annotated[
        int | None, typer.Option(min=0, max=MAX_SEED, help="Seed (default: the config's).")
    ] = None,
    gait_ids: Annotated[
        Path | None,
        typer.Option(help="Text file: one gait id per line, in grid order (a gait library)."),
    ] = None,
    prior_from: Annotated[
        list[str] | None,
        typer.Option(
            "--prior-from",
            help="Warm start from an earlier session id or subject code (repeat for more; "
            "'session:7' or 'subject:07' where digits could be either).",
        ),
    ] = None,
    as_json: Annotated[
        bool,
        typer.Option(
            "--json",
            help="Print one JSON object: id, subject, config, seed, db, prior_from, prior_rho.",
        ),
    ] = False,
    db: DbOption = None,
) -> None:
    """Start a session of SUBJECT with CONFIG; prints its id."""
    from gaitpref.sessions import Session, read_prior_from

    def run() -> Session:
        library = None
        if gait_ids is not None:
            if not gait_ids.is_file():
                what = "is a folder" if gait_ids.is_dir() else "does not exist"
                raise ValueError(f"--gait-ids {str(gait_ids)!r} {what}; give a text file")
            from gaitpref.gaits.library_io import MAX_LIBRARY_BYTES

            with gait_ids.open("rb") as fh:  # read no further than the bound: not held whole
                data = fh.read(MAX_LIBRARY_BYTES + 1)
            if len(data) > MAX_LIBRARY_BYTES:
                raise ValueError(
                    f"--gait-ids {str(gait_ids)!r} is larger than {MAX_LIBRARY_BYTES:,} bytes; "
                    "it was not read"
                )
            try:  # UTF-8, whatever the locale; the error named neither the option nor the file
                text = data.decode("utf-8")
            except UnicodeDecodeError as exc:
                raise ValueError(
                    f"--gait-ids {str(gait_ids)!r} is not UTF-8 text (byte {exc.start}: "
                    f"{exc.reason})"
                ) from None
            library = [ln.strip() for ln in text.splitlines() if ln.strip()]
        for item in prior_from or []:  # an empty one (an unset shell variable) is no warm start
            if not read_prior_from([item]):
                raise ValueError(f"--prior-from {item!r} names no session id or subject code")
        prior = read_prior_from(prior_from or [])
        return Session.create(db, config, subject, seed=seed, library=library, prior_from=prior)

    session = guard(run)
    if as_json:  # for scripts: the id without parsing a sentence
        from gaitpref.sessions.warm import recorded_prior

        info = {
            "id": session.id,
            "subject": session.subject,
            "config": session.config.name,
            "seed": session.seed,
            "db": session.storage.url,  # its password (if any) as ***
            "prior_from": [p.model_dump() for p in recorded_prior(session.record)],
            "prior_rho": session.record.meta.get("prior_rho"),
        }
        session.close()
        typer.echo(json.dumps(info))
        return
    console.print(
        f"session {session.id}: subject {session.subject}, config {session.config.name}, "
        f"seed {session.seed}, in {session.storage.url}",
        markup=False,
    )
    warm = _warm_start_line(session)
    if warm is not None:  # which sessions a subject code named: said before the first trial
        console.print(warm, markup=False)
    console.print(f"run it with: {_resume_hint(session.id, db)}", markup=False)
    session.close()


def _warm_start_line(session: Session) -> str | None:
    """The earlier sessions ``session``'s warm start read, as its row records them (None: a
    cold start): each with its subject and the last of its events read (events it gained since
    are not in this session's model), and the shared fraction ``rho`` learned from them."""
    from gaitpref.sessions.warm import recorded_prior

    prior = recorded_prior(session.record)
    if not prior:
        return None
    read = ", ".join(
        f"session {p.session} ({p.subject}) to event {p.last_seq}" for p in prior[:_WARM_SHOWN]
    )
    if len(prior) > _WARM_SHOWN:  # up to 256: the rest in session show --json
        read += f" and {len(prior) - _WARM_SHOWN} more (session show --json lists them)"
    rho = session.record.meta.get("prior_rho")
    shared = f"; rho {rho:.2f}" if isinstance(rho, float) else ""
    return f"warm-started from {plural(len(prior), 'earlier session')}: {read}{shared}"


#: the earlier sessions a warm start's line names one by one (a subject code may name 256)
_WARM_SHOWN = 12


@session_app.command("run")
def run_session(session_id: IdArgument, db: DbOption = None) -> None:
    """The interactive loop: show each trial, ask the answer, confirm, write (u undo, q pause
    and quit; inside a blind validation round u withdraws it)."""
    from gaitpref.terminal import run_terminal

    with _opened(db, session_id) as session:
        guard(
            lambda: run_terminal(
                session,
                console,
                resume=_resume_hint(session_id, db),
                flag_with=_flag_hint(session_id, db),
            )
        )


@session_app.command("validate")
def validate(
    session_id: IdArgument,
    ranking: Annotated[
        str | None, typer.Option(help="The subject's ranking, best first (e.g. BCA).")
    ] = None,
    gaits: Annotated[
        str | None,
        typer.Option(
            help="With --ranking: the round's gait names as shown, in the shown order, "
            "comma-separated (the display of the round prints the command); the ranking is "
            "refused if the open round shows other gaits now (drawn again meanwhile)."
        ),
    ] = None,
    withdraw: Annotated[
        bool,
        typer.Option(
            "--withdraw",
            help="Withdraw the open, unanswered round instead (give --reason); asks first "
            "unless --yes.",
        ),
    ] = False,
    reason: Annotated[
        str, typer.Option(help="With --withdraw: why the round is withdrawn (logged).")
    ] = "",
    undo: Annotated[
        bool,
        typer.Option(
            "--undo",
            help="With --withdraw: also undo the answer after which the [stop] rule opened "
            "the round (a mis-keyed answer); its trial is asked again.",
        ),
    ] = False,
    db: DbOption = None,
    yes: YesOption = False,
) -> None:
    """Blind validation: the max/mean/min gaits in a logged random order, then unblinding
    (--withdraw withdraws the open round instead)."""
    from gaitpref.terminal import run_validation

    if withdraw:
        if ranking is not None or gaits is not None:
            fail("--withdraw withdraws the open round: it takes no --ranking or --gaits")
        if not reason.strip():
            fail("give --reason: why the validation round is withdrawn")
        _withdraw_round(session_id, reason, undo, db, yes)
        return
    if undo or reason:
        fail("--undo and --reason go with --withdraw")
    names = None if gaits is None else _gait_names(gaits, ranking)
    with _opened(db, session_id) as session:
        if ranking is not None:
            of = "" if names is None else f" of {', '.join(names)}"
            _confirm(f"Record the ranking {ranking}{of} for session {session_id}?", yes)

        def record_with(shown: Sequence[str]) -> str:
            return _validate_command(session_id, db, shown)

        guard(
            lambda: run_validation(session, ranking, console, gaits=names, record_with=record_with)
        )


def _withdraw_round(session_id: int, reason: str, undo: bool, db: str | None, yes: bool) -> None:
    """``session validate ID --withdraw``: withdraw the open round (checked, then confirmed)."""
    with _opened(db, session_id) as session:
        plan = session.validation_plan
        if plan is None:
            fail(f"session {session_id} has no open blind validation round: nothing to withdraw")
        number = plan.round
        guard(lambda: session.check_withdraw_validation(number, undo=undo))
        opened = session.validation_rounds()[-1]
        trials = [t.number for t in session.trials() if t.query == opened.opened_after]
        what = f"Withdraw blind validation round {number} of session {session_id}"
        if undo:
            what += (
                f" and undo the answer to trial {', '.join(map(str, trials))}, after which the "
                "[stop] rule opened it"
            )
        _confirm(f"{what}?", yes)
        unproposed: BaseException | None = None
        try:
            pending = session.withdraw_validation(number, reason, undo=undo)
        except HANDLED as exc:
            # written when the round is no longer open: the withdrawal and the undo stand, the
            # query to be proposed in place of the undone one, withdrawn, could not be
            if not undo or any(r.round == number and r.open for r in session.validation_rounds()):
                report(exc)  # nothing was written
            pending, unproposed = None, exc
        console.print(f"validation round {number} withdrawn; its log stays")
        if undo:
            console.print(f"undone: the answer to trial {', '.join(map(str, trials))}")
            if unproposed is not None:
                _say_unproposed(unproposed, session, db)
            _say_undone_withdrawn(pending, opened.opened_after, session, db)


def _gait_names(gaits: str, ranking: str | None) -> list[str]:
    """``--gaits``: the names between commas; refused without ``--ranking`` or with an empty
    name."""
    if ranking is None:
        fail(
            "--gaits checks the ranking given with --ranking: give both (or neither, to show "
            "the round and type its ranking)"
        )
    names = [name.strip() for name in gaits.split(",")]
    if not all(names):
        fail(
            "--gaits names the round's gaits as shown, separated by commas (e.g. G3,G7,G1), "
            f"got {gaits!r}"
        )
    return names


def _validate_command(session_id: int, db: str | None, gaits: Sequence[str]) -> str:
    """The command that records the ranking of the round that showed ``gaits``."""
    where = f" --db {shlex.quote(db)}" if db else ""
    return (
        f"gaitpref session validate {session_id}{where} --gaits "
        f"{shlex.quote(','.join(gaits))} --ranking RANKING"
    )


@session_app.command("list")
def list_sessions(
    subject: Annotated[str | None, typer.Option(help="Only this subject's sessions.")] = None,
    as_json: Annotated[
        bool,
        typer.Option(
            "--json",
            help="Print one JSON array, a session per object: id, subject, config, seed, "
            "status, imported_from, events, created, updated (UTC, ISO 8601).",
        ),
    ] = False,
    db: DbOption = None,
) -> None:
    """List the sessions in the database."""
    # The storage alone (not gaitpref.sessions, which loads the model): `session list` starts
    # quickly, without SciPy's optimizers (tests/cli/test_startup.py).
    from rich.table import Table

    from gaitpref.storage import open_storage

    def run() -> list[SessionRecord]:
        storage = open_storage(db, create=False)
        try:
            return list(storage.list_sessions(subject))
        finally:
            storage.close()

    rows = guard(run)
    if as_json:  # for scripts: the table folds long names at 80 columns off a terminal
        typer.echo(json.dumps([_listed(r) for r in rows]))
        return
    table = Table(title="sessions")
    # times are stored in UTC: the headers say so (the console writes "... UTC" after each)
    # every cell folded onto more lines, never cut with an ellipsis: on 80 columns
    # exo-2d-length-duration and exo-2d-length-width both showed as "exo-2d-le…"
    for col in ("id", "subject", "config", "seed", "status", "events"):
        table.add_column(col, overflow="fold")
    table.add_column("created (UTC)", overflow="fold")
    table.add_column("updated (UTC)", overflow="fold")
    for r in rows:
        table.add_row(
            str(r.id),
            r.subject,
            r.config_name,
            str(r.seed),
            r.status + (f" ({r.origin})" if r.origin else ""),
            str(r.last_seq),
            _utc(r.created_at),
            _utc(r.updated_at),
        )
    console.print(table)


def _listed(record: SessionRecord) -> dict[str, object]:
    """A row of ``session list --json``: ``imported_from`` is the id the session had in the
    database it was exported from (None: not imported), ``events`` the sequence number of its
    last event, the times in UTC (``2026-12-02T14:40:05.123456+00:00``)."""
    from gaitpref.storage.base import as_utc

    origin = record.meta.get("imported_from")
    return {
        "id": record.id,
        "subject": record.subject,
        "config": record.config_name,
        "seed": record.seed,
        "status": record.status,
        "imported_from": origin.get("session_id") if isinstance(origin, dict) else None,
        "events": record.last_seq,
        "created": as_utc(record.created_at).isoformat(),
        "updated": as_utc(record.updated_at).isoformat(),
    }


def _utc(when: datetime) -> str:
    """A stored time in UTC, to the minute (``2026-12-02 14:40``): its column says UTC."""
    from gaitpref.storage.base import as_utc

    return as_utc(when).strftime("%Y-%m-%d %H:%M")


@session_app.command("show")
def show(
    session_id: IdArgument,
    figure: Annotated[
        Path | None,
        typer.Option(
            help="Where to draw the figure, in a folder that exists (default: session-ID.png)."
        ),
    ] = None,
    no_figure: Annotated[bool, typer.Option("--no-figure", help="Print only.")] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    db: DbOption = None,
) -> None:
    """Summarize a session and plot its posterior and trials (as in the paper's figures)."""
    from gaitpref.sessions import posterior_summary
    from gaitpref.sessions.warm import recorded_prior

    if figure is not None and not no_figure:
        check_file_out(figure, "--figure")  # its folder must exist: made by no one but you
    with _opened(db, session_id) as session:
        summary = posterior_summary(session)
        path = None
        if not no_figure:
            from gaitpref.plots.session import save_session_figure

            target = figure or Path(f"session-{session.id}.png")
            path = guard(lambda: save_session_figure(session, target))
        trials = session.trials()
        # the unsafe flags in force (a withdrawn one is gone), each gait named as the terminal,
        # the console and exports name it
        flags = [
            {"trial": trial, "action": action, "gait": session.gait_name(action), "reason": why}
            for trial, (action, why) in sorted(session.unsafe_flags().items())
        ]
        excluded = [t.number for t in trials if t.excluded]
        compared = sum(not c.undone for c in session.comparisons())
        rounds = session.validation_rounds()
        opened_by = {r.round: r.opened_by for r in rounds}
        info = {
            "id": session.id,
            "subject": session.subject,
            "config": session.config.name,
            "seed": session.seed,
            "status": session.status,
            "trials": len(trials),
            "excluded": excluded,
            "comparisons": compared,
            "unsafe": flags,
            "posterior": summary,
            "validations": [
                {
                    "round": v.round,
                    "ranking": "".join(v.ranking),
                    "agrees": v.agrees,
                    "kendall_tau": v.kendall_tau,
                    "opened_by": opened_by.get(v.round),
                }
                for v in session.validations()
            ],
            # every round logged, the open and the withdrawn ones too, as validation_rounds()
            "validation_rounds": [
                {
                    "round": r.round,
                    "opened_by": r.opened_by,
                    "status": "answered" if r.answered else "open" if r.open else "withdrawn",
                    "withdrawn_reason": r.withdrawn,
                }
                for r in rounds
            ],
            "figure": None if path is None else str(path),
            "prior_from": [p.model_dump() for p in recorded_prior(session.record)],
            "prior_rho": session.record.meta.get("prior_rho"),
        }
        if as_json:
            typer.echo(json.dumps(info))
            return
        so_far = _best_so_far(session, summary)
        console.print(
            f"session {session.id}: subject {session.subject}, {session.config.name}, "
            f"seed {session.seed}, {session.status}\n"
            f"{plural(len(trials), 'trial')} ({len(excluded)} excluded), "
            f"{plural(compared, 'comparison')}\n{so_far}"
        )
        warm = _warm_start_line(session)
        if warm is not None:
            console.print(warm, markup=False)
        if flags:
            console.print(
                "flagged unsafe: "
                + "; ".join(f"trial {u['trial']}, gait {u['gait']} ({u['reason']})" for u in flags)
            )
        for v in session.validations():
            console.print(
                f"validation {v.round}: ranking {''.join(v.ranking)}, "
                f"{'agrees' if v.agrees else 'disagrees'}, Kendall's tau {v.kendall_tau:+.2f}"
            )
        if path is not None:
            console.print(f"figure: {path}")


def _best_so_far(session: Session, summary: dict[str, Any]) -> str:
    """The ``best so far`` line of ``session show``: the recommended gait (the highest posterior
    mean among the gaits that may be proposed, as the confidence names it; with gaits made on
    demand under ``[gaits] recommend = "made"``, among the gaits made), never one flagged unsafe
    or in the region of avoidance; the unrestricted highest is named as not to walk when it is
    another."""
    best, rec = summary["argmax"], summary["recommended"]
    if best is None:
        return "best so far: none yet (the line path's posterior lives on the points walked)"
    if not summary["learned"]:  # preference_learned, the console's condition; --json's learned
        return (
            "best so far: none yet (no preference learned yet: every gait is as likely to be "
            "the best)"
        )
    if rec is None:
        why = session.no_recommendation() or (
            "every gait is in the region of avoidance or near a gait flagged unsafe"
        )
        return f"best so far: none may be recommended ({why})"
    line = (
        f"best so far: {session.gait_name(rec)} (action {rec}: {session.space.describe(rec)}), "
        f"posterior mean {summary['mean_at_recommended']:.4g} ± "
        f"{summary['sd_at_recommended']:.2g}"
    )
    if session.gait_made(rec) is False:  # gaits on demand: a point no query proposed
        from gaitpref.sessions.gaits import NOT_MADE

        line += f"\n  ({NOT_MADE})"
    spec = session.config.generator
    made_only = spec is not None and spec.recommends_made
    if best != rec and made_only and session.gait_made(best) is False:
        line += (  # [gaits] recommend = "made": the model's highest is a point not made
            f"\n  (the highest posterior mean, {session.gait_name(best)} (action {best}), is "
            "a point whose gait is not made: only a gait made may be recommended)"
        )
    elif best != rec:
        line += (
            f"\n  (the highest posterior mean, {session.gait_name(best)} (action {best}), may not "
            "be proposed: flagged unsafe, near a gait flagged unsafe, or in the region of "
            "avoidance)"
        )
    return line


@session_app.command("undo")
def undo(session_id: IdArgument, db: DbOption = None, yes: YesOption = False) -> None:
    """Take back the last answer (its trial is asked again); asks first unless --yes."""
    with _opened(db, session_id) as session:
        if session.status == "finished":
            fail(f"session {session_id} is finished: nothing can be undone")
        guard(lambda: session.check_change("undo"))  # nothing to undo: said before the question
        _confirm(f"Undo the last answer of session {session_id}?", yes)

        before: list[Trial] = []

        def undo_last(s: Session) -> tuple[list[Trial], int | None, SessionQuery | None]:
            # the last answer as of the undo: another writer may have answered during the prompt
            before[:] = done = s.trials()
            return done, done[-1].query if done else None, s.undo()

        unproposed: BaseException | None = None
        try:
            done, last, pending = session.read(undo_last, turn=True)
        except HANDLED as exc:
            # written when the answer is no longer in force: the undo stands, the query to be
            # proposed in place of its own, withdrawn, could not be
            last = before[-1].query if before else None
            if last is None or any(t.query == last for t in session.trials()):
                report(exc)  # nothing was written
            done, pending, unproposed = before, None, exc
        trials = ", ".join(str(t.number) for t in done if t.query == last)
        console.print(f"undone: the answer to trial {trials}")
        if unproposed is not None:
            _say_unproposed(unproposed, session, db)
        if session.validation_plan is not None:
            number = session.validation_plan.round
            console.print(
                f"blind validation round {number} stays open (an undo takes back answers only): "
                f"record its ranking, or withdraw it with gaitpref session validate {session_id} "
                "--withdraw --reason TEXT"
            )
        _say_undone_withdrawn(pending, last, session, db)


def _say_unproposed(exc: BaseException, session: Session, db: str | None) -> NoReturn:
    """After an undo that is written (``session undo``, ``session validate --withdraw --undo``)
    whose query, withdrawn, could not be replaced (``exc``: the database failed to write the new
    query, the gait generator failed, or no gait may be proposed): say so and that the next ask
    proposes it, print ``exc`` and exit with status 1, not 2 (which says nothing was written)."""
    from gaitpref.errors import StorageError

    line = (
        "its query proposed a gait flagged unsafe since, or in the region of avoidance now, "
        "and was withdrawn, but "
    )
    if isinstance(exc, StorageError):
        line += (
            "the new query drawn in its place was not written (the error below says why): it is "
            f"proposed at the next ask ({_resume_hint(session.id, db)})"
        )
    else:
        line += "no new query could be proposed in its place (the error below says why)"
    console.print(line, markup=False)
    report(exc, code=1)


def _say_undone_withdrawn(
    pending: SessionQuery | None, undone: int | None, session: Session, db: str | None
) -> None:
    """After an undo of query ``undone``'s answer, whose query is pending again unless it was
    withdrawn (``pending``: what the undo returned): say so, and what is pending in its place;
    none is proposed while the session is paused or a blind validation round is open."""
    if pending is not None and pending.id == undone:
        return
    line = (
        "its query proposed a gait flagged unsafe since, or in the region of avoidance now, "
        "and was withdrawn: "
    )
    if pending is not None:
        console.print(f"{line}a new query is proposed in its place (query {pending.id})")
        return
    until = []
    if session.validation_plan is not None:
        until.append(
            f"blind validation round {session.validation_plan.round} is ranked or withdrawn"
        )
    if session.status == "paused":
        until.append(f"the session is resumed ({_resume_hint(session.id, db)})")
    when = f": the next is proposed once {' and '.join(until)}" if until else ""
    console.print(f"{line}no query is proposed in its place yet{when}", markup=False)


@session_app.command("exclude")
def exclude(
    session_id: IdArgument,
    trial: Annotated[int, typer.Argument(metavar="TRIAL", help="The trial number.")],
    reason: Annotated[
        str,
        typer.Option(
            help="Why (gaitpref.sessions.REASONS, e.g. device_fault; a wrong one lists them all)."
        ),
    ],
    detail: Annotated[str, typer.Option(help="What happened.")] = "",
    db: DbOption = None,
) -> None:
    """Exclude a trial (device fault, stumble, ...): its comparisons leave the model; a
    pending query proposing a gait in the region of avoidance now is withdrawn."""
    with _opened(db, session_id) as session:
        pending, shown = session.pending, session.validation_plan
        guard(lambda: session.exclude(trial, reason.replace("-", "_"), detail))
        console.print(f"trial {trial} excluded ({reason}); the record stays")
        _say_withdrawn(pending, session, "in the region of avoidance of the model without it")
        if shown is not None and session.validation_plan != shown:
            again = (
                "it is drawn again among the gaits still allowed"
                if session.validation_plan is not None
                else "fewer than three gaits may be shown now, so none is open"
            )
            console.print(
                "the blind validation round showed a gait in the region of avoidance now and "
                f"was withdrawn: {again}"
            )


def _say_withdrawn(pending: SessionQuery | None, session: Session, where: str) -> None:
    """Say so when the flag or exclusion just made withdrew ``pending`` (a gait ``where``)."""
    if pending is not None and session.pending is None:
        console.print(
            f"the pending query {pending.id} proposed a gait {where} and was withdrawn: the "
            "next query is proposed anew"
        )


@session_app.command("unsafe")
def unsafe(
    session_id: IdArgument,
    trial: Annotated[int, typer.Argument(metavar="TRIAL", help="The trial number.")],
    reason: Annotated[
        str, typer.Option(help="Why it was unsafe (required to flag; shown in exports).")
    ] = "",
    withdraw: Annotated[
        bool, typer.Option("--withdraw", help="Take the trial's unsafe flag back.")
    ] = False,
    db: DbOption = None,
) -> None:
    """Flag a trial unsafe: its gait, and those within [safety].unsafe_radius, are never
    proposed again (--withdraw takes the flag back)."""
    with _opened(db, session_id) as session:
        if withdraw:
            guard(lambda: session.withdraw_unsafe(trial))
            console.print(f"trial {trial}: unsafe flag withdrawn")
            return
        if not reason.strip():
            fail("give --reason: what made the trial unsafe")
        pending = session.pending
        guard(lambda: session.flag_unsafe(trial, reason))
        console.print(
            f"trial {trial} flagged unsafe ({reason}); "
            + session.config.safety.flag_effect(session.config.space.continuous)
        )
        _say_withdrawn(pending, session, "near it")


@session_app.command("note")
def note(
    session_id: IdArgument,
    text: Annotated[str, typer.Argument(metavar="TEXT", help="The note.")],
    db: DbOption = None,
) -> None:
    """Log a note in the session."""
    with _opened(db, session_id) as session:
        seq = guard(lambda: session.note(text))
        console.print(f"note logged as event {seq}")


@session_app.command("finish")
def finish(session_id: IdArgument, db: DbOption = None, yes: YesOption = False) -> None:
    """Finish the session: it takes no more events; asks first unless --yes."""
    with _opened(db, session_id) as session:
        _confirm(f"Finish session {session_id}? It will take no more answers.", yes)
        guard(session.finish)
        console.print(f"session {session_id} finished")


@session_app.command("export")
def export(
    session_id: IdArgument,
    out: Annotated[Path, typer.Option(help="A new (or empty) folder.")],
    fmt: Annotated[str, typer.Option("--format", help="csv or json.")] = "csv",
    db: DbOption = None,
) -> None:
    """Export a session to a folder: its event log, config and manifest, and one table each of
    trials, comparisons, suggestions, ratings (with [feedback.rating]), the posterior, blind
    validation and the confidence after every answer (docs/sessions.md lists the columns)."""
    from gaitpref.cli.main import progress_bar
    from gaitpref.sessions import export_session

    if fmt not in ("csv", "json"):
        fail(f"--format must be csv or json, got {fmt!r}")
    with _opened(db, session_id) as session, progress_bar(transient=True) as bar:
        # the confidence after every answer is worked out again: minutes on a large grid
        task = bar.add_task("confidence table", total=None)

        def advance(done: int, total: int) -> None:
            bar.update(task, completed=done, total=total)

        manifest = guard(lambda: export_session(session, out, fmt, advance))  # type: ignore[arg-type]
        console.print(f"exported session {session_id} to {out} (manifest: {manifest.name})")


@session_app.command("import")
def import_(
    folder: Annotated[Path, typer.Argument(metavar="FOLDER", help="An export folder.")],
    db: DbOption = None,
    as_new: Annotated[
        bool, typer.Option("--as-new", help="Import a session the database already holds again.")
    ] = False,
) -> None:
    """Rebuild a session from an export (checked by replay before anything is written)."""
    from gaitpref.sessions import import_session

    session = guard(lambda: import_session(db, folder, as_new=as_new))
    was = session.record.meta["imported_from"]["session_id"]
    console.print(f"imported as session {session.id} (was {was}) in {session.storage.url}")
    session.close()
