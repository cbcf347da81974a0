"""One Rich console and one error helper for the whole ``gaitpref`` command.

Every command prints through :data:`console` (stdout) and :data:`err_console` (stderr), and turns
errors into a message and an exit status in one place, :func:`exit_for`:

==============================================  =====================  ======
error family (:mod:`gaitpref.errors`)           printed as             status
==============================================  =====================  ======
:class:`~gaitpref.errors.ConfigError`           ``config error: ...``  2
:class:`~gaitpref.errors.StorageError`          ``storage error: ...`` 2
:class:`~gaitpref.errors.FeedbackError`,        ``answer refused: ...`` 2
:class:`~gaitpref.errors.QueryError`
:class:`~gaitpref.errors.SessionError`          ``session error: ...`` 2
:class:`~gaitpref.errors.GaitError`             ``gait error: ...``    2
:class:`~gaitpref.errors.ModelError`            ``model error: ...``   1
any other :class:`~gaitpref.errors.GaitprefError`, ``error: ...``      2
``ValueError``, ``TypeError``, ``OSError``
==============================================  =====================  ======

Status 2 means "the input was refused; nothing was written"; status 1 means a computation could
not finish (or a check found a problem, or a question was answered no), and is also the status
of an undo that is written though the query to be proposed in place of the one it withdrew was
not (``session undo``, ``session validate --withdraw --undo``: any error then, a storage error
too, exits 1, after the lines that say what was written); 130, an interrupt.  The
statuses, and what goes to stdout and to stderr, are documented for scripts in
``docs/getting-started.md`` ("In scripts: exit statuses and output"), held to this table by
``tests/cli/test_scripts.py``.  The message is always ``str(exc)``: the error classes name the
table, key, session or event themselves, so the CLI never re-formats their arguments.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, TypeVar

import typer
from rich.console import Console
from rich.markup import escape

from gaitpref import errors

if TYPE_CHECKING:
    from gaitpref.config import ExperimentConfig

T = TypeVar("T")

#: Markup off: config names, descriptions, notes, reasons and paths are printed as they are
#: ("exo [v2]" vanished, "[/bold]" raised MarkupError); a print of ours that styles passes
#: ``markup=True`` with everything it interpolates escaped.
console = Console(highlight=False, soft_wrap=True, markup=False)
err_console = Console(stderr=True, highlight=False, soft_wrap=True, markup=False)

#: (family, label, exit status), most specific first.
FAMILIES: tuple[tuple[type[BaseException], str, int], ...] = (
    (errors.ConfigError, "config error", 2),
    (errors.StorageError, "storage error", 2),
    (errors.FeedbackError, "answer refused", 2),
    (errors.QueryError, "answer refused", 2),
    (errors.SessionError, "session error", 2),
    (errors.GaitError, "gait error", 2),
    (errors.ModelError, "model error", 1),
    (errors.GaitprefError, "error", 2),
    (ValueError, "error", 2),
    (TypeError, "error", 2),
    (OSError, "error", 2),
)
HANDLED: tuple[type[BaseException], ...] = tuple(family for family, _, _ in FAMILIES)


def exit_for(exc: BaseException) -> tuple[str, int]:
    """The line to print and the exit status for ``exc`` (one of :data:`HANDLED`)."""
    for family, label, code in FAMILIES:
        if isinstance(exc, family):
            return f"{label}: {exc}", code
    raise TypeError(f"{type(exc).__name__} is not an error the CLI reports") from exc


def fail(message: str, code: int = 2) -> NoReturn:
    """Print ``error: message`` on stderr and exit with ``code`` (2: the input was refused)."""
    _print_error("error", message)
    raise typer.Exit(code)


def report(exc: BaseException, where: str = "", code: int | None = None) -> NoReturn:
    """Print ``exc`` as :func:`exit_for` says (after ``where``, e.g. which run) and exit with
    its status (``code``: another, e.g. 1 where a part of the command was written)."""
    line, status = exit_for(exc)
    label, _, message = line.partition(": ")
    _print_error(label, f"{where}: {message}" if where else message)
    raise typer.Exit(status if code is None else code)


def _print_error(label: str, message: str) -> None:
    # the message is printed as is: brackets in it (``[model]``, ``gaitpref[console]``) are text
    err_console.print(f"[bold red]{label}:[/] {escape(message)}", markup=True)


def guard(fn: Callable[[], T]) -> T:
    """``fn()``, reporting any handled error (:func:`report`) instead of a traceback."""
    try:
        return fn()
    except HANDLED as exc:
        report(exc)


def checked_config(
    source: str, cfg: ExperimentConfig, check: Callable[[ExperimentConfig], None]
) -> None:
    """``check(cfg)``, its :class:`ConfigError` naming the config as a parse error does
    (``config 'my.toml': [stop].samples: ...``): a new run's checks named the key only."""
    try:
        check(cfg)
    except errors.ConfigError as exc:
        raise errors.ConfigError(
            f"config {source!r}: {exc}", table=exc.table, key=exc.key
        ) from None


