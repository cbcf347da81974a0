"""The session figure, the export and the posterior summary compute on one BLAS thread, as ask,
tell and the confidence do (``model/threads.py``): on two cores an export of 100 trials of
``exo-2d-rated`` took 6.2 s with BLAS's default threads against 1.9 s on one, with the same bytes
(every export file and the figure's PNG, grid and line-path sessions:
``benchmarks/check_blas_outputs.py``, ``benchmarks/results/blas_outputs.md``)."""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from gaitpref import Session
from gaitpref.model.posterior import Posterior
from gaitpref.plots.session import save_session_figure, session_picture
from gaitpref.sessions import export_session, posterior_summary
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive


def _blas_threads() -> int:
    return max(int(i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas")


@pytest.fixture
def seen(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The BLAS threads in force at every posterior draw and marginal variance."""
    out: list[int] = []
    sample = Posterior.sample
    variance = Posterior.__dict__["variance"].func

    def spy_sample(self: Posterior, *args: Any, **kwargs: Any) -> np.ndarray:
        out.append(_blas_threads())
        return sample(self, *args, **kwargs)

    def spy_variance(self: Posterior) -> np.ndarray:
        out.append(_blas_threads())
        return variance(self)  # type: ignore[no-any-return]

    prop = cached_property(spy_variance)
    prop.__set_name__(Posterior, "variance")
    monkeypatch.setattr(Posterior, "sample", spy_sample)
    monkeypatch.setattr(Posterior, "variance", prop)
    return out


@pytest.mark.parametrize(
    "make",
    [
        lambda s, tmp: session_picture(s),
        lambda s, tmp: save_session_figure(s, tmp / "fig.png"),
        lambda s, tmp: export_session(s, tmp / "export"),
        lambda s, tmp: posterior_summary(s),
    ],
    ids=["picture", "figure", "export", "summary"],
)
def test_it_computes_on_one_blas_thread(
    make: Callable[[Session, Path], object], drive: Drive, seen: list[int], tmp_path: Path
) -> None:
    storage = MemoryStorage()
    s = Session.create(storage, CONFIG, "S01", seed=3)
    drive(s, 6)
    s.close()
    s = Session.open(storage, s.id)  # the posterior's variance not computed yet
    seen.clear()
    with threadpool_limits(limits=2, user_api="blas"):
        make(s, tmp_path)
        after = _blas_threads()
    assert seen, "no posterior draw or variance was computed"
    assert set(seen) == {1}, seen
    assert after == 2  # restored afterwards


def test_the_region_of_avoidance_after_an_answer_is_read_on_one_blas_thread(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``loop.allowed()``, which the recommendation and the confidence call after every answer,
    read the posterior's variance on BLAS's default threads: 16 ms against 0.4 ms on one
    (exo-2d-rated, 60 answers, two loaded cores), with the same masks."""
    from gaitpref import load_config

    threads: list[int] = []
    many = Posterior.variance_many

    def spy_many(self: Posterior, *args: Any, **kwargs: Any) -> np.ndarray:
        threads.append(_blas_threads())
        return many(self, *args, **kwargs)

    monkeypatch.setattr(Posterior, "variance_many", spy_many)
    s = Session.create(MemoryStorage(), load_config("exo-2d-rated"), "S01", seed=1)
    for _ in range(4):
        q = s.next_query()
        a, b = q.actions[0], q.buffer[0] if q.buffer else q.actions[0]
        s.answer(q.id, [] if a == b else [(a, b, "first")], [])
    threads.clear()
    with threadpool_limits(limits=2, user_api="blas"):
        s.refresh()  # a new posterior: nothing of it read yet
        threads.clear()
        s.recommended()
        after = _blas_threads()
    assert threads and set(threads) == {1}, threads
    assert after == 2
