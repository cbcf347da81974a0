"""Gait library: grid order, ids, features, file round trip and validation errors."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, Space
from gaitpref.gaits import (
    SCHEMA_VERSION,
    GaitLibrary,
    GaitLibraryError,
    build_library,
    load_library,
)
from gaitpref.gaits.library import grid_size


def _document(lib: GaitLibrary, tmp_path: Path) -> dict[str, Any]:
    path = tmp_path / "lib.json"
    lib.save(path)
    data: dict[str, Any] = json.loads(path.read_text())
    return data


def _write(tmp_path: Path, data: dict[str, Any]) -> Path:
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(data))
    return path


def test_grid_order_matches_space(duration_library: GaitLibrary) -> None:
    lib = duration_library
    space = Space(lib.features())
    assert lib.shape == space.shape == (3, 2)
    for i in range(len(lib)):
        assert lib.parameters(i) == space.values_of(i)
        assert lib.gait(i).step_length == lib.parameters(i)["step_length"]
        named: dict[str, Any] = lib.parameters(i)  # by name, as keyword arguments
        assert lib.index(**named) == i == space.index(lib.parameters(i))
    # C order: the last axis (duration) varies fastest
    assert lib.parameters(1) == {"step_length": 0.10, "step_duration": 1.15}
    assert lib.lookup(step_length=0.13, step_duration=0.85) is lib.gait(2)


def test_features_ids_and_cot_grid(
    duration_library: GaitLibrary, speed_library: GaitLibrary
) -> None:
    length, duration = duration_library.features()
    assert isinstance(length, Feature)
    assert (length.name, length.unit, length.coactive) == ("step_length", "m", (0.1, 0.2))
    assert (duration.name, duration.unit, duration.words) == (
        "step_duration",
        "s",
        ("slower", "faster"),
    )
    width = speed_library.features()[1]
    assert (width.name, width.unit, width.coactive) == ("step_width", "m", (0.2, 0.4))
    assert duration_library.gait_id(2) == "L0.130-T0.850"
    assert speed_library.gait_id(1) == "L0.080-V0.200-W0.300"
    assert duration_library.index_of_id("L0.160-T1.150") == 5
    grid = duration_library.cot_grid()
    assert grid.shape == (3, 2)
    assert grid[1, 0] == duration_library.lookup(step_length=0.13, step_duration=0.85).cot
    # a width label does not change the gait
    assert np.array_equal(speed_library.cot_grid()[:, 0], speed_library.cot_grid()[:, 1])


def test_lookup_errors_name_the_problem(duration_library: GaitLibrary) -> None:
    with pytest.raises(GaitLibraryError, match="off the grid"):
        duration_library.gait(6)
    with pytest.raises(GaitLibraryError, match="not a grid value"):
        duration_library.lookup(step_length=0.11, step_duration=0.85)
    with pytest.raises(GaitLibraryError, match="missing"):
        duration_library.lookup(step_length=0.10)
    with pytest.raises(GaitLibraryError, match="no gait with id"):
        duration_library.index_of_id("L9.000-T1.000")


def test_save_load_round_trip(duration_library: GaitLibrary, tmp_path: Path) -> None:
    path = tmp_path / "lib.json"
    duration_library.save(path)
    loaded = GaitLibrary.load(path)
    assert loaded.axes == duration_library.axes and loaded.speed is None
    assert loaded.params == duration_library.params
    assert loaded.settings == duration_library.settings
    for a, b in zip(loaded.gaits, duration_library.gaits, strict=True):
        np.testing.assert_array_equal(a.alpha, b.alpha)
        np.testing.assert_array_equal(a.orbit_state, b.orbit_state)
        assert (a.cot, a.step_duration, a.delta_squared, a.message) == (
            b.cot, b.step_duration, b.delta_squared, b.message
        )  # fmt: skip
    data = json.loads(path.read_text())
    assert data["schema_version"] == SCHEMA_VERSION and data["grid_order"] == "C"
    assert data["gaits"][2]["id"] == "L0.130-T0.850"


def test_wrong_schema_version_is_refused(duration_library: GaitLibrary, tmp_path: Path) -> None:
    data = _document(duration_library, tmp_path)
    data["schema_version"] = 99
    with pytest.raises(GaitLibraryError, match="schema_version: 99 is not supported"):
        load_library(_write(tmp_path, data))


def test_bad_shapes_are_refused(duration_library: GaitLibrary, tmp_path: Path) -> None:
    data = _document(duration_library, tmp_path)
    data["gaits"][3]["alpha"] = [data["gaits"][3]["alpha"][0][:-1]]
    with pytest.raises(GaitLibraryError, match=r"gaits\[3\]\.alpha: expected shape \(1, 7\)"):
        load_library(_write(tmp_path, data))
    data = _document(duration_library, tmp_path)
    data["gaits"][0]["orbit_state"] = [0.0, 1.0]
    with pytest.raises(GaitLibraryError, match=r"gaits\[0\]\.orbit_state"):
        load_library(_write(tmp_path, data))
    data = _document(duration_library, tmp_path)
    data["gaits"].pop()
    with pytest.raises(GaitLibraryError, match="5 gaits for a grid of 6 points"):
        load_library(_write(tmp_path, data))


def test_inconsistent_or_missing_fields_are_refused(
    duration_library: GaitLibrary, tmp_path: Path
) -> None:
    data = _document(duration_library, tmp_path)
    del data["gaits"][1]["cot"]
    with pytest.raises(GaitLibraryError, match=r"gaits\[1\]\.cot: missing"):
        load_library(_write(tmp_path, data))
    data = _document(duration_library, tmp_path)
    data["gaits"][1]["step_duration"] = 0.5
    with pytest.raises(GaitLibraryError, match="step duration"):
        load_library(_write(tmp_path, data))
    data = _document(duration_library, tmp_path)
    data["format"] = "something-else"
    with pytest.raises(GaitLibraryError, match="not a gait library"):
        load_library(_write(tmp_path, data))


def test_infeasible_gaits_are_refused_unless_allowed(
    duration_library: GaitLibrary, tmp_path: Path
) -> None:
    data = _document(duration_library, tmp_path)
    data["gaits"][4]["feasible"] = False
    data["gaits"][4]["solver_message"] = "infeasible: normal force violated"
    path = _write(tmp_path, data)
    with pytest.raises(GaitLibraryError, match=r"1 of 6 gaits are infeasible.*L0\.160-T0\.850"):
        load_library(path)
    lib = load_library(path, allow_infeasible=True)
    assert lib.infeasible() == [4]
    assert np.isnan(lib.cot_grid()[2, 0])


def test_missing_and_corrupt_files(tmp_path: Path) -> None:
    with pytest.raises(GaitLibraryError, match="no such gait library file"):
        load_library(tmp_path / "absent.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(GaitLibraryError, match="not valid JSON"):
        load_library(bad)


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),  # a RecursionError before
        ('{"format": ' + "1" * 5000 + "}", "4300 digits"),  # a bare ValueError before
    ],
)
def test_json_past_the_parsers_limits_is_a_library_error(
    tmp_path: Path, text: str, why: str
) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text(text)
    with pytest.raises(GaitLibraryError, match=f"bad.json: not valid JSON.*{why}"):
        load_library(bad)


@pytest.mark.parametrize(
    ("field", "where"),
    [
        ('"cot": ', "gaits[0].cot"),
        ('"speed": ', "speed"),
        ('"alpha": [[', "gaits[0].alpha"),
        ('"values": [', "axes[0].values"),
        ('"leg_mass": ', "model.parameters"),
        ('"clearance": ', "formulation"),
    ],
)
def test_an_integer_past_a_floats_range_is_a_library_error(
    speed_library: GaitLibrary, tmp_path: Path, field: str, where: str
) -> None:
    """An OverflowError traceback before (gaits show, a config's library)."""
    path = tmp_path / "lib.json"
    speed_library.save(path)
    text = json.dumps(json.loads(path.read_text()))  # one line: '"alpha": [[-0.1, ...'
    huge = "1" + "0" * 400
    start = text.index(field) + len(field)
    end = min(text.index(c, start) for c in ",]" if c in text[start:])
    path.write_text(text[:start] + huge + text[end:])
    with pytest.raises(GaitLibraryError, match=f"lib.json: {re.escape(where)}"):
        load_library(path)


def test_a_failed_save_leaves_no_file_behind(duration_library: GaitLibrary, tmp_path: Path) -> None:
    target = tmp_path / "lib.json"
    target.mkdir()  # the rename onto it fails
    with pytest.raises(OSError):
        duration_library.save(target)
    assert [p.name for p in tmp_path.iterdir()] == ["lib.json"] and target.is_dir()
    assert not list(target.iterdir())


def test_library_checks_its_grid(duration_library: GaitLibrary) -> None:
    lib = duration_library
    with pytest.raises(GaitLibraryError, match="6 points but the library has 5"):
        GaitLibrary(lib.params, lib.settings, lib.axes, lib.gaits[:5])
    with pytest.raises(GaitLibraryError, match="not both/neither"):
        GaitLibrary(lib.params, lib.settings, lib.axes, lib.gaits, speed=0.2)
    swapped = (lib.axes[1], lib.axes[0])
    with pytest.raises(GaitLibraryError, match="start with step_length"):
        GaitLibrary(lib.params, lib.settings, swapped, lib.gaits)


def test_the_grid_size_is_exact_past_int64(
    duration_library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    """np.prod wrapped around silently: (2**22,) * 3 (2**66 points) counted 0, so a library
    of no gaits passed the count check on such a grid."""
    huge = (2**22, 2**22, 2**22)
    assert grid_size(huge) == 2**66 and grid_size((2**21, 2**21, 2**21 + 1)) > 2**63
    lib = duration_library
    monkeypatch.setattr(GaitLibrary, "shape", property(lambda self: huge))
    with pytest.raises(GaitLibraryError, match=f"has {2**66} points but the library has 0"):
        GaitLibrary(lib.params, lib.settings, lib.axes, ())
    assert lib.size == 2**66
    with pytest.raises(OverflowError):  # more than len() can say, rather than a wrong count
        len(lib)


def test_build_rejects_a_bad_grid_before_optimizing() -> None:
    with pytest.raises(GaitLibraryError, match="strictly increasing"):
        build_library([0.12, 0.10], speed=0.2)
    with pytest.raises(ValueError, match="exactly one"):
        build_library([0.12], speed=0.2, step_durations=[1.0])


@pytest.mark.parametrize(
    ("lengths", "problem"),
    [
        ([0.12, 2.5], "step length must be in"),  # optimized up to 2.5, then a ValueError
        ([0.12, 0.1201, 0.1202], "too close to give distinct gait ids"),  # after every gait
    ],
)
def test_build_refuses_what_no_library_holds_before_optimizing(
    monkeypatch: pytest.MonkeyPatch, lengths: list[float], problem: str
) -> None:
    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("optimized a gait of a grid that is refused")

    monkeypatch.setattr("gaitpref.gaits.build.optimize_gait", never)
    with pytest.raises(ValueError, match=problem):
        build_library(lengths, speed=0.2)


def test_gaits_are_read_only(duration_library: GaitLibrary) -> None:
    gait = duration_library.gait(0)
    with pytest.raises(ValueError, match="read-only"):
        gait.alpha[0, 0] = 1.0


def test_a_library_file_over_the_size_limit_is_refused_by_name(
    duration_library: GaitLibrary, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A library file was read whole whatever its size; the bound lives with the format now
    (the export's import and the console take it from there)."""
    from gaitpref.gaits import library_io
    from gaitpref.sessions import export

    assert export.MAX_LIBRARY_BYTES == library_io.MAX_LIBRARY_BYTES == 256 * 2**20
    path = tmp_path / "lib.json"
    duration_library.save(path)
    size = path.stat().st_size
    monkeypatch.setattr(library_io, "MAX_LIBRARY_BYTES", size - 1)
    with pytest.raises(GaitLibraryError, match=rf"lib\.json: larger than the {size - 1:,} bytes"):
        load_library(path)
    monkeypatch.setattr(library_io, "MAX_LIBRARY_BYTES", size)
    assert len(load_library(path)) == len(duration_library)


@pytest.mark.parametrize(
    ("where", "value", "message"),
    [
        (
            "model",
            [1.0, 2.0, 3.0],
            r"model\.parameters: expected an object of numbers by name, "
            "got list",
        ),
        ("model", "hip_mass", r"model\.parameters: expected an object .* got str"),
        ("model_item", "heavy", r"model\.parameters: model parameter leg_mass must be a number"),
        ("formulation", [5], r"formulation\.degree: missing"),
        ("status", True, r"gaits\[0\]: feasible must be a boolean, solver_status an integer"),
    ],
)
def test_fields_of_the_wrong_type_are_refused_naming_the_field(
    duration_library: GaitLibrary, tmp_path: Path, where: str, value: Any, message: str
) -> None:
    """A list or a text as the model's parameters was read as the names of its items
    ('missing [...], unexpected ['h', 'i', ...]'); a formulation that is not an object named
    the file twice; a boolean solver status was taken as 1."""
    data = _document(duration_library, tmp_path)
    if where == "model":
        data["model"]["parameters"] = value
    elif where == "model_item":
        data["model"]["parameters"]["leg_mass"] = value
    elif where == "formulation":
        data["formulation"] = value
    else:
        data["gaits"][0]["solver_status"] = value
    with pytest.raises(GaitLibraryError, match=message) as err:
        load_library(_write(tmp_path, data))
    assert str(err.value).count("edited.json") == 1


def test_the_entry_bound_holds_for_the_longest_numbers_id_and_message(
    duration_library: GaitLibrary,
) -> None:
    """``max_gaits_in_file`` rests on ``entry_bytes_bound``: a gait's entry written with the
    longest float reprs everywhere, a 200-character id, three parameters and a message of the
    allowed length takes no more bytes in the file than the bound."""
    from gaitpref.gaits.library import MAX_GAIT_ID
    from gaitpref.gaits.library_io import MESSAGE_ALLOWANCE, entry_bytes_bound, to_document

    longest = -1.2345678901234567e-300  # 24 characters, as long as a float's repr gets
    assert len(repr(longest)) == 24
    degree = 12
    document = to_document(duration_library)
    entry = dict(document["gaits"][0])
    for key, value in entry.items():
        if isinstance(value, float):
            entry[key] = longest
    entry.update(
        index=10**6,
        id="g" * MAX_GAIT_ID,
        parameters={"step_length": longest, "step_duration": longest, "step_width": longest},
        degree=degree,
        alpha=[[longest] * (degree + 1)],
        orbit_state=[longest] * 4,
        solver_status=-(10**9),
        solver_message="m" * MESSAGE_ALLOWANCE,
    )
    sizes = []
    for n in (0, 1, 7):
        document["gaits"] = [entry] * n
        sizes.append(len(json.dumps(document, indent=1, allow_nan=False).encode()))
    assert sizes[1] - sizes[0] <= entry_bytes_bound(degree)
    assert sizes[2] - sizes[0] <= 7 * entry_bytes_bound(degree)
    assert sizes[1] - sizes[0] > entry_bytes_bound(degree) // 2  # a bound, not a guess


def test_save_refuses_a_library_larger_than_a_file_is_read_back(
    duration_library: GaitLibrary, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A library whose file load_library would refuse is not written (it was, and then could
    not be opened)."""
    from gaitpref.gaits import library_io

    path = tmp_path / "lib.json"
    duration_library.save(path)
    size = path.stat().st_size
    monkeypatch.setattr(library_io, "MAX_LIBRARY_BYTES", size - 1)
    with pytest.raises(GaitLibraryError, match=rf"6 gaits take {size:,} bytes, more than the"):
        duration_library.save(tmp_path / "big.json")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lib.json"]
    monkeypatch.setattr(library_io, "MAX_LIBRARY_BYTES", size)
    duration_library.save(tmp_path / "big.json")
    assert GaitLibrary.load(tmp_path / "big.json").shape == (3, 2)
