"""``bench paper-2d`` and ``bench compass-gait`` refuse ``--backend``, ``--jobs``,
``--address`` and ``--table`` before they make the ``--out`` folder or build anything.

The run itself refused the first three, after the output folder was made: ``--jobs 0`` left
an empty ``--out`` folder behind.  ``bench compass-gait --objective hzd`` (no ``--library``)
made the folder and built its 24 gaits before ``--table xls`` was refused.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref.cli import app

BAD = [
    (["--backend", "foo"], "--backend must be one of"),
    (["--jobs", "0"], "Invalid value for '--jobs': 0 is neither a count"),
    (["--address", "localhost:1"], "address is for the Ray backend"),
    (["--table", "xls"], "--table must be csv"),
]


@pytest.mark.parametrize(("option", "message"), BAD)
@pytest.mark.parametrize("study", ["paper-2d", "compass-gait"])
def test_refused_before_the_output_folder_is_made(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, study: str, option: list[str], message: str
) -> None:
    import gaitpref.simulate.compass

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("a gait library was built before the options were checked")

    monkeypatch.setattr(gaitpref.simulate.compass, "compass_objective", never)
    out = tmp_path / "out"
    args = ["bench", study, "--runs", "1", "--trials", "2", "--out", str(out), *option]
    if study == "compass-gait":
        args += ["--objective", "hzd"]  # no --library: it would build one into --out
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert message in " ".join(result.output.split())
    assert not out.exists()


def test_notes_past_the_limit_are_refused_before_the_study(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--notes`` was read whole: ``--notes /dev/zero`` was a MemoryError traceback.  At most
    MAX_NOTES_BYTES (1 MB; lowered here to 10) are read."""
    import gaitpref.cli.simulate

    monkeypatch.setattr(gaitpref.cli.simulate, "MAX_NOTES_BYTES", 10)
    notes = tmp_path / "notes.md"
    out = tmp_path / "out"
    args = ["bench", "paper-2d", "--runs", "1", "--trials", "2", "--out", str(out)]
    notes.write_text("x" * 11, encoding="utf-8")
    result = CliRunner().invoke(app, [*args, "--notes", str(notes)])
    assert result.exit_code == 2, result.output
    assert f"--notes {str(notes)!r} is larger than" in " ".join(result.output.split())
    assert not out.exists()


@pytest.mark.parametrize("study", ["paper-2d", "compass-gait"])
def test_the_ray_backend_without_ray_is_refused_before_the_output_folder_is_made(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, study: str
) -> None:
    """Ray not installed was found only when the runs started: the progress bar drawn, the
    ``--out`` folder made (and ``compass-gait --objective hzd`` had built its gait library)."""
    import sys

    import gaitpref.simulate.compass

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("a gait library was built before the options were checked")

    monkeypatch.setattr(gaitpref.simulate.compass, "compass_objective", never)
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray: ImportError
    out = tmp_path / "out"
    args = ["bench", study, "--runs", "1", "--trials", "2", "--out", str(out), "--backend", "ray"]
    if study == "compass-gait":
        args += ["--objective", "hzd"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    text = " ".join(result.output.split())
    assert "--backend ray: the Ray backend needs Ray: pip install 'gaitpref[ray]'" in text
    assert not out.exists()


def test_negative_iterations_are_refused_by_name_before_a_gait_library_is_built(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--iterations 1,-5`` was refused by the posterior replay, after ``--objective hzd``
    had built its gait library, as 'iterations must be non-negative counts'."""
    import gaitpref.simulate.compass

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("a gait library was built before --iterations was checked")

    monkeypatch.setattr(gaitpref.simulate.compass, "compass_objective", never)
    out = tmp_path / "out"
    args = ["bench", "compass-gait", "--objective", "hzd", "--out", str(out)]
    result = CliRunner().invoke(app, [*args, "--iterations", "1,-5"])
    assert result.exit_code == 2, result.output
    assert "--iterations must be counts >= 0, got '1,-5'" in " ".join(result.output.split())
    assert not out.exists()


@pytest.mark.parametrize("study", ["paper-2d", "compass-gait"])
def test_a_ray_address_where_nothing_listens_is_refused_before_the_output_folder_is_made(
    tmp_path: Path, study: str
) -> None:
    """It was refused once the runs started: the progress bar drawn, an empty --out left."""
    import socket

    pytest.importorskip("ray")
    with socket.socket() as free:  # a port nothing listens on once closed
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]
    out = tmp_path / "out"
    args = ["bench", study, "--runs", "1", "--trials", "2", "--out", str(out), "--backend", "ray"]
    result = CliRunner().invoke(app, [*args, "--address", f"127.0.0.1:{port}"])
    assert result.exit_code == 2, result.output
    text = " ".join(result.output.split())
    assert f"--address: could not reach the Ray cluster at '127.0.0.1:{port}'" in text
    assert not out.exists()


@pytest.mark.parametrize("there", [False, True])
def test_a_ray_runtime_that_cannot_start_removes_the_empty_output_folder_it_made(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, there: bool
) -> None:
    """``--address auto`` with no cluster fails once the runs start (Ray answers at once, so
    it is not probed first): an --out the command made, still empty, is removed and said so;
    one that was there is left as it was (an empty folder was left behind and not named)."""
    pytest.importorskip("ray")
    from gaitpref.simulate import sweep

    def no_cluster(address: str | None = None, jobs: int | None = None) -> bool:
        raise RuntimeError(f"could not start or reach the Ray cluster at {address!r}: none.")

    monkeypatch.setattr(sweep, "start_ray", no_cluster)
    out = tmp_path / "out"
    if there:
        out.mkdir()
    args = ["bench", "paper-2d", "--runs", "1", "--trials", "2", "--out", str(out)]
    result = CliRunner().invoke(app, [*args, "--backend", "ray", "--address", "auto"])
    assert result.exit_code == 2, result.output
    text = " ".join(result.output.split())
    assert "could not start or reach the Ray cluster at 'auto': none" in text
    if there:
        assert "made by this command" not in text and list(out.iterdir()) == []
    else:
        assert f"none; --out '{out}', made by this command, was removed" in text
        assert not out.exists()
