"""schemathesis against the app's own OpenAPI document on a real server: no answer is a 5xx.

Bounded: a few examples per operation, and the robot runs at time scale 0 so generated missions
finish at once.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from shadowhound.web import WebServer
from tests.web.conftest import make_agent

if os.environ.get("CI"):  # CI must run this test, so a missing tool is a failure there
    import schemathesis  # noqa: F401
else:
    pytest.importorskip("schemathesis", reason="schemathesis (dev extra) is not installed")


def test_no_operation_answers_with_a_server_error(serve: Callable[..., WebServer],
                                                  tmp_path: Path) -> None:
    server = serve(make_agent())
    cli = shutil.which("schemathesis", path=str(Path(sys.executable).parent)) or "schemathesis"
    command = [cli, "run", f"{server.url}/openapi.json", "--checks", "not_a_server_error",
               "--max-examples", "8", "--phases", "examples,coverage,fuzzing",
               "--exclude-path", "/api/camera/stream", "--exclude-path", "/api/events",
               "--request-timeout", "5", "--no-color",
               "--suppress-health-check", "all", "--seed", "1"]
    env = {**os.environ, "SCHEMATHESIS_HOOKS": "", "HOME": str(tmp_path)}
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, env=env,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
