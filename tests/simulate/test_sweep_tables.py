"""Run tables and curves: hand-computed summaries, exact file round trips, clear errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref.simulate.tables import (
    RunTable,
    read_curves,
    read_table,
    summarize,
    write_curves,
    write_table,
)


def table() -> RunTable:
    # setting a: 2 runs x 3 trials; setting b: 1 run x 3 trials
    return RunTable(
        np.array(["a"] * 6 + ["b"] * 3),
        np.array([0, 0, 0, 1, 1, 1, 0, 0, 0]),
        np.zeros(9, dtype=int),
        np.tile([1, 2, 3], 3),
        np.arange(9),
        np.array([0.1, 0.2, 0.3, 0.3, 0.6, 1 / 3, 0.5, 0.25, 1.0]),
    )


def test_summary_by_hand() -> None:
    c = summarize(table())
    assert c.settings == ("a", "b")
    t, m, se = c.curve("a")
    np.testing.assert_array_equal(t, [1, 2, 3])
    np.testing.assert_allclose(m, [0.2, 0.4, (0.3 + 1 / 3) / 2])
    # two runs: sd = |x1 - x2| / sqrt(2), se = sd / sqrt(2) = |x1 - x2| / 2
    np.testing.assert_allclose(se, [0.1, 0.2, abs(0.3 - 1 / 3) / 2])
    assert np.isnan(c.at("b", 2)[1]) and c.at("b", 2)[0] == 0.25
    with pytest.raises(KeyError, match="trial 4"):
        c.at("a", 4)
    with pytest.raises(KeyError, match="setting 'c'"):
        c.curve("c")


@pytest.mark.parametrize("name", ["runs.csv", "runs.csv.gz", "runs.parquet"])
def test_run_table_round_trips_exactly(tmp_path: Path, name: str) -> None:
    t = table()
    back = read_table(write_table(t, tmp_path / name))
    assert back.equals(t)


def test_curves_file_has_the_published_columns(tmp_path: Path) -> None:
    path = write_curves(summarize(table()), tmp_path / "curves.csv")
    assert path.read_text().splitlines()[0] == "setting,trial,mean,se"
    back = read_curves(path)
    np.testing.assert_allclose(back.curve("a")[1], summarize(table()).curve("a")[1], atol=1e-6)


def test_bad_files_and_tables_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"\.csv, \.csv\.gz or \.parquet"):
        write_table(table(), tmp_path / "runs.xlsx")
    bad = tmp_path / "bad.csv"
    bad.write_text("setting,trial,mean\nx,1,0.5\n")
    with pytest.raises(ValueError, match="missing column"):
        read_curves(bad)
    with pytest.raises(FileNotFoundError):
        read_table(tmp_path / "none.csv")
    with pytest.raises(ValueError, match="differ in length"):
        RunTable(np.array(["a"]), np.array([0, 1]), [0], [1], [0], [0.5])  # type: ignore[arg-type]


def test_matrix_refuses_ragged_runs() -> None:
    t = table()
    ragged = RunTable(
        t.setting[:5],
        t.objective[:5],
        t.seed[:5],
        t.trial[:5],
        t.action[:5],
        t.normalized_objective[:5],
    )
    with pytest.raises(ValueError, match=r"trials 1\.\.3"):
        ragged.matrix("a")


def test_compressed_tables_are_byte_for_byte_reproducible(tmp_path: Path) -> None:
    a = write_table(table(), tmp_path / "a.csv.gz").read_bytes()
    b = write_table(table(), tmp_path / "b.csv.gz").read_bytes()
    assert a == b
