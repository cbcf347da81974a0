"""Simulated users, objectives, simulated experiments and sweeps over them.

    study = Study.from_config(load_config("synthetic-2d"), [Setting("n1_b1", 1, 1, True),
                              Setting.random()], objectives, seeds=(0, 1, 2), trials=150)
    result = run_study(study, backend="joblib", jobs=2)   # or backend="ray", address=...
    write_table(result.table, "runs.parquet"); result.curves.curve("n1_b1")

``run_study(..., resume=True)`` raises :class:`ResumeError` on a partial file of another study
and warns with :class:`PartialRunsWarning` when it drops what a dead machine left; a run that
fails raises :class:`StudyRunError`.  All three are importable from here.

The paper's studies: :mod:`gaitpref.simulate.paper2d` (Fig. 4) and
:mod:`gaitpref.simulate.compass` (Fig. 2); ``gaitpref bench ...`` runs them.
"""

from gaitpref.simulate.partial import StudyRunError
from gaitpref.simulate.resume import PartialRunsWarning, ResumeError
from gaitpref.simulate.study import RunResult, RunTask, Setting, Study, run_one
from gaitpref.simulate.sweep import BACKENDS, StudyResult, run_study
from gaitpref.simulate.tables import (
    Curves,
    RunTable,
    read_curves,
    read_table,
    summarize,
    write_curves,
    write_table,
)

__all__ = [
    "BACKENDS",
    "Curves",
    "PartialRunsWarning",
    "ResumeError",
    "RunResult",
    "RunTable",
    "RunTask",
    "Setting",
    "Study",
    "StudyResult",
    "StudyRunError",
    "read_curves",
    "read_table",
    "run_one",
    "run_study",
    "summarize",
    "write_curves",
    "write_table",
]
