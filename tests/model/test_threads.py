"""Independent fits side by side (``model/threads.py``, ``model/share_mix.py``): results in task
order, errors raised after every task has finished, the caller's NumPy error state in the
workers, and share hypotheses weighed in threads to the same numbers as one after the other."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import numpy as np
import pytest

import gaitpref.model.share_mix as share_mix
import gaitpref.model.threads as threads
from gaitpref.model.population import population_evidence
from gaitpref.model.share_mix import share_prior, weigh_shares
from gaitpref.model.threads import in_threads
from tests.model.test_population import _pair_data, _population_data
from tests.model.test_share_mix import HYPER, RHO, TINY


@pytest.fixture
def two_cpus(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(threads, "available_cpus", lambda: 2)


def _slow(value: int, delay: float, seen: list[str]) -> Callable[[], int]:
    def task() -> int:
        time.sleep(delay)
        seen.append(threading.current_thread().name)
        return value

    return task


@pytest.mark.usefixtures("two_cpus")
def test_results_come_in_task_order_from_worker_threads() -> None:
    seen: list[str] = []
    tasks = [_slow(k, 0.05 if k == 0 else 0.0, seen) for k in range(5)]
    assert in_threads(tasks) == [0, 1, 2, 3, 4]
    assert all(name.startswith("gaitpref-fit") for name in seen)
    assert len(set(seen)) == 2  # at most one thread per CPU


@pytest.mark.usefixtures("two_cpus")
def test_serial_when_not_parallel_or_one_task() -> None:
    seen: list[str] = []
    me = threading.current_thread().name
    assert in_threads([_slow(k, 0.0, seen) for k in range(3)], parallel=False) == [0, 1, 2]
    assert in_threads([_slow(7, 0.0, seen)]) == [7]
    assert seen == [me] * 4


@pytest.mark.usefixtures("two_cpus")
def test_the_first_error_in_task_order_is_raised_after_every_task_finished() -> None:
    done: list[int] = []

    def fail(k: int, delay: float) -> Callable[[], int]:
        def task() -> int:
            time.sleep(delay)
            done.append(k)
            raise ValueError(f"task {k}")

        return task

    def ok() -> int:
        time.sleep(0.1)
        done.append(2)
        return 2

    with pytest.raises(ValueError, match="task 0"):
        in_threads([fail(0, 0.05), fail(1, 0.0), ok])
    assert sorted(done) == [0, 1, 2]


@pytest.mark.usefixtures("two_cpus")
def test_workers_run_in_the_callers_numpy_error_state() -> None:
    def divide() -> float:
        return float(np.float64(1.0) / np.float64(0.0))

    with np.errstate(divide="raise"), pytest.raises(FloatingPointError):
        in_threads([divide, divide])


def test_the_evidence_without_its_gradient_is_the_same_number() -> None:
    rng = np.random.default_rng(5)
    w, l_, who = _population_data(rng, TINY, 3, 6)
    data = _pair_data(TINY, w, l_, who)
    for share in (None, 0.0, 0.3):
        full = population_evidence(TINY, HYPER, RHO, data, share=share)
        value = population_evidence(TINY, HYPER, RHO, data, share=share, gradient=False)
        assert value.value == full.value  # bit for bit: the same fit
        assert np.array_equal(value.fit.whitened_mode, full.fit.whitened_mode)
        assert value.gradient.shape == full.gradient.shape
        assert np.all(np.isnan(value.gradient))


@pytest.mark.usefixtures("two_cpus")
def test_share_hypotheses_weighed_in_threads_equal_one_after_the_other(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rng = np.random.default_rng(6)
    w, l_, who = _population_data(rng, TINY, 3, 6)
    data = _pair_data(TINY, w, l_, who)
    names: list[str] = []
    real = population_evidence

    def spy(*args: object, **kwargs: object) -> object:
        names.append(threading.current_thread().name)
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(share_mix, "population_evidence", spy)
    monkeypatch.setattr(share_mix, "PARALLEL_OBSERVATIONS", 10**9)
    serial = weigh_shares(TINY, HYPER, RHO, share_prior(RHO), data)
    assert set(names) == {threading.current_thread().name}
    names.clear()
    monkeypatch.setattr(share_mix, "PARALLEL_OBSERVATIONS", 1)
    parallel = weigh_shares(TINY, HYPER, RHO, share_prior(RHO), data)
    assert names and all(n.startswith("gaitpref-fit") for n in names)
    assert parallel == serial  # every objective and weight bit for bit


def test_one_blas_thread_holds_in_a_thread_while_another_leaves_its_block(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Two threads inside :func:`one_blas_thread` at once (the console computes one session's
    confidence while another's tell runs): the first to leave restored BLAS's threads under the
    second, which then ran on them, and the last to leave set the process's BLAS to one thread
    for good.  The limit holds while any thread is inside, and is restored once none is.  (A
    stand-in for threadpoolctl's controller: how OpenBLAS shows a limit set in another thread
    varies by release.)"""
    blas = {"threads": 2}  # the process's BLAS threads

    class Limiter:
        def __init__(self) -> None:
            self.original = blas["threads"]
            blas["threads"] = 1

        def restore_original_limits(self) -> None:
            blas["threads"] = self.original

        def __enter__(self) -> Limiter:
            return self

        def __exit__(self, *exc: object) -> None:
            self.restore_original_limits()

    class Controller:
        def limit(self, *, limits: int, user_api: str) -> Limiter:
            assert (limits, user_api) == (1, "blas")
            return Limiter()

    monkeypatch.setattr(threads, "_controller", Controller)
    seen: list[int] = []
    first_in, second_in, first_out = threading.Event(), threading.Event(), threading.Event()

    def first() -> None:
        with threads.one_blas_thread():
            first_in.set()
            second_in.wait(5)
        first_out.set()

    def second() -> None:
        first_in.wait(5)
        with threads.one_blas_thread():
            second_in.set()
            first_out.wait(5)
            seen.append(blas["threads"])

    workers = [threading.Thread(target=first), threading.Thread(target=second)]
    for w in workers:
        w.start()
    for w in workers:
        w.join(10)
    assert seen == [1]  # still one thread, though the first thread left its block
    assert blas["threads"] == 2  # restored once neither is inside
    with threads.one_blas_thread(), threads.one_blas_thread():  # nested in one thread
        assert blas["threads"] == 1
    assert blas["threads"] == 2
