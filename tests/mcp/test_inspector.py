"""The official MCP Inspector (`@modelcontextprotocol/inspector`, CLI mode) accepts the server:
a client written by others lists its tools and calls one, over stdio and Streamable HTTP.

scripts/test.sh installs the Inspector into .npm-tools/ with npm. Without node the test skips,
except where SHADOWHOUND_REQUIRE_MCP_INSPECTOR=1 (scripts/test.sh, so CI) makes it fail.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from .conftest import SRC, server_command

ROOT = Path(__file__).resolve().parents[2]
INSPECTOR = ROOT / ".npm-tools" / "node_modules" / ".bin" / "mcp-inspector"
INSTALL = "npm install --prefix .npm-tools @modelcontextprotocol/inspector"


@pytest.fixture
def inspector() -> list[str]:
    required = os.environ.get("SHADOWHOUND_REQUIRE_MCP_INSPECTOR") == "1"
    if shutil.which("node") is None:
        if required:
            pytest.fail("node is not installed, and SHADOWHOUND_REQUIRE_MCP_INSPECTOR=1")
        pytest.skip("node is not installed (the MCP Inspector is a node program)")
    if not INSPECTOR.exists():
        pytest.fail(f"the MCP Inspector is not installed: run scripts/test.sh or `{INSTALL}`")
    # Its connect time-out (15 s by default) only bounds a hung server here: a loaded machine
    # may take longer than that to start Python and the server.
    return [str(INSPECTOR), "--cli", "--connect-timeout", "120000"]


def _inspect(command: list[str], *args: str) -> dict:
    proc = subprocess.run([*command, *args], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return json.loads(proc.stdout)


def test_inspector_lists_tools_and_calls_one_over_stdio(inspector, tmp_path):
    # The Inspector starts the server with a clean environment: pass what it needs.
    server = [
        *inspector,
        "-e",
        f"PYTHONPATH={SRC}",
        "-e",
        f"SHADOWHOUND_MEMORY__DATA_DIR={tmp_path}",
        *server_command(),
    ]
    tools = _inspect(server, "--method", "tools/list")["tools"]
    names = {t["name"] for t in tools}
    assert {"run_mission", "plan_mission", "emergency_stop", "nav_move", "body_sit"} <= names
    answer = _inspect(
        server, "--method", "tools/call", "--tool-name", "nav_rotate", "--tool-arg", "degrees=45"
    )
    assert answer.get("isError") is not True, answer
    result = answer["structuredContent"]
    assert result["success"] is True
    assert result["robot"]["yaw_deg"] == pytest.approx(45.0, abs=1.0)


def test_inspector_lists_tools_and_calls_one_over_http(inspector, http_server):
    server = http_server()
    target = [*inspector, server.url, "--transport", "http"]
    names = {t["name"] for t in _inspect(target, "--method", "tools/list")["tools"]}
    assert "get_state" in names
    state = _inspect(target, "--method", "tools/call", "--tool-name", "get_state")
    assert state["structuredContent"]["robot"]["connected"] is True


def test_inspector_gives_a_length_as_text_with_its_unit(inspector, tmp_path):
    """The README promises "2 ft" wherever a length goes: the tool schema says a number or a
    string, so the Inspector sends "50 cm" as it was typed (it turns a field declared only as a
    number into a number, and "50 cm" into NaN), and the registry reads it as 0.5 m."""
    server = [
        *inspector,
        "-e",
        f"PYTHONPATH={SRC}",
        "-e",
        f"SHADOWHOUND_MEMORY__DATA_DIR={tmp_path}",
        *server_command(),
    ]
    tools = {t["name"]: t for t in _inspect(server, "--method", "tools/list")["tools"]}
    distance = tools["nav_move"]["inputSchema"]["properties"]["distance"]
    assert sorted(distance["type"]) == ["number", "string"], distance
    answer = _inspect(
        server,
        "--method",
        "tools/call",
        "--tool-name",
        "nav_move",
        "--tool-arg",
        "distance=50 cm",
    )
    assert answer.get("isError") is not True, answer
    result = answer["structuredContent"]
    assert result["success"] is True
    assert result["robot"]["x"] == pytest.approx(0.5, abs=0.02)
