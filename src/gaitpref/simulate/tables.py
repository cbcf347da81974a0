"""Tidy tables of a study: one row per run and trial, and per-setting learning curves.

The run table has the columns ``setting, objective, seed, trial, action, normalized_objective``
(``trial`` counts executed actions from 1; ``action`` is a flat grid index), and ``rating`` when
a setting's simulated subject rated the executed gaits (``1`` worst to ``K``; ``0`` in the rows
of settings that did not rate).  A curve is the mean
of ``normalized_objective`` over a setting's runs at each trial, with its standard error
``sd / sqrt(runs)`` (``sd`` with ``ddof = 1``; NaN for a single run), as in the paper's Fig. 4.

Files: ``.csv`` (optionally ``.csv.gz``) with the standard library, ``.parquet`` through pyarrow
(``pip install gaitpref[parquet]``).  Floats are written with ``repr`` so a table reads back
bit for bit.  A CSV run table may start with one comment line, ``# ...``, saying what wrote it
(a study's partial table names its sweep: :mod:`gaitpref.simulate.resume`); :func:`read_table`
skips it.

Notation: ``R`` rows; per setting ``runs x trials`` values.
"""

from __future__ import annotations

import csv
import gzip
import io
import itertools
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np
from numpy.typing import NDArray

from gaitpref.space import FloatArray, IntArray

RUN_COLUMNS = ("setting", "objective", "seed", "trial", "action", "normalized_objective")
#: how a CSV run table's first line starts when it says what wrote the table (a study's
#: partial table: :mod:`gaitpref.simulate.resume`); :func:`read_table` skips that line
COMMENT = "# "
CURVE_COLUMNS = ("setting", "trial", "mean", "se")
_RUN_DTYPES = (str, np.intp, np.intp, np.intp, np.intp, np.float64)
_CURVE_DTYPES = (str, np.intp, np.float64, np.float64)


