"""``POST /api/sessions`` checks the config before it builds anything (issue 15, item 1).

The request runs in a child process whose address space is capped at 2 GB: a console that built
the grid before checking its size would die there (MemoryError) instead of taking the machine.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

HUGE = """
[space.step_length]
min = 0.08
max = 0.18
num = 1000000000
unit = "m"
[model]
lengthscale = { step_length = 0.03 }
signal_variance = 0.005
noise = 0.02
[cospar]
n = 1
buffer = 1
subspace = "grid"  # the full grid asked for (without it, such a num is continuous: issue 13)
"""

CHILD = textwrap.dedent(
    """
    import json, resource, sys
    resource.setrlimit(resource.RLIMIT_AS, (2 * 1024**3, 2 * 1024**3))
    from fastapi.testclient import TestClient
    from gaitpref.console import create_app
    with TestClient(create_app(sys.argv[1])) as c:
        r = c.post("/api/sessions", json={"config": sys.argv[2], "subject": "S01"})
        print(json.dumps({"status": r.status_code, "body": r.json(),
                          "sessions": c.get("/api/sessions").json()}))
    """
)


def test_a_billion_point_grid_is_refused_before_it_is_built(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'c.db'}"
    done = subprocess.run(
        [sys.executable, "-c", CHILD, url, HUGE], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr[-2000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["status"] == 422, out
    assert out["body"]["detail"][0]["loc"] == ["body", "config"]
    assert "step_length" in out["body"]["detail"][0]["msg"]
    assert out["sessions"] == []


MODEL = "[model]\nlengthscale = 0.2\nsignal_variance = 0.005\nnoise = 0.02\n"


def _features(nums: list[int]) -> str:
    return MODEL + "".join(
        f"[space.x{i}]\nmin = 0\nmax = 1\nnum = {n}\n" for i, n in enumerate(nums)
    )


def test_features_of_a_million_values_each_are_refused_before_they_are_built(
    tmp_path: Path,
) -> None:
    """The console read the config with its own limit (a num past 250,000 a continuous
    feature), but the session reads the stored text again with the library's (1,000,000): 32
    such features were 32 million values made for a 700-character config (gigabytes), then
    sent whole by every GET /api/sessions/{id}.  Now the values a config's features have in all
    are counted in its text first, as the session will make them."""
    url = f"sqlite:///{tmp_path / 'c.db'}"
    config = _features([1_000_000] * 32)
    done = subprocess.run(
        [sys.executable, "-c", CHILD, url, config], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr[-2000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["status"] == 422, out
    detail = out["body"]["detail"][0]
    assert detail["loc"] == ["body", "config"]
    assert "32,000,000 values in all" in detail["msg"] and "at most 250,000" in detail["msg"]
    assert out["sessions"] == []


def test_the_console_checks_the_config_as_the_session_will_run_it() -> None:
    """A 600 x 600 grid with subspace 'auto': the console's own limit (250,000 actions) read it
    as the line path, but the session, reading the stored text with the library's limit, ran
    the full grid of 360,000 actions (every posterior drawn and sent whole).  One feature of
    300,000 values (continuous to the console, discrete to the session) likewise."""
    from fastapi.testclient import TestClient

    from gaitpref.console import create_app

    with TestClient(create_app("memory://")) as client:
        for nums, says in (
            ([600, 600], "the grid has 360,000 actions"),
            ([300_000], "300,000 values in all"),
        ):
            r = client.post("/api/sessions", json={"config": _features(nums), "subject": "S01"})
            assert r.status_code == 422, r.text
            detail = r.json()["detail"][0]
            assert detail["loc"] == ["body", "config"] and says in detail["msg"], detail
        assert client.get("/api/sessions").json() == []
        for fits in ([500, 500], [200_000], [2000, 2000]):  # the full grid; lines; lines
            r = client.post("/api/sessions", json={"config": _features(fits), "subject": "S01"})
            assert r.status_code == 201, r.text
