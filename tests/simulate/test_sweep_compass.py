"""The compass-gait study: the authors' COT, posterior snapshots, the HZD library adapter."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest

from gaitpref.simulate.compass import (
    compass_gait_study,
    compass_objective,
    posterior_snapshots,
)
from gaitpref.simulate.hzd import build_cot_curve, library_objective, read_cot_curve
from gaitpref.simulate.objectives import cot_polynomial
from gaitpref.simulate.study import run_one

DATA = Path(__file__).parent / "data"


def test_cot_polynomial_matches_the_documented_values() -> None:
    assert cot_polynomial(0.08) == pytest.approx(0.0314, abs=5e-5)
    assert cot_polynomial(0.18) == pytest.approx(0.0263, abs=5e-5)
    x = np.linspace(0.08, 0.18, 10001)
    cot = cot_polynomial(x)
    assert x[np.argmin(cot)] == pytest.approx(0.133, abs=2e-3)  # "near 0.132 m"
    assert cot.min() == pytest.approx(0.0195, abs=5e-5)


def test_poly_objective_is_on_the_24_point_grid() -> None:
    obj = compass_objective("poly")
    x = obj.space.features[0].array
    assert x.size == 24 and x[0] == 0.08 and x[-1] == pytest.approx(0.18)
    np.testing.assert_allclose(obj.cot, cot_polynomial(x))
    with pytest.raises(ValueError, match="--library is for --objective hzd"):
        compass_objective("poly", "lib.csv")
    with pytest.raises(ValueError, match="objective must be 'poly' or 'hzd'"):
        compass_objective("spline")  # type: ignore[arg-type]


def test_study_minimizes_cot_with_n2_b0_and_a_random_floor() -> None:
    study = compass_gait_study(compass_objective(), runs=3, trials=10)
    first = study.settings[0]
    assert (first.name, first.n, first.buffer, first.coactive) == ("n2_b0", 2, 0, False)
    assert study.settings[1].strategy == "random"
    assert study.minimize and study.seeds == (0, 1, 2)
    assert study.kernel.variance == 1e-4 and study.noise == 0.01


def test_snapshots_replay_run_zero_of_the_study() -> None:
    study = compass_gait_study(compass_objective(), runs=1, trials=20, baseline=False)
    snaps = posterior_snapshots(study, (0, 3, 10), samples=3)
    assert [s.iteration for s in snaps] == [0, 3, 10]
    run = run_one(study.tasks()[0])
    for snap in snaps:
        np.testing.assert_array_equal(snap.trials, run.actions[: 2 * snap.iteration])
        assert snap.samples.shape == (3, 24) and snap.std.shape == (24,)
    assert np.all(snaps[0].mean == 0)  # the prior
    # the posterior mean peaks near the lowest COT after 10 iterations
    best = int(np.argmin(compass_objective().cot))
    assert abs(int(np.argmax(snaps[-1].mean)) - best) <= 2
    with pytest.raises(ValueError, match="iterations"):
        posterior_snapshots(study, (-1,))


def write_library(path: Path, x: np.ndarray, cot: np.ndarray, feasible: np.ndarray) -> Path:
    """A plain export (.csv or .npz) of a COT curve."""
    if path.suffix == ".csv":
        rows = ["step_length,cot,feasible"]
        rows += [
            f"{float(a)!r},{float(c)!r},{str(bool(f)).lower()}"
            for a, c, f in zip(x, cot, feasible, strict=True)
        ]
        path.write_text("\n".join(rows) + "\n")
    else:
        np.savez(path, step_length=x, cot=cot, feasible=feasible)
    return path


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_library_on_the_grid_keeps_the_grid(tmp_path: Path, suffix: str) -> None:
    grid = compass_objective().space
    x = grid.features[0].array
    cot = 0.007 + (x - 0.11) ** 2  # a U shape like the HZD prototype's
    path = write_library(tmp_path / f"lib{suffix}", x[::-1], cot[::-1], np.ones(24, bool))
    space, got, note = library_objective(read_cot_curve(path), grid)
    assert space is grid and note == ""
    np.testing.assert_allclose(got, cot)


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_library_drops_infeasible_gaits_and_says_so(tmp_path: Path, suffix: str) -> None:
    grid = compass_objective().space
    x = np.linspace(0.06, 0.20, 15)
    feasible = np.ones(15, bool)
    feasible[3] = False
    path = write_library(tmp_path / f"lib{suffix}", x, 1 + x, feasible)
    space, cot, note = library_objective(read_cot_curve(path), grid, "lib")
    kept = x[feasible & (x >= 0.08 - 1e-9) & (x <= 0.18 + 1e-9)]
    np.testing.assert_allclose(space.features[0].array, kept)
    np.testing.assert_allclose(cot, 1 + kept)
    assert "dropped 1 infeasible gait" in note and f"{x[3]:.4f}" in note
    assert (
        f"lib's {kept.size} step lengths differ" in note
        and "the library's own step lengths" in note
    )
    assert space.features[0].unit == "m"


def test_bad_library_files_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="no such gait library"):
        read_cot_curve(tmp_path / "none.csv")
    (tmp_path / "a.txt").write_text("x")
    with pytest.raises(ValueError, match=r"must be \.json \(or a \.csv/\.npz export\)"):
        read_cot_curve(tmp_path / "a.txt")
    (tmp_path / "b.csv").write_text("step_length,energy\n0.1,1\n")
    with pytest.raises(ValueError, match="missing field 'cot'"):
        read_cot_curve(tmp_path / "b.csv")
    (tmp_path / "c.csv").write_text("step_length,cot\n0.1,1\n0.1,2\n")
    with pytest.raises(ValueError, match="repeat"):
        read_cot_curve(tmp_path / "c.csv")
    (tmp_path / "d.csv").write_text("step_length,cot,feasible\n0.1,1,maybe\n")
    with pytest.raises(ValueError, match="feasible must be true/false"):
        read_cot_curve(tmp_path / "d.csv")
    np.savez(tmp_path / "e.npz", step_length=[0.1, 0.12], cot=[1.0])
    with pytest.raises(ValueError, match="equal length"):
        read_cot_curve(tmp_path / "e.npz")
    write_library(tmp_path / "f.csv", np.array([0.01, 0.3]), np.ones(2), np.ones(2, bool))
    with pytest.raises(ValueError, match="fewer than 2 feasible gaits"):
        library_objective(read_cot_curve(tmp_path / "f.csv"), compass_objective().space)


def test_unreadable_exports_are_refused_naming_the_file(tmp_path: Path) -> None:
    """A truncated .npz was a zipfile.BadZipFile traceback from bench compass-gait --library;
    object arrays and a .csv that is not UTF-8 were ValueErrors that did not name the file."""
    np.savez(tmp_path / "ok.npz", step_length=[0.1, 0.12], cot=[1.0, 2.0])
    whole = (tmp_path / "ok.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(whole[: len(whole) // 2])
    np.save(tmp_path / "pickled.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    (tmp_path / "pickled.npy").rename(tmp_path / "pickled.npz")
    (tmp_path / "latin.csv").write_bytes(b"step_length,cot\n0.1,\xff\n")
    for name in ("cut.npz", "pickled.npz", "latin.csv"):
        with pytest.raises(ValueError, match=f"{name}: cannot be read as"):
            read_cot_curve(tmp_path / name)
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(ValueError, match=r"empty.csv: empty file$"):
        read_cot_curve(tmp_path / "empty.csv")


def test_a_library_file_written_by_the_gait_library_branch() -> None:
    """``data/gait-library-6.json``: ``build_library(linspace(0.08, 0.18, 6), speed=0.2)`` saved
    by ``gaitpref.gaits`` (its ``cot_over_step_length`` gave these values when it was built)."""
    x, cot, feasible = read_cot_curve(DATA / "gait-library-6.json")
    np.testing.assert_allclose(x, np.linspace(0.08, 0.18, 6))
    np.testing.assert_allclose(
        cot, [0.02546976, 0.00971932, 0.0078689, 0.01076695, 0.01455892, 0.01873395], rtol=1e-6
    )
    assert feasible.all()


def test_a_saved_library_that_is_not_one_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "lib.json"
    path.write_text(json.dumps({"speed": 0.2, "gaits": []}))
    with pytest.raises(ValueError, match=r"gait library .*lib\.json"):
        read_cot_curve(path)


def test_building_a_small_library_gives_what_reading_it_back_gives(tmp_path: Path) -> None:
    x = np.array([0.09, 0.13, 0.17])
    built = build_cot_curve(x, save=tmp_path / "lib.json")
    back = read_cot_curve(tmp_path / "lib.json")
    for a, b in zip(built, back, strict=True):
        np.testing.assert_array_equal(a, b)
    assert built[2].all() and built[1][1] < min(built[1][0], built[1][2])  # U-shaped COT


def test_a_cot_curve_file_over_the_size_limit_is_refused_before_it_is_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A .csv or .npz COT curve of any size was read whole."""
    from gaitpref.simulate import hzd

    path = tmp_path / "curve.csv"
    path.write_text("step_length,cot\n0.1,1\n0.2,2\n")
    size = path.stat().st_size
    monkeypatch.setattr(hzd, "MAX_CURVE_BYTES", size - 1)
    with pytest.raises(ValueError, match=rf"curve\.csv: holds {size} bytes, more than the"):
        read_cot_curve(path)
    monkeypatch.setattr(hzd, "MAX_CURVE_BYTES", size)
    assert read_cot_curve(path)[0].tolist() == [0.1, 0.2]


def test_an_npz_that_unpacks_past_the_limit_is_refused_unread(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A small compressed .npz ("zip bomb") was unpacked whole, and a header claiming a huge
    shape allocated it before failing."""
    import zipfile

    from gaitpref.simulate import hzd

    bomb = tmp_path / "bomb.npz"
    np.savez_compressed(bomb, step_length=np.zeros(1_000_000), cot=np.zeros(1_000_000))
    assert bomb.stat().st_size < 100_000
    monkeypatch.setattr(hzd, "MAX_CURVE_BYTES", 1_000_000)
    with pytest.raises(ValueError, match=r"bomb\.npz: its arrays unpack to 16,000,\d+ bytes"):
        read_cot_curve(bomb)

    liar = tmp_path / "liar.npz"
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (10**9,)}
    )
    with zipfile.ZipFile(liar, "w") as z:
        z.writestr("step_length.npy", header.getvalue() + b"\0" * 8)
    with pytest.raises(ValueError, match=r"step_length\.npy: its header claims shape"):
        read_cot_curve(liar)
