"""``gaitpref bench population --partial FILE --resume``: a bench that stopped continues from the
runs in its partial file (each cold run's line holds the preferences the warm runs start from)
and prints the JSON of a bench that never stopped, byte for byte; a file of other options is
refused naming what differs; a last line cut short is dropped with a warning."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from gaitpref.config import load_config
from gaitpref.simulate.population import population_bench
from tests.simulate.resumekit import (
    POPULATION,
    break_subject,
    check_resume_needs_an_existing_partial_file,
    invoke,
    population_objectives,
    read_lines,
    resume,
    write_lines,
)


@pytest.fixture()
def objectives(tmp_path: Path) -> Path:
    return population_objectives(tmp_path)


@pytest.fixture()
def args(objectives: Path) -> list[str]:
    return ["bench", "population", "--objectives", str(objectives), "--trials", "4",
            "--config", POPULATION, "--json"]  # fmt: skip


def _runs(path: Path) -> list[tuple[str, int]]:
    lines = [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]
    assert lines[0]["gaitpref bench"]["bench"] == "population"
    return [(r["run"], r["subject"]) for r in lines[1:]]


def _stopped(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, subject: int, arm: str
) -> Path:
    """The bench run with ``--partial tmp_path/kept.jsonl`` and subject ``subject``'s ``arm`` run
    failing: it stops (status 1), the finished runs in that file, which is returned."""
    partial = tmp_path / "kept.jsonl"
    break_subject(monkeypatch, subject, arm)
    assert invoke(*args, "--partial", str(partial))[0] == 1
    return partial


@pytest.mark.parametrize(
    ("arm", "subject", "kept", "rerun"),
    [
        ("cold", 2, [("cold", 0), ("cold", 1)], [("cold", 2), ("warm", 0), ("warm", 1),
                                                  ("warm", 2)]),
        ("warm", 1, [("cold", 0), ("cold", 1), ("cold", 2), ("warm", 0)], [("warm", 1),
                                                                           ("warm", 2)]),
    ],
)  # fmt: skip
def test_a_resumed_bench_prints_the_uninterrupted_json(
    args: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    arm: str,
    subject: int,
    kept: list[tuple[str, int]],
    rerun: list[tuple[str, int]],
) -> None:
    """Stopped in the cold runs, the warm runs start from the kept cold runs' preferences read
    back from the file; stopped in the warm runs, only the rest run."""
    code, whole, err = invoke(*args)
    assert code == 0, err
    partial = tmp_path / "kept.jsonl"
    break_subject(monkeypatch, subject, arm)
    code, out, err = invoke(*args, "--partial", str(partial))
    assert code == 1 and out == "", err
    assert f"subject {subject} ({arm}), seed 0 failed (ValueError): the subject left" in err
    assert f"the same command with --partial '{partial}' --resume continues the bench" in err
    assert _runs(partial) == kept
    monkeypatch.undo()
    ran = break_subject(monkeypatch, -1, "cold")  # none breaks now; which runs run is recorded
    code, out, err = resume(args, partial)
    assert code == 0, err
    assert ran == rerun
    assert out == whole  # byte for byte
    assert not partial.exists()


def test_stopped_twice_and_resumed_on_two_processes(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    code, whole, _ = invoke(*args)
    partial = _stopped(args, tmp_path, monkeypatch, 1, "cold")
    monkeypatch.undo()
    break_subject(monkeypatch, 0, "warm")
    code, _, err = resume(args, partial)
    assert code == 1, err
    assert f"3 of 6 runs finished; their results are in {partial}" in err
    assert _runs(partial) == [("cold", 0), ("cold", 1), ("cold", 2)]
    monkeypatch.undo()
    code, out, err = resume(args, partial, "--jobs", "2")
    assert code == 0, err
    assert out == whole


def test_a_last_line_cut_short_is_dropped_with_a_warning(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The machine died writing subject 1's cold line: it is dropped and that run runs again."""
    code, whole, _ = invoke(*args)
    partial = _stopped(args, tmp_path, monkeypatch, 2, "cold")
    data = partial.read_bytes()
    partial.write_bytes(data[:-10])
    monkeypatch.undo()
    ran = break_subject(monkeypatch, -1, "cold")
    code, out, err = resume(args, partial)
    assert code == 0, err
    assert f"warning: {partial}:3: the last line is cut short" in err
    assert ran == [("cold", 1), ("cold", 2), ("warm", 0), ("warm", 1), ("warm", 2)]
    assert out == whole


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (["--trials", "5"], "trials differs: 4 in the file, 5 here"),
        (["--seed", "1"], "seed differs: 0 in the file, 1 here"),
        (["--tolerance", "0.1"], "tolerance differs: 0.05 in the file, 0.1 here"),
        (["--user-noise", "0.01"], "user_noise differs: 0.0 in the file, 0.01 here"),
    ],
)
def test_a_file_of_other_options_is_refused_naming_them(
    args: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    change: list[str],
    message: str,
) -> None:
    partial = _stopped(args, tmp_path, monkeypatch, 1, "warm")
    kept = partial.read_bytes()
    ran = break_subject(monkeypatch, -1, "cold")
    code, _, err = resume(args, partial, *change)
    assert code == 2, err
    assert f"{partial} holds the finished runs of another bench: {message}" in err
    assert ran == [] and partial.read_bytes() == kept


