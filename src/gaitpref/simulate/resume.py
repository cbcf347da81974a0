"""Resume a study that stopped, from the finished runs in its partial run table.

A study given a ``partial`` file (:func:`~gaitpref.simulate.sweep.run_study`; ``gaitpref bench
paper-2d|compass-gait`` keep ``OUT/runs.partial.csv``) appends each run to it as the run
finishes.  The file's first line names the sweep that wrote it, ``# gaitpref study {JSON}``
(:func:`signature`: the release, the study's name, settings, objective ids, seeds, trials,
seed, noise, user noise, kernel, and digests of its grid and objective values); the CSV run
table follows (:func:`~gaitpref.simulate.tables.read_table` skips the line).

:func:`read_partial` reads the runs back for ``run_study(..., resume=True)``: it refuses
(:class:`ResumeError`, naming the file and what differs) a file written by another sweep, and
one whose lines are not a run table of this study (naming the file and line).  Every run is
seeded from its coordinates only (:func:`~gaitpref.simulate.study.run_seed_sequence`), so the
runs it keeps and those run afresh make the table an uninterrupted study makes, bit for bit
(floats are written with ``repr``).

What a machine that died while writing leaves is dropped with a :class:`PartialRunsWarning`
naming the file and lines, and its run runs again: a last line cut short (no newline), and a
last run with fewer rows than trials.  A file written before the first line named the sweep
(gaitpref 0.1.0 before resuming) is read too: its runs must be runs of this study with its
trials, and the first of them is run again and must give the same rows (its objective, seeds
and settings checked so), with a warning that this is all that could be checked.  The file is
then rewritten (atomically) with the signature and the runs kept, and the resumed study
appends to it.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gaitpref import __version__
from gaitpref.atomic import write_text_atomic
from gaitpref.errors import GaitprefError
from gaitpref.limits import MAX_PARTIAL_BYTES
from gaitpref.simulate.study import RunResult, RunTask, Study, run_one
from gaitpref.simulate.tables import COMMENT, RunTable, csv_rows, run_columns

#: how the first line of a study's partial table starts, after ``# ``
SIGNATURE = "gaitpref study "


class ResumeError(GaitprefError, ValueError):
    """A partial run table that a study cannot resume from: written by another sweep (the
    message names what differs) or not a run table of this study (it names the line)."""


class PartialRunsWarning(UserWarning):
    """Lines of a partial run table dropped (cut short by a machine that died while writing
    them), or a file whose sweep could be checked only in part."""


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def describe(study: Study) -> dict[str, Any]:
    """What makes ``study``'s runs what they are, as JSON values (a digest for the grid and the
    objective values)."""
    space = [
        {
            "name": f.name,
            "values": list(f.values),
            "unit": f.unit,
            "coactive": list(f.coactive),
            "words": list(f.words),
            "continuous": bool(f.continuous),
        }
        for f in study.space.features
    ]
    objectives = np.ascontiguousarray(study.objectives, dtype="<f8")
    kernel = study.kernel
    ls = kernel.lengthscale
    return {
        "gaitpref": __version__,
        "study": study.name,
        "settings": [
            {
                **asdict(s),
                "coactive": bool(s.coactive),
                "rating_quantiles": list(s.rating_quantiles),
            }
            for s in study.settings
        ],
        "objective_ids": list(study.objective_ids),
        "seeds": list(study.seeds),
        "trials": study.trials,
        "seed": study.seed,
        "minimize": bool(study.minimize),
        "noise": float(study.noise),
        "user_noise": float(study.user_noise),
        "kernel": {
            "lengthscale": list(ls) if isinstance(ls, tuple) else float(ls),
            "variance": float(kernel.variance),
            "jitter": float(kernel.jitter),
        },
        "space": _digest(json.dumps(space, sort_keys=True).encode("utf-8")),
        "objectives": _digest(str(objectives.shape).encode("ascii") + objectives.tobytes()),
    }


def signature(study: Study) -> str:
    """The first line of ``study``'s partial table, without ``# ``: :data:`SIGNATURE` and
    :func:`describe` as JSON."""
    return SIGNATURE + json.dumps(describe(study), separators=(",", ":"))


def _short(value: object) -> str:
    text = json.dumps(value)
    return text if len(text) <= 80 else text[:77] + "..."


#: what differs when a field of :func:`describe` does, in the errors
_FIELDS = {
    "study": "the study's name differs",
    "objective_ids": "the objectives differ",
    "seeds": "the seeds differ",
    "trials": "the trials per run differ",
    "seed": "the study seed differs",
    "minimize": "minimize differs",
    "noise": "the model's noise differs",
    "user_noise": "the simulated subjects' noise differs",
    "kernel": "the kernel differs",
    "space": "the grid (its features and values) differs",
    "objectives": "the objective values differ",
}


def _difference(kept: dict[str, Any], mine: dict[str, Any]) -> str | None:
    """What differs between the sweep that wrote a file (``kept``) and this one, first found."""
    if kept.get("gaitpref") != mine["gaitpref"]:
        return (
            f"it was written by gaitpref {kept.get('gaitpref')}, this is {mine['gaitpref']}, and "
            "runs of different releases may differ; resume it with the release that wrote it"
        )
    theirs, ours = kept.get("settings"), mine["settings"]
    if theirs != ours:
        names = [s.get("name") for s in theirs] if isinstance(theirs, list) else theirs
        mine_names = [s["name"] for s in ours]
        if not isinstance(theirs, list) or names != mine_names:
            return f"the settings differ: {_short(names)} in the file, {_short(mine_names)} here"
        for a, b in zip(theirs, ours, strict=True):
            for key in b:
                if a.get(key) != b[key]:
                    return (
                        f"setting {b['name']!r} differs: {key} {_short(a.get(key))} in the file, "
                        f"{_short(b[key])} here"
                    )
    for key, what in _FIELDS.items():
        if kept.get(key) != mine[key]:
            if key in ("space", "objectives"):
                return what
            return f"{what}: {_short(kept.get(key))} in the file, {_short(mine[key])} here"
    return None


@dataclass
class _Run:
    """One run's rows as read: its coordinates, first and last line, and columns."""

    key: tuple[str, int, int]
    first: int
    last: int
    trials: list[int]
    actions: list[int]
    values: list[float]
    ratings: list[int]


