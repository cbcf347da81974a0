"""``gaitpref.simulate`` is the package's one import surface: what ``run_study`` raises and warns,
resuming included, is importable from it."""

from __future__ import annotations

import gaitpref.simulate as simulate
from gaitpref.simulate.partial import StudyRunError
from gaitpref.simulate.resume import PartialRunsWarning, ResumeError


def test_the_resume_errors_are_on_the_package_surface() -> None:
    assert simulate.ResumeError is ResumeError
    assert simulate.PartialRunsWarning is PartialRunsWarning
    assert simulate.StudyRunError is StudyRunError
    assert {"ResumeError", "PartialRunsWarning", "StudyRunError"} <= set(simulate.__all__)
    assert all(hasattr(simulate, name) for name in simulate.__all__)
