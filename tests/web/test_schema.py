"""schemathesis against the app's own OpenAPI document on a real server.

Every answer must be documented: no 5xx, every status code, content type and body as the
document says (so the document matches what the server sends), and every request that breaks
the schema (a string for a boolean, a boolean for a number, ...) refused. Bounded: a fixed
number of examples per operation and a fixed seed; the robot runs at time scale 0 so generated
missions finish at once. The number of cases and the time are printed (pytest -s) and checked
against the report, so a run that tested nothing cannot pass.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from shadowhound.web import WebServer, create_app
from tests.web.conftest import TOKEN, make_agent

if os.environ.get("CI"):  # CI must run this test, so a missing tool is a failure there
    import schemathesis  # noqa: F401
else:
    pytest.importorskip("schemathesis", reason="schemathesis (dev extra) is not installed")

CHECKS = (
    "not_a_server_error",
    "status_code_conformance",
    "content_type_conformance",
    "response_schema_conformance",
    "negative_data_rejection",
)
# Endless streams (MJPEG, server-sent events): a request never ends, so no answer to check.
STREAMS = ("/api/camera/stream", "/api/events")
# A body schemathesis cannot make: a recording (no serializer for audio types). Its answers
# are documented all the same and met one by one in test_speech_api.py.
BINARY = ("post_speech",)


def schemathesis_run(url: str, tmp_path: Path, max_examples: int) -> dict[str, Any]:
    """Run the schemathesis CLI on `url`; its JSON report (with exit_code and output added)."""
    cli = shutil.which("schemathesis", path=str(Path(sys.executable).parent)) or "schemathesis"
    report = tmp_path / "report.json"
    command = [
        cli,
        "run",
        f"{url}/openapi.json",
        "--checks",
        ",".join(CHECKS),
        "--max-examples",
        str(max_examples),
        "--phases",
        "examples,coverage,fuzzing",
        "--request-timeout",
        "5",
        "--no-color",
        "--suppress-health-check",
        "all",
        "--seed",
        "1",
        "--report",
        "json",
        "--report-json-path",
        str(report),
    ]
    for path in STREAMS:
        command += ["--exclude-path", path]
    for operation in BINARY:
        command += ["--exclude-operation-id", operation]
    env = {**os.environ, "SCHEMATHESIS_HOOKS": "", "HOME": str(tmp_path)}
    done = subprocess.run(
        command, capture_output=True, text=True, timeout=300, env=env, cwd=tmp_path
    )
    found: dict[str, Any] = json.loads(report.read_text()) if report.exists() else {}
    found.update(exit=done.returncode, output=done.stdout[-6000:] + done.stderr[-2000:])
    return found


def assert_conforms(found: dict[str, Any], operations: int) -> None:
    assert found["exit"] == 0 and not found["failures"] and not found["errors"], found["output"]
    assert found["complete"] and found["stop_reason"] == "completed", found["output"]
    tested = found["operations"]
    assert tested["tested"] == tested["selected"] == operations, tested
    assert tested["errored"] == tested["skipped"] == 0, tested
    cases = found["test_cases"]
    assert cases["generated"] >= 10 * operations, cases  # it really exercised every operation
    assert cases["with_failures"] == cases["errored"] == 0, cases
    print(
        f"schemathesis: {cases['generated']} cases on {operations} operations in "
        f"{found['running_time']:.1f} s, 0 failures"
    )


def documented_operations(server: WebServer) -> int:
    paths = server.app.openapi()["paths"]
    return sum(
        1
        for path, ops in paths.items()
        if path not in STREAMS
        for op in ops.values()
        if op.get("operationId") not in BINARY
    )


def test_every_answer_is_documented_and_bad_requests_are_refused(
    serve: Callable[..., WebServer], tmp_path: Path
) -> None:
    server = serve(make_agent())
    assert_conforms(schemathesis_run(server.url, tmp_path, 8), documented_operations(server))


def test_a_server_with_a_token_documents_its_401(
    serve: Callable[..., WebServer], tmp_path: Path
) -> None:
    """Without the token every /api/ answer is 401 (health excepted): documented as such."""
    server = serve(make_agent(), token=TOKEN)
    assert_conforms(schemathesis_run(server.url, tmp_path, 3), documented_operations(server))


# -- the document itself -----------------------------------------------------------------------


def _document(**options: Any) -> dict[str, Any]:
    agent = make_agent()
    try:
        return create_app(agent, **options).openapi()
    finally:
        agent.cleanup()


def test_the_document_names_each_error_answer_with_its_body() -> None:
    doc = _document()
    paths = doc["paths"]
    ref = "#/components/schemas/{}".format

    def schema(path: str, method: str, code: str) -> str:
        answer = paths[path][method]["responses"][code]
        return str(answer["content"]["application/json"]["schema"]["$ref"])

    # 422 is what the app's handler sends (detail text + problems), never FastAPI's default.
    assert "HTTPValidationError" not in doc["components"]["schemas"]
    for path, method in [
        ("/api/mission", "post"),
        ("/api/missions", "get"),
        ("/api/camera/latest", "get"),
        ("/api/events", "get"),
    ]:
        assert schema(path, method, "422") == ref("ValidationProblem")
    assert "422" not in paths["/api/status"]["get"]["responses"]  # nothing there to validate
    # 413 (bytes) only where a body can be sent; the text limit (characters) is a 422.
    assert schema("/api/mission", "post", "413") == ref("Problem")
    assert "413" not in paths["/api/status"]["get"]["responses"]
    assert "16000 characters" in paths["/api/mission"]["post"]["responses"]["413"]["description"]
    assert schema("/api/mission", "post", "409") == ref("MissionRefused")
    assert schema("/api/mission", "post", "429") == ref("MissionRefused")
    assert schema("/api/missions/{mission_id}/cancel", "post", "404") == ref("Problem")
    # Without a token there is no 401; the host check gives 400.
    assert "401" not in paths["/api/status"]["get"]["responses"]
    assert schema("/api/status", "get", "400") == ref("Problem")
    # Request bodies are strict: the document says boolean, and only a boolean is taken.
    body = doc["components"]["schemas"]["MissionRequest"]["properties"]
    assert body["dry_run"]["type"] == "boolean"


def test_with_a_token_401_is_documented_except_on_health() -> None:
    paths = _document(token=TOKEN)["paths"]
    assert "401" in paths["/api/status"]["get"]["responses"]
    assert "401" in paths["/api/mission"]["post"]["responses"]
    assert "401" not in paths["/api/health"]["get"]["responses"]
    assert "400" not in paths["/api/status"]["get"]["responses"]  # no host check with a token