def _coords(key: tuple[str, int, int]) -> str:
    return f"setting {key[0]!r}, objective {key[1]}, seed {key[2]}"


def _lines(first: int, last: int) -> str:
    return f"line {first}" if first == last else f"lines {first}-{last}"


def _runs(reader: Any, path: Path, header: list[str], offset: int) -> Iterator[_Run]:
    """The rows of ``reader`` grouped into runs (consecutive rows of one run's coordinates);
    line numbers are the file's (``offset`` lines before the reader's first)."""
    run: _Run | None = None
    rated = len(header) > len(run_columns(False))
    for row in reader:
        line = reader.line_num + offset
        if len(row) != len(header):
            raise ResumeError(f"{path}:{line}: {len(row)} fields, the header has {len(header)}")
        try:
            key = (row[0], int(row[1]), int(row[2]))
            trial, action, value = int(row[3]), int(row[4]), float(row[5])
            rating = int(row[6]) if rated else 0
        except ValueError:
            raise ResumeError(
                f"{path}:{line}: not a run table's row ({', '.join(row)}): numbers expected "
                f"in {', '.join(header[1:])}"
            ) from None
        if run is None or run.key != key:
            if run is not None:
                yield run
            run = _Run(key, line, line, [], [], [], [])
        run.trials.append(trial)
        run.actions.append(action)
        run.values.append(value)
        run.ratings.append(rating)
        run.last = line
    if run is not None:
        yield run


def _warn(message: str) -> None:
    warnings.warn(message, PartialRunsWarning, stacklevel=3)


