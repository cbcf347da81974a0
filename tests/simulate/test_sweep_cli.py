"""``gaitpref bench ...`` end to end on tiny studies."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.simulate.objectives import cot_polynomial
from gaitpref.simulate.tables import read_curves, read_table

runner = CliRunner()


def invoke(*args: str) -> tuple[int, str]:
    result = runner.invoke(app, ["bench", *args])
    return result.exit_code, result.output


def test_paper_2d_writes_every_output(tmp_path: Path) -> None:
    code, out = invoke(
        "paper-2d",
        "--runs",
        "2",
        "--trials",
        "12",
        "--settings",
        "n1_b1,n1_b1_coactive",
        "--jobs",
        "1",
        "--out",
        str(tmp_path),
        "--table",
        "parquet",
    )
    assert code == 0, out
    assert "(joblib, 1 job)" in " ".join(out.split())  # '1 jobs'
    curves = read_curves(tmp_path / "curves.csv")
    assert curves.settings == ("n1_b1", "n1_b1_coactive", "random")
    table = read_table(tmp_path / "runs.parquet")
    assert len(table) == 3 * 2 * 12 and set(table.objective.tolist()) == {0, 1}
    summary = (tmp_path / "summary.md").read_text()
    assert "| n1_b1_coactive | 10 |" in summary and "## Timing" in summary
    assert (tmp_path / "curves.png").stat().st_size > 10_000


def test_paper_2d_refuses_bad_options(tmp_path: Path) -> None:
    code, out = invoke("paper-2d", "--settings", "n9_b9", "--out", str(tmp_path))
    assert code == 2 and "unknown setting 'n9_b9'" in out
    code, out = invoke("paper-2d", "--runs", "1", "--backend", "dask", "--out", str(tmp_path))
    assert code == 2 and "--backend must be one of joblib, ray" in out
    code, out = invoke("paper-2d", "--table", "xlsx", "--out", str(tmp_path))
    assert code == 2 and "--table must be csv, csv.gz or parquet" in out
    assert not (tmp_path / "summary.md").exists()


def test_settings_naming_random_selection_alone_are_refused_before_the_study(
    tmp_path: Path,
) -> None:
    """``--settings random`` ran the study, wrote runs.csv and curves.csv, then died drawing
    the figure (a panel per paper setting, none named) with a ValueError traceback, status 1."""
    args = ("--runs", "1", "--trials", "3", "--jobs", "1", "--settings", "random")
    code, out = invoke("paper-2d", *args, "--out", str(tmp_path / "out"))
    assert code == 2 and "settings name only 'random'" in " ".join(out.split()), out
    assert "Traceback" not in out and not (tmp_path / "out").exists()


@pytest.mark.parametrize("given", [[","], ["", " , "]])
def test_a_settings_list_that_names_none_is_refused(tmp_path: Path, given: list[str]) -> None:
    """``--settings ,`` split to no name and silently ran all six settings."""
    args = [a for v in given for a in ("--settings", v)]
    code, out = invoke("paper-2d", *args, "--runs", "1", "--trials", "2", "--out", str(tmp_path))
    assert code == 2 and "--settings names nothing" in out, out
    assert not (tmp_path / "runs.csv").exists()


def test_paper_2d_on_ray(tmp_path: Path, ray_runtime: None) -> None:
    code, out = invoke(
        "paper-2d",
        "--runs",
        "2",
        "--trials",
        "8",
        "--settings",
        "n2_b0",
        "--backend",
        "ray",
        "--jobs",
        "2",
        "--out",
        str(tmp_path),
    )
    assert code == 0, out
    assert "(ray, 2 jobs)" in " ".join(out.split())
    assert read_table(tmp_path / "runs.csv").settings == ("n2_b0", "random")


def test_compass_gait_poly_and_hzd(tmp_path: Path) -> None:
    code, out = invoke(
        "compass-gait",
        "--runs",
        "2",
        "--trials",
        "10",
        "--iterations",
        "1,3",
        "--jobs",
        "1",
        "--out",
        str(tmp_path / "poly"),
    )
    assert code == 0, out
    said = " ".join(out.split())  # it named neither the backend nor the workers
    assert "(joblib, 1 job); wrote" in said and "gait-library.json" not in said
    assert read_curves(tmp_path / "poly" / "curves.csv").settings == ("n2_b0", "random")
    assert (tmp_path / "poly" / "posterior.png").is_file()

    x = np.linspace(0.07, 0.19, 13)
    lib = tmp_path / "library.npz"
    np.savez(lib, step_length=x, cot=cot_polynomial(x) * 0.4)
    code, out = invoke(
        "compass-gait",
        "--objective",
        "hzd",
        "--library",
        str(lib),
        "--runs",
        "1",
        "--trials",
        "6",
        "--iterations",
        "2",
        "--jobs",
        "1",
        "--out",
        str(tmp_path / "hzd"),
    )
    assert code == 0, out
    assert "the library's own step lengths" in " ".join(out.split())
    table = read_table(tmp_path / "hzd" / "runs.csv")
    assert table.action.max() < 11  # the library's 11 step lengths within [0.08, 0.18] m


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--objective", "hzd", "--library", "none.json"), "no such gait library"),
        (("--objective", "spline"), "--objective must be 'poly' or 'hzd'"),
        (("--iterations", "a,b"), "--iterations must be comma-separated integers"),
        (("--iterations", ","), "--iterations must be comma-separated integers, got none"),
    ],
)
def test_compass_gait_refuses_bad_options(
    tmp_path: Path, args: tuple[str, ...], message: str
) -> None:
    code, out = invoke("compass-gait", *args, "--out", str(tmp_path))
    assert code == 2 and message in " ".join(out.split())


def test_an_out_that_is_a_file_and_unreadable_notes_are_refused_by_option(tmp_path: Path) -> None:
    """A FileExistsError traceback for --out naming a file; notes that are not UTF-8 gave the
    codec's message without the file."""
    afile = tmp_path / "afile"
    afile.write_text("x")
    for command in ("paper-2d", "compass-gait"):
        code, out = invoke(command, "--runs", "1", "--trials", "2", "--out", str(afile))
        assert code == 2 and f"--out '{afile}' is a file, not a folder" in " ".join(out.split())
    notes = tmp_path / "notes.md"
    notes.write_bytes(b"\xff\xfe")
    code, out = invoke("paper-2d", "--runs", "1", "--notes", str(notes), "--out", str(tmp_path))
    assert code == 2 and f"--notes '{notes}' is not UTF-8 text" in " ".join(out.split())


