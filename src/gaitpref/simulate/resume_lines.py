"""Resume a bench that stopped, from the finished runs in its ``--partial`` JSON-lines file.

``gaitpref bench continuous`` and ``gaitpref bench population`` write, as the first line of
their ``--partial`` file, the bench that writes it: ``{"gaitpref bench": {...}}``
(:func:`first_line`: the bench's name, the release and every option its runs depend on, with
digests of the config's text and of the objectives); each later line is one finished run.
:func:`read_lines` reads the runs back for a resumed bench: a file whose first line names
another bench, or other options, is refused with :class:`~gaitpref.simulate.resume.ResumeError`
naming what differs, as is a line that is not a JSON object (naming the file and line).  A last
line cut short (no newline: the machine died while writing it) is dropped with a
:class:`~gaitpref.simulate.resume.PartialRunsWarning` naming the file and line, and its run runs
again; the file is then written again without it (:func:`write_lines`, atomically).

A file written before the first line named its bench (gaitpref 0.1.0 before resuming) is
refused: nothing in it says which options wrote it.  ``bench population``'s cold lines hold
the preferences each cold run left, from which its warm runs start
(:func:`gaitpref.simulate.population.walked_record`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from gaitpref.atomic import write_text_atomic
from gaitpref.simulate.resume import ResumeError, read_whole_lines

#: the key of a bench's partial file's first line
KEY = "gaitpref bench"


def first_line(sweep: Mapping[str, object]) -> dict[str, object]:
    """The first line of a bench's partial file, as an object: ``{KEY: sweep}``."""
    return {KEY: dict(sweep)}


def _short(value: object) -> str:
    text = json.dumps(value)
    return text if len(text) <= 80 else text[:77] + "..."


def read_lines(path: Path, sweep: Mapping[str, object]) -> tuple[list[tuple[int, Any]], bool]:
    """The runs in ``path`` (each with its line number), checked to be those of the bench
    ``sweep`` describes, and whether the file must be written again (a line was dropped)."""
    text, rewrite = read_whole_lines(path, "bench", "a bench's partial file")
    lines = text.split("\n")[:-1]
    objects = [(n, _object(text, path, n)) for n, text in enumerate(lines, start=1)]
    if not objects:  # made, its first line not yet written
        return [], True
    _check_first(objects[0][1], path, sweep)
    return objects[1:], rewrite


def _object(text: str, path: Path, line: int) -> dict[str, Any]:
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ResumeError(f"{path}:{line}: not a JSON object ({exc.msg})") from None
    if not isinstance(value, dict):
        raise ResumeError(f"{path}:{line}: not a JSON object, got {_short(value)}")
    return value


def _check_first(first: dict[str, Any], path: Path, sweep: Mapping[str, object]) -> None:
    written = first.get(KEY)
    if not isinstance(written, dict):
        raise ResumeError(
            f"{path}:1: the first line does not name the bench that wrote the file (none did "
            "before resuming), so it cannot be checked and is not resumed; run the bench afresh "
            "with a new --partial file"
        )
    mine = json.loads(json.dumps(dict(sweep)))  # as JSON reads it back
    for key, value in mine.items():
        if written.get(key) != value:
            what = (
                f"{key} differs"
                if key.endswith("sha256")
                else f"{key} differs: {_short(written.get(key))} in the file, {_short(value)} here"
            )
            raise ResumeError(
                f"{path} holds the finished runs of another bench: {what}; resume with the "
                "command and options that wrote it, or give a new --partial file"
            )


def write_lines(path: Path, sweep: Mapping[str, object], records: Sequence[object]) -> None:
    """Write a bench's partial file: its first line, then ``records``, atomically."""
    lines = [json.dumps(first_line(sweep)), *(json.dumps(r) for r in records)]
    write_text_atomic(path, "".join(f"{line}\n" for line in lines), f".{path.name}.")


__all__ = ["KEY", "first_line", "read_lines", "write_lines"]