@dataclass(frozen=True)
class Kept:
    """The finished runs of a partial table: ``runs`` by their index in the study's tasks (in
    the file's order); ``rewrite``: the file must be written again before it is appended to
    (lines dropped, or no signature)."""

    runs: dict[int, RunResult]
    rewrite: bool


def partial_bytes(path: Path) -> bytes:
    """The bytes of the partial file ``path``, read whole: :class:`ResumeError` naming the file
    when it is larger than :data:`~gaitpref.limits.MAX_PARTIAL_BYTES` (no sweep writes one that
    large; it is not read)."""
    size = path.stat().st_size
    if size > MAX_PARTIAL_BYTES:
        raise ResumeError(
            f"{path}: {size:,} bytes, more than the {MAX_PARTIAL_BYTES:,} a resumed sweep reads "
            "(no sweep writes a partial file that large): not read; run the sweep afresh"
        )
    return path.read_bytes()


def read_whole_lines(path: Path, sweep: str, what: str) -> tuple[str, bool]:
    """The whole lines of the partial file ``path`` (read by :func:`partial_bytes`), and whether
    a last line cut short was dropped (a :class:`PartialRunsWarning` says so, naming the line:
    the ``sweep`` stopped while writing it); :class:`ResumeError` when it is not UTF-8 text,
    ``what`` naming what the file should have been."""
    data = partial_bytes(path)
    end = data.rfind(b"\n") + 1
    cut = end < len(data)
    if cut:
        line = data.count(b"\n", 0, end) + 1
        warnings.warn(
            f"{path}:{line}: the last line is cut short (the {sweep} stopped while writing it): "
            "dropped, and its run runs again",
            PartialRunsWarning,
            stacklevel=3,
        )
    try:
        return data[:end].decode("utf-8"), cut
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise ResumeError(f"{path}:{line}: not UTF-8 text, not {what}") from None


def read_partial(path: Path, study: Study, tasks: Sequence[RunTask] | None = None) -> Kept:
    """The finished runs of ``study`` in its partial table ``path`` (as the module says):
    :class:`ResumeError` for a file of another sweep or not a run table of this study, a
    :class:`PartialRunsWarning` for each thing dropped; ``tasks``: ``study.tasks()``."""
    tasks = study.tasks() if tasks is None else tasks
    text, rewrite = read_whole_lines(path, "study", "a study's run table")
    signed = text.startswith(COMMENT)
    offset = 0
    if signed:
        top, _, text = text.partition("\n")
        offset = 1
        _check_signature(top.removeprefix(COMMENT), path, study)
    rated = any(s.rating_quantiles for s in study.settings)
    reader = csv.reader(io.StringIO(text, newline=""))
    header = next(reader, None)
    if header is None:  # made, the header not yet written
        return Kept({}, True)
    expected = list(run_columns(rated))
    if header != expected:
        why = "rating column" if header == list(run_columns(not rated)) else "header"
        raise ResumeError(
            f"{path}:{1 + offset}: not this study's run table: its header is {','.join(header)}, "
            f"this study's is {','.join(expected)} (the {why} differs)"
        )
    index = {(t.setting.name, t.objective_id, t.seed): i for i, t in enumerate(tasks)}
    rates = {s.name: bool(s.rating_quantiles) for s in study.settings}
    kept: dict[int, RunResult] = {}
    runs = list(_runs(reader, path, header, offset))
    for k, run in enumerate(runs):
        first, last = run.first, run.last
        where = f"{path}:{first}"
        i = index.get(run.key)
        if i is None:
            raise ResumeError(
                f"{where}: {_coords(run.key)} is not a run of this study (its settings, "
                "objectives and seeds differ): the file was written by another sweep"
            )
        if i in kept:
            raise ResumeError(f"{where}: {_coords(run.key)} is in the file twice")
        n = len(run.trials)
        if run.trials != list(range(1, n + 1)) or n > study.trials:
            raise ResumeError(
                f"{path}:{_lines(first, last)}: {_coords(run.key)} has trials "
                f"{_short(run.trials)}, this study's runs have trials 1..{study.trials}"
            )
        if n < study.trials:
            if k < len(runs) - 1:
                raise ResumeError(
                    f"{path}:{_lines(first, last)}: {_coords(run.key)} has {n} of "
                    f"{study.trials} trials, and other runs follow it (was it written with "
                    "other trials?)"
                )
            _warn(
                f"{path}:{_lines(first, last)}: {_coords(run.key)} has {n} of {study.trials} "
                "trials (the study stopped while writing it): dropped, and it runs again"
            )
            rewrite = True
            continue
        kept[i] = RunResult(
            run.key[0],
            run.key[1],
            run.key[2],
            np.array(run.actions, dtype=np.intp),
            np.array(run.values, dtype=np.float64),
            np.array(run.ratings, dtype=np.intp) if rates[run.key[0]] else None,
        )
    if not signed and kept:
        _check_one(path, tasks, kept)
        rewrite = True
    return Kept(kept, rewrite or not signed)