def test_array_files_that_are_not_one_array_are_refused_naming_the_file(tmp_path: Path) -> None:
    """A file that looks like a zip but is not one raised BadZipFile (a traceback) in simulate,
    bench population and compass-gait --library; an .npz archive given for one array was
    iterated as its names ('could not convert string to float')."""
    import numpy as np

    from gaitpref.cli.main import app as root

    notzip = tmp_path / "notzip.npy"
    notzip.write_bytes(b"PK\x03\x04garbage")
    archive = tmp_path / "archive.npy"
    with archive.open("wb") as fh:
        np.savez(fh, a=np.zeros(3))
    for path, message in (
        (notzip, "is not a readable .npy array"),
        (archive, "is an .npz archive"),
    ):
        for args in (
            ["simulate", "synthetic-2d", "--objective", str(path), "--trials", "2"],
            ["bench", "population", "--objectives", str(path), "--trials", "2"],
        ):
            result = runner.invoke(root, args)
            assert result.exit_code == 2, result.output
            assert f"'{path}' {message}" in " ".join(result.output.split())
    library = tmp_path / "lib.npz"
    library.write_bytes(b"PK\x03\x04garbage")
    code, out = invoke("compass-gait", "--objective", "hzd", "--library", str(library),
                       "--runs", "1", "--trials", "2", "--out", str(tmp_path / "o"))  # fmt: skip
    assert code == 2 and "lib.npz: cannot be read as npz" in out


def test_array_files_whose_header_the_file_does_not_hold_or_not_of_numbers_are_refused(
    tmp_path: Path,
) -> None:
    """A 200-byte .npy whose header says (10**9,) made simulate allocate 7.45 GiB before it
    found the data missing (a MemoryError traceback where memory is limited); a structured
    array gave a TypeError traceback and a complex one ran with its imaginary parts dropped."""
    import tracemalloc

    import numpy as np

    from gaitpref.cli.main import app as root

    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (1000000000,), }"
    header = header.ljust(117) + "\n"
    liar = tmp_path / "liar.npy"
    liar.write_bytes(b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode())
    record = tmp_path / "record.npy"
    np.save(record, np.zeros((5, 5), dtype=[("x", "f8")]))
    complex_ = tmp_path / "complex.npy"
    np.save(complex_, np.zeros((5, 5), complex))
    for path, message in (
        (liar, "is not a readable .npy array"),
        (record, "holds [('x', '<f8')] values; give an array of real numbers"),
        (complex_, "holds complex128 values; give an array of real numbers"),
    ):
        for args in (
            ["simulate", "synthetic-2d", "--objective", str(path), "--trials", "2"],
            ["bench", "population", "--objectives", str(path), "--trials", "2"],
        ):
            tracemalloc.start()
            try:
                result = runner.invoke(root, args)
                peak = tracemalloc.get_traced_memory()[1]
            finally:
                tracemalloc.stop()
            assert result.exit_code == 2, result.output
            assert f"'{path}' {message}" in " ".join(result.output.split())
            assert peak < 2**30, peak


