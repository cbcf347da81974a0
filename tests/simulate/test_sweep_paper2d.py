"""The Fig. 4 study definition, the checks against the published curves and summary.md."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gaitpref.data import paper_objectives
from gaitpref.simulate.paper2d import (
    PAPER_2D_SETTINGS,
    CheckpointRow,
    paper_2d_study,
    paper_claims,
    published_curves,
)
from gaitpref.simulate.report import MachineInfo, paper_2d_summary
from gaitpref.simulate.sweep import StudyResult, run_study
from gaitpref.simulate.tables import RunTable, summarize

NAMES = [s.name for s in PAPER_2D_SETTINGS]


def test_published_curves_are_the_shipped_ones() -> None:
    pub = published_curves()
    assert pub.settings == tuple(NAMES)
    assert pub.at("n1_b1_coactive", 25) == pytest.approx((0.699, 0.022), abs=1e-3)
    assert pub.at("n2_b0", 150)[0] == pytest.approx(0.877, abs=1e-3)
    assert pub.curve("n3_b0")[0].tolist() == list(range(1, 151))


def test_the_study_is_run_k_on_objective_k() -> None:
    study = paper_2d_study(runs=4, trials=30)
    assert [s.name for s in study.settings] == [*NAMES, "random"]
    assert study.objective_ids == (0, 1, 2, 3) and study.seeds == (0,)
    np.testing.assert_array_equal(study.objectives[3], paper_objectives()[3].ravel())
    n3 = next(s for s in study.settings if s.name == "n3_b0_coactive")
    assert (n3.n, n3.buffer, n3.coactive) == (3, 0, True)
    only = paper_2d_study(runs=2, settings=["n1_b1"], baseline=False)
    assert [s.name for s in only.settings] == ["n1_b1"]
    with pytest.raises(ValueError, match="unknown setting 'n4_b0'"):
        paper_2d_study(settings=["n4_b0"])
    with pytest.raises(ValueError, match="no setting named"):  # not all six
        paper_2d_study(settings=[])
    with pytest.raises(ValueError, match="settings name only 'random'"):
        paper_2d_study(settings=["random"], baseline=False)
    with pytest.raises(ValueError, match=r"runs must be 1\.\.100"):
        paper_2d_study(runs=101)


def fake_table(levels: dict[str, float], runs: int = 50, trials: int = 150) -> RunTable:
    """Each setting's runs follow the published curve shifted by ``levels[setting]``, plus
    noise, so the claims can be made to hold or fail on purpose."""
    rng = np.random.default_rng(0)
    pub = published_curves()
    parts = []
    for name, shift in levels.items():
        base = pub.curve(name)[1][:trials] if name in pub.settings else np.full(trials, 0.45)
        values = base + shift + 0.05 * rng.standard_normal((runs, trials))
        parts.append(
            RunTable(
                np.full(runs * trials, name),
                np.repeat(np.arange(runs), trials),
                np.zeros(runs * trials, dtype=int),
                np.tile(np.arange(1, trials + 1), runs),
                np.zeros(runs * trials, dtype=int),
                values.ravel(),
            )
        )
    return RunTable.concat(parts)


def claims_by_statement(table: RunTable) -> dict[str, bool]:
    return {c.statement: c.holds for c in paper_claims(table, published_curves())}


def test_claims_hold_on_curves_like_the_published_ones() -> None:
    claims = claims_by_statement(fake_table(dict.fromkeys(NAMES, 0.01)))
    assert len(claims) == 6 + 3 + 2
    assert all(claims.values())


def test_claims_fail_when_we_are_below_or_the_order_is_wrong() -> None:
    levels = dict.fromkeys(NAMES, 0.0)
    levels["n1_b1_coactive"] = -0.2  # far below the paper, and worse than without coactive
    levels["n2_b0"] = 0.25  # (2, 0) no longer the slowest learner without coactive
    claims = claims_by_statement(fake_table(levels))
    failed = {k for k, v in claims.items() if not v}
    assert any(k.startswith("n1_b1_coactive: mean not more than 3") for k in failed)
    assert "coactive feedback helps at (n, b) = (1, 1)" in failed
    assert "coactive feedback helps at (n, b) = (2, 0)" in failed  # n2_b0 is now above
    assert "(n, b) = (2, 0) learns slowest without coactive feedback" in failed
    assert "(n, b) = (2, 0) learns slowest with coactive feedback" in failed  # (1, 1) is now
    assert "coactive feedback helps at (n, b) = (3, 0)" not in failed
    assert claims[
        "n3_b0: mean not more than 3 combined SE below the published mean at trials "
        "25, 50, 100, 150"
    ]


def test_checkpoint_z_uses_the_combined_standard_error() -> None:
    row = CheckpointRow("n2_b0", 25, 0.5, 0.03, 0.6, 0.04)
    assert row.z == pytest.approx(-2.0)


def test_summary_reports_the_table_the_checks_and_failures(small_machine: MachineInfo) -> None:
    levels = dict.fromkeys(NAMES, 0.0)
    levels["n1_b1_coactive"] = -0.2
    table = fake_table({**levels, "random": 0.0})
    study = paper_2d_study(runs=50)
    result = StudyResult(study, table, summarize(table), "joblib", 2, 12.5)
    text = paper_2d_summary(result, published_curves(), small_machine, "Because of X.")
    assert "| n2_b0 | 10 |" in text and "| n1_b1_coactive | 150 |" in text
    assert "Random selection (the floor): t=10:" in text
    assert "does NOT hold: n1_b1_coactive: mean not more than 3" in text
    assert "## Notes\n\nBecause of X." in text
    assert "**12.5 s** wall time" in text and "before: 1.00 / 0.50 / 0.25" in text


def test_a_tiny_real_study_is_summarized(small_machine: MachineInfo) -> None:
    study = paper_2d_study(runs=3, trials=25, settings=["n1_b1", "n1_b1_coactive"])
    result = run_study(study, jobs=1)
    text = paper_2d_summary(result, published_curves(), small_machine)
    assert "| n1_b1_coactive | 25 |" in text and "| n1_b1 | 50 |" not in text
    assert "coactive feedback helps at (n, b) = (1, 1)" in text
    assert "learns slowest" not in text  # needs all three (n, b)
    assert result.table.settings == ("n1_b1", "n1_b1_coactive", "random")


def test_one_run_per_setting_leaves_out_the_checks_against_the_published_means(
    small_machine: MachineInfo,
) -> None:
    """With --runs 1 every z is NaN (no standard error) and each such check was reported as
    failed: '[ ] ... z = +nan', 'does NOT hold: n1_b1: mean not more than 3 ...'."""
    study = paper_2d_study(runs=1, trials=25, settings=["n1_b1", "n1_b1_coactive"])
    result = run_study(study, jobs=1)
    text = paper_2d_summary(result, published_curves(), small_machine)
    assert "mean not more than 3 combined SE below" not in text and "z = +nan" not in text
    assert "One run per setting has no standard error" in text
    assert "coactive feedback helps at (n, b) = (1, 1)" in text


def test_a_study_no_check_applies_to_says_so(small_machine: MachineInfo) -> None:
    """10 trials reach no checkpoint and one setting has no twin: the summary said '0 of 0
    checks hold.', which reads as a pass, and cited design notes the repository does not ship."""
    study = paper_2d_study(runs=2, trials=10, settings=["n1_b1"], baseline=False)
    text = paper_2d_summary(run_study(study, jobs=1), published_curves(), small_machine)
    assert "0 of 0 checks hold" not in text
    assert "No check applies to this study: a setting's mean is checked against the " in text
    assert "design/algorithm.md" not in text


@pytest.fixture
def small_machine() -> MachineInfo:
    return MachineInfo(2, "Linux x86_64", "3.11", (1.0, 0.5, 0.25), (1.5, 0.6, 0.3))


def test_study_result_is_frozen(small_machine: MachineInfo) -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        small_machine.cores = 4  # type: ignore[misc]


def test_a_study_shorter_than_the_first_checkpoint_says_so(small_machine: MachineInfo) -> None:
    """--trials 5: the table had no row and the floor's sentence read "(the floor): ."."""
    study = paper_2d_study(runs=2, trials=5, settings=["n1_b1"])
    result = run_study(study, jobs=1)
    text = paper_2d_summary(result, published_curves(), small_machine)
    assert "No row: the table's trials (10, 25, 50, 100, 150) are past the study's 5" in text
    assert "Random selection (the floor)" not in text