def _check_signature(line: str, path: Path, study: Study) -> None:
    if not line.startswith(SIGNATURE):
        raise ResumeError(
            f"{path}:1: not a study's partial run table (its first line does not start with "
            f"'{COMMENT}{SIGNATURE}')"
        )
    try:
        written = json.loads(line.removeprefix(SIGNATURE))
    except json.JSONDecodeError as exc:
        raise ResumeError(f"{path}:1: the sweep's description is not JSON ({exc})") from None
    if not isinstance(written, dict):
        raise ResumeError(f"{path}:1: the sweep's description is not a JSON object")
    mine = json.loads(json.dumps(describe(study)))  # as JSON reads it back
    differs = _difference(written, mine)
    if differs is not None:
        raise ResumeError(
            f"{path} holds the finished runs of another sweep: {differs}; resume with the "
            "command and options that wrote it, or move the file away to run this study afresh"
        )


def _check_one(path: Path, tasks: Sequence[RunTask], kept: dict[int, RunResult]) -> None:
    """A file without a signature: its first run, run again, must give its rows."""
    i, was = next(iter(kept.items()))
    _warn(
        f"{path} does not name the sweep that wrote it (written before partial tables did): "
        f"its runs are runs of this study with its trials, and {coordinates_of(was)}, run "
        "again, gives the same rows; nothing else of the sweep could be checked"
    )
    now = run_one(tasks[i])
    same = np.array_equal(now.actions, was.actions) and np.array_equal(
        now.normalized, was.normalized
    )
    if same and now.ratings is not None and was.ratings is not None:
        same = np.array_equal(now.ratings, was.ratings)
    if not same:
        raise ResumeError(
            f"{path}: {coordinates_of(was)}, run again, does not give the file's rows: the "
            "file was written by another sweep (other objectives, study seed, model or "
            "release); move it away to run this study afresh"
        )


def coordinates_of(result: RunResult) -> str:
    """A run result as the errors name its run."""
    return _coords((result.setting, result.objective_id, result.seed))


def partial_text(study: Study, table: RunTable | None) -> str:
    """``study``'s partial table holding ``table``'s runs (None: none), signature first."""
    rated = any(s.rating_quantiles for s in study.settings)
    out = io.StringIO(newline="")
    out.write(f"{COMMENT}{signature(study)}\n")
    w = csv.writer(out, lineterminator="\n")
    w.writerow(run_columns(rated))
    if table is not None:
        w.writerows(csv_rows(table))
    return out.getvalue()


def write_partial(path: Path, study: Study, table: RunTable | None) -> None:
    """Write ``study``'s partial table at ``path`` holding ``table``'s runs, atomically."""
    write_text_atomic(path, partial_text(study, table), f".{path.name}.")


__all__ = [
    "SIGNATURE",
    "Kept",
    "PartialRunsWarning",
    "ResumeError",
    "coordinates_of",
    "describe",
    "partial_text",
    "read_partial",
    "signature",
    "write_partial",
]
