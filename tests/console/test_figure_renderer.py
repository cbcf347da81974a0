"""Figures are drawn off the request path: requests await one drawing, the newest, shared."""

from __future__ import annotations

import asyncio
import threading

import numpy as np
import pytest

from gaitpref import Session
from gaitpref.console import figures
from gaitpref.storage import MemoryStorage


@pytest.fixture(scope="module")
def session() -> Session:
    s = Session.create(MemoryStorage(), "exo-1d-step-length", "S01", seed=2)
    q = s.next_query()
    s.answer(q.id, [], [])
    return s


def test_waiting_requests_share_the_newest_drawing(session: Session) -> None:
    renderer = figures.FigureRenderer(processes=False)
    gate = threading.Event()
    fetched: list[int] = []
    version = [1]

    def blocker() -> tuple[int, figures.Picture]:
        gate.wait(10)  # the drawing thread is busy with another session meanwhile
        return 99, figures.picture_of(session, "posterior")

    def fetch() -> tuple[int, figures.Picture]:
        fetched.append(version[0])
        return version[0], figures.picture_of(session, "posterior")

    async def scenario() -> list[bytes]:
        busy = asyncio.ensure_future(renderer.png(7, "posterior", 99, blocker))
        await asyncio.sleep(0.05)
        waiting = [asyncio.ensure_future(renderer.png(1, "posterior", v, fetch)) for v in (1, 2)]
        await asyncio.sleep(0.05)
        version[0] = 3  # the session moved on before the drawing started
        gate.set()
        await busy
        return list(await asyncio.gather(*waiting))

    pngs = asyncio.run(scenario())
    assert fetched == [3]  # one drawing, of the newest version, for both requests
    assert pngs[0] == pngs[1] and pngs[0].startswith(b"\x89PNG")
    assert renderer.cache.get((1, 3, "posterior")) == pngs[0]
    renderer.close()


def test_a_failed_drawing_is_reported_to_its_requests() -> None:
    renderer = figures.FigureRenderer(processes=False)

    def broken() -> tuple[int, figures.Picture]:
        raise RuntimeError("session 5 cannot be read")

    with pytest.raises(RuntimeError, match="session 5"):
        asyncio.run(renderer.png(5, "posterior", 1, broken))
    renderer.close()


def test_the_drawing_process_draws_the_same_picture(session: Session) -> None:
    pic = figures.picture_of(session, "posterior")
    renderer = figures.FigureRenderer()
    drawn = asyncio.run(renderer.png(1, "posterior", 2, lambda: (2, pic)))
    renderer.close()
    assert drawn.startswith(b"\x89PNG") and len(drawn) > 1000
    assert np.array_equal(pic.mean, np.asarray(session.posterior().mean))