def check_file_out(out: Path, option: str) -> None:
    """Refuse a file to write (``option``: ``gaits build --out``, ``gaits plot --out``,
    ``session show --figure``) that could not be written, before any work: a folder, a folder
    that does not exist (never made: a mistyped path would scatter folders; an output that is
    a folder, ``session export --out`` or a bench's ``--out``, is made, parents and all), or
    one that cannot be written in."""
    import tempfile

    if out.is_dir():
        raise typer.BadParameter(f"{out} is a folder: give a file name", param_hint=option)
    folder = out.parent
    if not folder.is_dir():
        raise typer.BadParameter(f"no folder {folder} to write {out.name} in", param_hint=option)
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise typer.BadParameter(
            f"cannot write in {folder} ({exc.strerror or exc})", param_hint=option
        ) from None


def read_array(path: Path, what: str) -> Any:
    """The one NumPy array (``.npy``) at ``path``, or :func:`fail` naming ``what`` and the file:
    missing, not an array file (a zip that is not one raised ``BadZipFile``), an ``.npz``
    archive of several (iterated as its names before), or an array of objects; and an array
    that is not of real numbers (a structured record, text, complex numbers: a TypeError
    traceback, or a ComplexWarning and the imaginary parts dropped).  The file is mapped
    (``mmap_mode="r"``) before it is copied: a header whose shape the file does not hold is
    refused without first allocating that shape (a 200-byte file asked for 7.45 GiB)."""
    import zipfile

    import numpy as np

    where = f"{what} {str(path)!r}"
    if not path.is_file():
        fail(f"{where} does not exist")
    try:  # errstate: a shape past int64 overflows numpy's size arithmetic (a warning)
        with np.errstate(over="ignore"):
            arr = np.load(path, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
        fail(f"{where} is not a readable .npy array: {exc}")
    if not isinstance(arr, np.ndarray):  # an .npz archive
        arr.close()
        fail(f"{where} is an .npz archive; give one .npy array (numpy.save)")
    if arr.dtype.kind not in "biuf":
        fail(f"{where} holds {arr.dtype} values; give an array of real numbers (numpy.save)")
    return np.array(arr)


@contextmanager
def json_only(as_json: bool) -> Iterator[None]:
    """A block whose prints to stdout go to stderr when ``as_json`` (``--json``: stdout holds
    the JSON printed after it, alone).  A user's objective (``PATH.py:NAME``) that printed, when
    imported or called, broke the JSON a script read."""
    if not as_json:
        yield
        return
    import sys
    from contextlib import redirect_stdout

    with redirect_stdout(sys.stderr):
        yield


@contextmanager
def reported() -> Iterator[None]:
    """A block whose handled errors are reported (:func:`report`) instead of raised."""
    try:
        yield
    except HANDLED as exc:
        report(exc)