def test_another_config_text_is_refused(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = _stopped(args, tmp_path, monkeypatch, 1, "warm")
    edited = tmp_path / "edited.toml"
    edited.write_text(load_config(POPULATION).text + "\n# edited\n", encoding="utf-8")
    code, _, err = invoke(*args, "--config", str(edited), "--partial", str(partial), "--resume")
    assert code == 2, err
    assert f"{partial} holds the finished runs of another bench: config_sha256 differs" in err


def test_another_objectives_file_is_refused(
    args: list[str], objectives: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = _stopped(args, tmp_path, monkeypatch, 1, "warm")
    kept = partial.read_bytes()
    values = np.load(objectives)
    values[2] = values[2][::-1]
    np.save(objectives, values)
    code, _, err = resume(args, partial)
    assert code == 2, err
    assert f"{partial} holds the finished runs of another bench: objectives_sha256 differs" in err
    assert partial.read_bytes() == kept


def test_a_file_of_bench_continuous_is_refused(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = _stopped(args, tmp_path, monkeypatch, 1, "warm")
    lines = read_lines(partial)
    first = json.loads(lines[0])
    first["gaitpref bench"]["bench"] = "continuous"
    partial.write_text(json.dumps(first) + "\n" + "".join(lines[1:]), encoding="utf-8")
    code, _, err = resume(args, partial)
    assert code == 2, err
    assert 'bench differs: "continuous" in the file, "population" here' in err


def test_a_damaged_line_is_refused_naming_it(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = _stopped(args, tmp_path, monkeypatch, 1, "warm")
    lines = read_lines(partial)
    cold = json.loads(lines[2])
    assert (cold["run"], cold["subject"]) == ("cold", 1)
    del cold["preferences"]["loser"][0]  # one preference short
    lines[2] = json.dumps(cold) + "\n"
    write_lines(partial, lines)
    code, _, err = resume(args, partial)
    assert code == 2, err
    assert f"{partial}:3: not a run record of bench population (subject 1, cold)" in err
    lines[2] = lines[1]
    write_lines(partial, lines)
    code, _, err = resume(args, partial)
    assert code == 2 and f"{partial}:3: the cold run of subject 0 is in the file twice" in err
    lines[2] = '{"subject": 7, "run": "cold"}\n'
    write_lines(partial, lines)
    code, _, err = resume(args, partial)
    assert code == 2 and f"{partial}:3: not a run of this bench (subjects 0..2" in err


def test_resume_needs_an_existing_partial_file(args: list[str], tmp_path: Path) -> None:
    check_resume_needs_an_existing_partial_file(args, tmp_path)


def test_population_bench_resumes_from_python(
    objectives: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``population_bench(..., partial=PATH, resume=True)`` returns the uninterrupted result."""
    cfg, values = load_config(POPULATION), np.load(objectives)
    whole = population_bench(cfg, values, 3, samples=50)
    partial = tmp_path / "kept.jsonl"
    break_subject(monkeypatch, 2, "cold")
    with pytest.raises(RuntimeError):
        population_bench(cfg, values, 3, samples=50, partial=partial)
    monkeypatch.undo()
    with pytest.raises(ValueError, match="resume: give the partial file"):
        population_bench(cfg, values, 3, samples=50, resume=True)
    with pytest.raises(FileNotFoundError):
        population_bench(cfg, values, 3, samples=50, partial=tmp_path / "no.jsonl", resume=True)
    resumed = population_bench(cfg, values, 3, samples=50, partial=partial, resume=True)
    assert json.dumps(resumed) == json.dumps(whole)
    assert not partial.exists()