def _frozen(a: NDArray[Any]) -> NDArray[Any]:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class RunTable:
    """The tidy per-run, per-trial table (columns as arrays of equal length)."""

    setting: NDArray[np.str_]
    objective: IntArray
    seed: IntArray
    trial: IntArray
    action: IntArray
    normalized_objective: FloatArray
    rating: IntArray | None = None  # the rating given at each trial (0: not rated)

    def __post_init__(self) -> None:
        sizes = {len(getattr(self, c)) for c in self.columns}
        if len(sizes) != 1:
            raise ValueError(f"run table columns differ in length: {sorted(sizes)}")
        for name, dtype in zip(RUN_COLUMNS, _RUN_DTYPES, strict=True):
            object.__setattr__(self, name, _frozen(np.asarray(getattr(self, name), dtype=dtype)))
        if self.rating is not None:
            rating = _frozen(np.asarray(self.rating, dtype=np.intp))
            if rating.size and rating.min() < 0:
                raise ValueError("run table column rating holds labels 1..K, or 0 (not rated)")
            object.__setattr__(self, "rating", rating)

    @property
    def columns(self) -> tuple[str, ...]:
        """The table's columns: :data:`RUN_COLUMNS`, and ``rating`` when it has ratings."""
        return RUN_COLUMNS if self.rating is None else (*RUN_COLUMNS, "rating")

    def __len__(self) -> int:
        return int(self.trial.size)

    @property
    def settings(self) -> tuple[str, ...]:
        """Setting names in order of first appearance."""
        return tuple(dict.fromkeys(self.setting.tolist()))

    def matrix(self, setting: str) -> FloatArray:
        """``runs x trials`` normalised objective of one setting, runs in table order."""
        rows = self.setting == setting
        if not np.any(rows):
            raise KeyError(f"no setting {setting!r} in this table; it has {list(self.settings)}")
        trials = self.trial[rows]
        width = int(trials.max())
        values = self.normalized_objective[rows]
        if values.size % width or not np.array_equal(
            trials, np.tile(np.arange(1, width + 1), values.size // width)
        ):
            raise ValueError(
                f"setting {setting!r}: runs do not all have trials 1..{width} in order"
            )
        out: FloatArray = values.reshape(-1, width)
        return out

    def ratings(self, setting: str) -> IntArray:
        """``runs x trials`` ratings of one setting (0: not rated), runs in table order."""
        if self.rating is None:
            raise KeyError("this run table has no ratings (no setting rated)")
        width = self.matrix(setting).shape[1]
        out: IntArray = self.rating[self.setting == setting].reshape(-1, width)
        return out

    def equals(self, other: RunTable) -> bool:
        """Exact equality of every column."""
        return self.columns == other.columns and all(
            np.array_equal(getattr(self, c), getattr(other, c)) for c in self.columns
        )

    def rows(self) -> Iterator[tuple[str, int, int, int, int, float]]:
        yield from zip(*(getattr(self, c).tolist() for c in RUN_COLUMNS), strict=True)

    @classmethod
    def concat(cls, tables: Sequence[RunTable]) -> RunTable:
        if not tables:
            raise ValueError("nothing to concatenate")
        rating = None
        if any(t.rating is not None for t in tables):
            rating = np.concatenate(
                [np.zeros(len(t), np.intp) if t.rating is None else t.rating for t in tables]
            )
        s, o, sd, t, a, v = (np.concatenate([getattr(t, c) for t in tables]) for c in RUN_COLUMNS)
        return cls(s, o, sd, t, a, v, rating)


@dataclass(frozen=True, eq=False)
class Curves:
    """Mean and standard error of the normalised objective per setting and trial."""

    setting: NDArray[np.str_]
    trial: IntArray
    mean: FloatArray
    se: FloatArray

    def __post_init__(self) -> None:
        for name, dtype in zip(CURVE_COLUMNS, _CURVE_DTYPES, strict=True):
            object.__setattr__(self, name, _frozen(np.asarray(getattr(self, name), dtype=dtype)))
        if len({len(getattr(self, c)) for c in CURVE_COLUMNS}) != 1:
            raise ValueError("curve columns differ in length")

    @property
    def settings(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(self.setting.tolist()))

    def curve(self, setting: str) -> tuple[IntArray, FloatArray, FloatArray]:
        """``(trials, mean, se)`` of one setting, by trial."""
        rows = np.flatnonzero(self.setting == setting)
        if rows.size == 0:
            raise KeyError(f"no curve for setting {setting!r}; there are {list(self.settings)}")
        order = rows[np.argsort(self.trial[rows], kind="stable")]
        return self.trial[order], self.mean[order], self.se[order]

    def at(self, setting: str, trial: int) -> tuple[float, float]:
        """``(mean, se)`` of ``setting`` at ``trial``."""
        trials, mean, se = self.curve(setting)
        k = np.flatnonzero(trials == trial)
        if k.size == 0:
            raise KeyError(f"setting {setting!r} has no trial {trial} (it has 1..{trials.max()})")
        return float(mean[k[0]]), float(se[k[0]])


def summarize(table: RunTable) -> Curves:
    """Per-setting learning curves of a run table."""
    parts: list[tuple[list[str], IntArray, FloatArray, FloatArray]] = []
    for name in table.settings:
        m = table.matrix(name)
        runs, width = m.shape
        se = m.std(axis=0, ddof=1) / np.sqrt(runs) if runs > 1 else np.full(width, np.nan)
        parts.append(([name] * width, np.arange(1, width + 1), m.mean(axis=0), se))
    return Curves(
        np.array([s for p in parts for s in p[0]], dtype=str),
        np.concatenate([p[1] for p in parts]),
        np.concatenate([p[2] for p in parts]),
        np.concatenate([p[3] for p in parts]),
    )


# -- files -----------------------------------------------------------------------------------------
@contextmanager
def _open_text(path: Path, mode: str) -> Iterator[IO[str]]:
    if not path.name.endswith(".gz"):
        with open(path, mode, encoding="utf-8", newline="") as fh:
            yield fh
        return
    # mtime 0 and no file name in the gzip header: the same table gives the same bytes
    with (
        open(path, mode + "b") as raw,
        gzip.GzipFile(filename="", mode=mode + "b", fileobj=raw, mtime=0) as gz,
        io.TextIOWrapper(gz, encoding="utf-8", newline="") as fh,
    ):
        yield fh


def _is_parquet(path: Path) -> bool:
    if path.suffix == ".parquet":
        return True
    if path.name.endswith((".csv", ".csv.gz")):
        return False
    raise ValueError(f"{path}: table files must end in .csv, .csv.gz or .parquet")


def _pyarrow() -> Any:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise RuntimeError(
            "writing Parquet needs pyarrow: pip install 'gaitpref[parquet]' (or use a .csv file)"
        ) from None
    return pa, pq


def check_table_path(path: str | Path) -> None:
    """Refuse, before a study runs, a table file :func:`write_table` could not write: another
    suffix (``ValueError``), or Parquet without pyarrow (``RuntimeError``)."""
    if _is_parquet(Path(path)):
        _pyarrow()


def write_table(table: RunTable, path: str | Path) -> Path:
    """Write the run table as CSV (``.csv``/``.csv.gz``) or Parquet (``.parquet``)."""
    path = Path(path)
    if _is_parquet(path):
        pa, pq = _pyarrow()
        pq.write_table(pa.table({c: getattr(table, c) for c in table.columns}), path)
        return path
    with _open_text(path, "w") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(table.columns)
        _write_rows(w, table)
    return path


def run_columns(rated: bool) -> tuple[str, ...]:
    """A run table's header: :data:`RUN_COLUMNS`, and ``rating`` when ``rated``."""
    return (*RUN_COLUMNS, "rating") if rated else RUN_COLUMNS


def csv_rows(table: RunTable) -> Iterator[tuple[object, ...]]:
    """The rows of ``table`` as a CSV run table writes them (floats with ``repr``)."""
    ratings = [] if table.rating is None else table.rating.tolist()
    for k, (s, o, sd, t, a, v) in enumerate(table.rows()):
        yield (s, o, sd, t, a, repr(v), *ratings[k : k + 1])


def _write_rows(w: Any, table: RunTable) -> None:
    w.writerows(csv_rows(table))


class RecordFile:
    """A text file written a record at a time, each record flushed and counted (``appended``),
    so that what was written survives what stops the rest; ``newline`` as :func:`open`'s.

    The file must be new (``FileExistsError`` naming it otherwise): one left by a sweep that
    stopped holds its finished runs, and was written over, then removed.  ``existing``: the
    file exists and already holds that many records (a sweep resumed from it): it is appended
    to, and counted from there."""

    def __init__(
        self, path: str | Path, newline: str | None = None, existing: int | None = None
    ) -> None:
        self.path = Path(path)
        self.appended = existing or 0
        mode = "x" if existing is None else "a"
        try:
            self._fh: IO[str] | None = open(self.path, mode, encoding="utf-8", newline=newline)  # noqa: SIM115
        except FileExistsError:
            raise FileExistsError(
                f"{self.path} already exists (the finished runs of a sweep that stopped?); "
                "move it away or give a new file: it would be written over"
            ) from None

    def _open(self) -> IO[str]:
        """The file, while it is open (ValueError once closed)."""
        if self._fh is None:
            raise ValueError(f"{self.path}: already closed")
        return self._fh

    def _recorded(self) -> None:
        """One more record written: flushed and counted."""
        self._open().flush()
        self.appended += 1

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None


class TableAppender(RecordFile):
    """A CSV run table (``.csv``) written a few rows at a time, e.g. each run of a study as it
    finishes (a :class:`RecordFile`); :func:`read_table` reads it.  ``rated``: with the
    ``rating`` column.  ``comment``: one line of text written first, as ``# comment`` (what
    wrote the table: :mod:`gaitpref.simulate.resume`; :func:`read_table` skips it).
    ``existing``: the table exists, its header and that many runs written, and is appended to
    (no header, no comment)."""

    def __init__(
        self,
        path: str | Path,
        rated: bool,
        comment: str | None = None,
        existing: int | None = None,
    ) -> None:
        if not Path(path).name.endswith(".csv"):
            raise ValueError(f"{Path(path)}: a table written row by row must end in .csv")
        if comment is not None and ("\n" in comment or "\r" in comment):
            raise ValueError(f"{Path(path)}: a table's comment is one line, got {comment!r}")
        super().__init__(path, newline="", existing=existing)
        self.rated = rated
        self._w = csv.writer(self._open(), lineterminator="\n")
        if existing is None:
            if comment is not None:
                self._open().write(f"{COMMENT}{comment}\n")
            self._w.writerow(run_columns(rated))
            self._open().flush()

    def append(self, table: RunTable) -> None:
        self._open()
        if (table.rating is not None) != self.rated:
            raise ValueError(f"{self.path}: rows with columns {table.columns} do not fit")
        _write_rows(self._w, table)
        self._recorded()


def read_table(path: str | Path) -> RunTable:
    """Read a run table written by :func:`write_table`."""
    path = Path(path)
    if _is_parquet(path):
        _, pq = _pyarrow()
        t = pq.read_table(path)
        rating = t.column("rating").to_numpy() if "rating" in t.column_names else None
        s, o, sd, tr, a, v = (t.column(c).to_numpy() for c in RUN_COLUMNS)
        return RunTable(s, o, sd, tr, a, v, rating)
    cols = _read_csv(path, RUN_COLUMNS, optional=("rating",), comment=True)
    objective, seed, trial, action = (np.array(c, dtype=np.intp) for c in cols[1:5])
    return RunTable(
        np.array(cols[0], dtype=str),
        objective,
        seed,
        trial,
        action,
        np.array(cols[5], dtype=float),
        None if cols[6] is None else np.array(cols[6], dtype=np.intp),
    )


def write_curves(curves: Curves, path: str | Path) -> Path:
    """Write curves as CSV with columns ``setting, trial, mean, se``."""
    path = Path(path)
    with _open_text(path, "w") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(CURVE_COLUMNS)
        for s, t, m, e in zip(
            curves.setting.tolist(),
            curves.trial.tolist(),
            curves.mean.tolist(),
            curves.se.tolist(),
            strict=True,
        ):
            w.writerow((s, t, f"{m:.6f}", f"{e:.6f}"))
    return path


def read_curves(path: str | Path, columns: Sequence[str] = CURVE_COLUMNS) -> Curves:
    """Read curves from CSV; ``columns`` names the file's setting, trial, mean and se columns."""
    cols = _read_csv(Path(path), tuple(columns))
    return Curves(
        np.array(cols[0], dtype=str),
        np.array(cols[1], dtype=np.intp),
        np.array(cols[2], dtype=float),
        np.array(cols[3], dtype=float),
    )


def _read_csv(
    path: Path, columns: tuple[str, ...], optional: tuple[str, ...] = (), comment: bool = False
) -> list[list[str]]:
    """The named columns' cells; an ``optional`` column the file lacks comes back as None;
    ``comment``: a first line starting with :data:`COMMENT` is skipped."""
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    with _open_text(path, "r") as fh:
        return _parse_csv(fh, columns, str(path), optional, comment)


def _parse_csv(
    fh: Any,
    columns: tuple[str, ...],
    where: str,
    optional: tuple[str, ...] = (),
    comment: bool = False,
) -> list[Any]:
    first = 1
    lines: Iterator[str] = iter(fh)
    if comment:
        top = next(lines, "")
        if top.startswith(COMMENT):
            first = 2
        else:
            lines = itertools.chain([top] if top else [], lines)
    reader = csv.reader(lines)
    header = next(reader, None)
    if header is None:
        raise ValueError(f"{where}: empty file")
    missing = [c for c in columns if c not in header]
    if missing:
        raise ValueError(f"{where}: missing column(s) {', '.join(missing)}; header is {header}")
    wanted = [*columns, *(c for c in optional if c in header)]
    idx = [header.index(c) for c in wanted]
    out: list[list[str]] = [[] for _ in wanted]
    for line, row in enumerate(reader, start=first + 1):
        if len(row) != len(header):
            raise ValueError(f"{where}:{line}: {len(row)} fields, header has {len(header)}")
        for k, i in enumerate(idx):
            out[k].append(row[i])
    found = dict(zip(wanted, out, strict=True))
    return [*out[: len(columns)], *(found.get(c) for c in optional)]
