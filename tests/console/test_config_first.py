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