def test_parquet_without_pyarrow_is_refused_before_the_study_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """It ran the whole study, then failed with a RuntimeError traceback, writing nothing."""
    import sys

    monkeypatch.setitem(sys.modules, "pyarrow", None)  # import pyarrow: ImportError
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    code, out = invoke("paper-2d", "--runs", "1", "--trials", "2", "--settings", "n1_b1",
                       "--table", "parquet", "--out", str(tmp_path))  # fmt: skip
    assert code == 2 and "--table parquet: writing Parquet needs pyarrow" in " ".join(out.split())
    assert "runs in" not in out and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("command", "name"),
    [("paper-2d", "runs.csv"), ("paper-2d", "summary.md"), ("compass-gait", "posterior.png")],
)
def test_a_folder_where_an_output_goes_is_refused_before_the_study(
    tmp_path: Path, command: str, name: str
) -> None:
    """The study ran, then died writing that file with an IsADirectoryError traceback, and its
    partial run table had been removed: every run's result lost."""
    (tmp_path / name).mkdir()
    code, out = invoke(
        command, "--runs", "1", "--trials", "3", "--jobs", "1", "--out", str(tmp_path)
    )
    assert code == 2, out
    assert f"--out '{tmp_path}': {name} is a folder" in " ".join(out.split())
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_results_that_cannot_be_written_keep_the_run_table(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A file that cannot be written after the study finished (a full disk): status 1 and the
    run table kept in runs.partial.csv, not a traceback with every run lost."""
    import gaitpref.simulate.figures as figures

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(28, "No space left on device", str(tmp_path / "curves.png"))

    monkeypatch.setattr(figures, "plot_paper_2d", full)
    args = ("--runs", "2", "--trials", "3", "--settings", "n1_b1", "--jobs", "1")
    code, out = invoke("paper-2d", *args, "--out", str(tmp_path))
    assert code == 1, out
    text = " ".join(out.split())
    assert "results could not be written (No space left on device:" in text
    assert f"the run table is kept in {tmp_path / 'runs.partial.csv'}" in text
    kept = read_table(tmp_path / "runs.partial.csv")
    assert len(kept) == 2 * 2 * 3 and kept.equals(read_table(tmp_path / "runs.csv"))


@pytest.mark.parametrize("command", ["paper-2d", "compass-gait"])
def test_an_earlier_studys_results_in_out_are_not_written_over(
    tmp_path: Path, command: str
) -> None:
    """A second study into the same --out (a quick test with the default out/paper-2d after a
    study of hours) wrote over the first's run table, curves and figures without a word."""
    args = ("--runs", "1", "--trials", "3", "--jobs", "1", "--out", str(tmp_path))
    code, out = invoke(command, *args)
    assert code == 0, out
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    code, out = invoke(command, *args, "--seed", "1", "--table", "parquet")
    assert code == 2, out
    text = " ".join(out.split())
    assert f"--out '{tmp_path}' holds an earlier study's results (runs.csv, curves.csv" in text
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_a_gait_library_left_in_out_is_built_again_but_not_a_folder_in_its_place(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """--objective hzd without --library saves OUT/gait-library.json, the config's library
    built again the same: one there is no earlier study's result (docs/results/README.md)."""
    import gaitpref.simulate.compass

    def built(*args: object, **kwargs: object) -> None:
        raise ValueError("built")  # the options passed: the library would be built now

    monkeypatch.setattr(gaitpref.simulate.compass, "compass_objective", built)
    (tmp_path / "gait-library.json").write_text("{}", encoding="utf-8")
    args = ("--objective", "hzd", "--runs", "1", "--trials", "3", "--out", str(tmp_path))
    code, out = invoke("compass-gait", *args)
    assert code == 2 and "error: built" in out, out
    (tmp_path / "gait-library.json").unlink()
    (tmp_path / "gait-library.json").mkdir()
    code, out = invoke("compass-gait", *args)
    assert code == 2 and "gait-library.json is a folder" in " ".join(out.split()), out


def test_a_gait_library_built_is_named_among_the_files_written(tmp_path: Path) -> None:
    """--objective hzd without --library saves OUT/gait-library.json: the last line listed the
    other files only."""
    args = ("--objective", "hzd", "--runs", "1", "--trials", "3", "--iterations", "1")
    code, out = invoke("compass-gait", *args, "--jobs", "1", "--out", str(tmp_path))
    assert code == 0, out
    assert "posterior.png, gait-library.json" in " ".join(out.split())
    assert (tmp_path / "gait-library.json").is_file()
