"""The scripted LLM server, exercised with the real ``openai`` client."""

from __future__ import annotations

import json
import logging
import re
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from typing import Any

import openai
import pytest
from openai import OpenAI

from tests.llm_server import (
    NO_REPLY_LEFT,
    Reply,
    ScriptedLLM,
    delay,
    drop,
    dynamic,
    garbage,
    hang,
    json_plan,
    status,
    text,
    tool_calls,
)

MESSAGES: list[Any] = [
    {"role": "system", "content": "You plan robot missions."},
    {"role": "user", "content": "walk forward one metre"},
]


SAFETY = 60.0  # seconds: bounds a hung test (a loaded machine is slow), never what is asserted


def until(check: Any, what: str) -> None:
    """Poll `check` until it is true; fail after SAFETY seconds."""
    deadline = time.monotonic() + SAFETY
    while not check():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.01)


@pytest.fixture
def srv() -> Iterator[ScriptedLLM]:
    with ScriptedLLM(models=("test-model", "other-model")) as server:
        yield server


def client_for(server: ScriptedLLM, *, max_retries: int = 0, timeout: float = SAFETY) -> OpenAI:
    return OpenAI(base_url=server.url, api_key="test", max_retries=max_retries, timeout=timeout)


def chat(client: OpenAI, **kw: Any) -> Any:
    return client.chat.completions.create(model="test-model", messages=MESSAGES, **kw)


def get_json(url: str) -> tuple[int, dict[str, Any]]:
    try:
        with urllib.request.urlopen(url, timeout=SAFETY) as resp:
            return resp.status, json.loads(resp.read())
    except urllib.error.HTTPError as err:
        with err:
            return err.code, json.loads(err.read())


def test_addresses_are_loopback(srv: ScriptedLLM) -> None:
    assert srv.root == f"http://127.0.0.1:{srv.port}"
    assert srv.url == srv.root + "/v1"
    assert srv.port > 0


def test_text_reply_with_usage_and_request_recorded(srv: ScriptedLLM) -> None:
    srv.script(text("hello robot", usage=(12, 3)))
    completion = chat(client_for(srv), temperature=0)
    assert completion.object == "chat.completion"
    assert completion.id == "chatcmpl-1"
    assert completion.model == "test-model"
    choice = completion.choices[0]
    assert choice.message.role == "assistant"
    assert choice.message.content == "hello robot"
    assert choice.message.tool_calls is None
    assert choice.finish_reason == "stop"
    assert completion.usage is not None
    assert (completion.usage.prompt_tokens, completion.usage.completion_tokens) == (12, 3)
    assert completion.usage.total_tokens == 15
    assert len(srv.requests) == 1
    assert srv.requests[0]["messages"] == MESSAGES
    assert srv.requests[0]["model"] == "test-model"
    assert srv.requests[0]["temperature"] == 0
    assert srv.pending() == 0


def test_usage_omitted(srv: ScriptedLLM) -> None:
    srv.script(text("no accounting here", usage=None))
    completion = chat(client_for(srv))
    assert completion.usage is None
    assert completion.choices[0].message.content == "no accounting here"


def test_tool_calls_parsed_by_client(srv: ScriptedLLM) -> None:
    srv.script(
        tool_calls(("walk", {"distance_m": 1.0}), ("sit", '{"broken'), content="thinking"),
        tool_calls(("stand", {})),
    )
    client = client_for(srv)
    message = chat(client).choices[0].message
    assert message.content == "thinking"
    assert message.tool_calls is not None
    first, second = message.tool_calls
    assert (first.id, first.type) == ("call_1", "function")
    assert first.function.name == "walk"
    assert json.loads(first.function.arguments) == {"distance_m": 1.0}
    assert second.id == "call_2"
    assert second.function.arguments == '{"broken'  # strings go out verbatim
    later = chat(client).choices[0]
    assert later.finish_reason == "tool_calls"
    assert later.message.content is None
    assert later.message.tool_calls is not None
    assert later.message.tool_calls[0].id == "call_3"


def test_json_plan(srv: ScriptedLLM) -> None:
    steps = [{"skill": "walk", "args": {"distance_m": 1.0}}, {"skill": "sit", "args": {}}]
    srv.script(json_plan(steps, usage=None))
    completion = chat(client_for(srv))
    assert json.loads(completion.choices[0].message.content) == {"steps": steps}
    assert completion.usage is None


def test_status_error(srv: ScriptedLLM) -> None:
    srv.script(status(500, "model exploded"), status(429, "slow down"), status(401))
    client = client_for(srv)
    with pytest.raises(openai.InternalServerError) as info:
        chat(client)
    assert info.value.status_code == 500
    assert "model exploded" in str(info.value)
    with pytest.raises(openai.RateLimitError):
        chat(client)
    with pytest.raises(openai.AuthenticationError):
        chat(client)


def test_retry_after_500_succeeds(srv: ScriptedLLM) -> None:
    srv.script(status(500), text("ok"))
    completion = chat(client_for(srv, max_retries=2))
    assert completion.choices[0].message.content == "ok"
    assert len(srv.requests) == 2
    assert srv.requests[0] == srv.requests[1]


def test_retry_after_ms_header_shortens_backoff(
    srv: ScriptedLLM, caplog: pytest.LogCaptureFixture
) -> None:
    """The client waits what the header asks (1 ms), not its own backoff (~0.5 s, then ~1 s):
    judged by the waits the client says it takes, not by a clock."""
    srv.script(status(503, retry_after_ms=1), status(503, retry_after_ms=1), text("ok"))
    caplog.set_level(logging.INFO, logger="openai")
    assert chat(client_for(srv, max_retries=2)).choices[0].message.content == "ok"
    assert len(srv.requests) == 3
    waits = [
        float(m.group(1))
        for r in caplog.records
        if (m := re.match(r"Retrying request in ([0-9.]+) seconds", r.getMessage()))
    ]
    assert waits == [0.001, 0.001], caplog.text


def test_delay_longer_than_timeout(srv: ScriptedLLM) -> None:
    srv.script(delay(30, text("too late")))
    with pytest.raises(openai.APITimeoutError):
        chat(client_for(srv, timeout=0.3))
    assert srv.holding() == 1  # the client gave up while the server still held its reply


def test_delay_shorter_than_timeout_then_reply(srv: ScriptedLLM) -> None:
    srv.script(delay(0.05, text("worth the wait")))
    assert chat(client_for(srv)).choices[0].message.content == "worth the wait"


def test_hang_never_answers_and_sees_the_client_leave(srv: ScriptedLLM) -> None:
    srv.script(hang(), text("after the hang"))
    client = client_for(srv, timeout=0.3)
    with pytest.raises(openai.APITimeoutError):
        chat(client)
    until(lambda: srv.hung_up() >= 1, "the server to see the client hang up")
    assert srv.hung_up() == 1 and len(srv.requests) == 1 and srv.holding() == 0
    assert chat(client).choices[0].message.content == "after the hang"


@pytest.mark.parametrize("let_go", ["stop", "release"])
def test_stop_and_release_are_not_held_up_by_a_pending_delay(let_go: str) -> None:
    """The delay (longer than the test would ever wait) is cut short: the client sees the
    connection lost, not its own time-out, nor the scripted reply."""
    server = ScriptedLLM().start()
    server.script(delay(3600, text("never")), text("served on"))
    errors: list[BaseException] = []

    def call() -> None:
        try:
            chat(client_for(server))
        except BaseException as exc:  # noqa: BLE001 - collected for the assertion below
            errors.append(exc)

    caller = threading.Thread(target=call, daemon=True)
    caller.start()
    until(lambda: server.holding() == 1, "the server to hold the request")
    getattr(server, let_go)()
    caller.join(timeout=SAFETY)
    assert not caller.is_alive(), "the delay held the client up"
    assert len(errors) == 1
    assert isinstance(errors[0], openai.APIConnectionError)
    assert not isinstance(errors[0], openai.APITimeoutError)
    assert server.holding() == 0
    if let_go == "release":  # it serves on
        assert chat(client_for(server)).choices[0].message.content == "served on"
        server.stop()


def test_drop_gives_connection_error(srv: ScriptedLLM) -> None:
    srv.script(drop(), text("after the drop"))
    client = client_for(srv)
    with pytest.raises(openai.APIConnectionError) as info:
        chat(client)
    assert not isinstance(info.value, openai.APITimeoutError)
    assert len(srv.requests) == 1
    # the same client recovers on a fresh connection
    assert chat(client).choices[0].message.content == "after the drop"


def test_garbage_body_raises(srv: ScriptedLLM) -> None:
    # openai 3.52 lets json.JSONDecodeError (a ValueError, NOT an openai.OpenAIError) escape
    # for a 200 application/json body that is not JSON. Callers must catch ValueError too.
    srv.script(garbage(b"{not json"))
    with pytest.raises((openai.OpenAIError, ValueError)) as info:
        chat(client_for(srv))
    assert isinstance(info.value, (openai.APIError, json.JSONDecodeError)), repr(info.value)


def test_garbage_that_the_client_does_not_reject(srv: ScriptedLLM) -> None:
    # Not errors as far as the client is concerned: callers have to check the result themselves.
    srv.script(garbage(b"hello", content_type="text/plain"), garbage(b'{"unexpected": true}'))
    client = client_for(srv)
    assert chat(client) == "hello"  # a plain str instead of a ChatCompletion
    odd = chat(client)
    assert odd.choices is None


def test_garbage_error_page(srv: ScriptedLLM) -> None:
    srv.script(garbage(b"<html>Bad Gateway</html>", status=502, content_type="text/html"))
    with pytest.raises(openai.InternalServerError) as info:
        chat(client_for(srv))
    assert info.value.status_code == 502


def test_dynamic_reply_sees_the_request(srv: ScriptedLLM) -> None:
    def echo(body: dict[str, Any]) -> Reply:
        return text(f"you said: {body['messages'][-1]['content']}")

    def fail(body: dict[str, Any]) -> Reply:
        raise ValueError("script bug")

    srv.script(dynamic(echo), dynamic(fail))
    client = client_for(srv)
    assert chat(client).choices[0].message.content == "you said: walk forward one metre"
    with pytest.raises(openai.InternalServerError, match="script bug"):
        chat(client)


def test_models_list(srv: ScriptedLLM) -> None:
    models = client_for(srv).models.list()
    assert [m.id for m in models] == ["test-model", "other-model"]
    assert all(m.owned_by == "test" for m in models)


def test_ollama_tags() -> None:
    with ScriptedLLM(ollama_tags=["llama3.1:8b", "qwen2.5:7b"]) as server:
        code, body = get_json(server.root + "/api/tags")
        assert code == 200
        assert body == {
            "models": [
                {"name": "llama3.1:8b", "model": "llama3.1:8b"},
                {"name": "qwen2.5:7b", "model": "qwen2.5:7b"},
            ]
        }


def test_ollama_tags_absent_and_unknown_routes_are_404(srv: ScriptedLLM) -> None:
    for path in ("/api/tags", "/v1/embeddings", "/"):
        code, body = get_json(srv.root + path)
        assert code == 404
        assert "message" in body["error"]


def test_empty_queue_is_a_clear_500(srv: ScriptedLLM) -> None:
    with pytest.raises(openai.InternalServerError, match=NO_REPLY_LEFT) as info:
        chat(client_for(srv))
    assert info.value.status_code == 500
    assert info.value.body == {
        "message": NO_REPLY_LEFT,
        "type": "server_error",
        "param": None,
        "code": None,
    }
    assert len(srv.requests) == 1  # still recorded


def test_streaming_is_refused(srv: ScriptedLLM) -> None:
    srv.script(text("unused"))
    with pytest.raises(openai.BadRequestError, match="stream"):
        chat(client_for(srv), stream=True)
    assert srv.pending() == 1  # the scripted reply is not consumed


def test_pending_and_clear(srv: ScriptedLLM) -> None:
    srv.script(text("a"), text("b"))
    srv.script(text("c"))
    assert srv.pending() == 3
    assert chat(client_for(srv)).choices[0].message.content == "a"
    assert srv.pending() == 2
    srv.clear()
    assert srv.pending() == 0
    with pytest.raises(TypeError):
        srv.script("not a reply")  # type: ignore[arg-type]


def test_keep_alive_requests_share_a_connection(srv: ScriptedLLM) -> None:
    srv.script(*(text(str(i)) for i in range(5)))
    client = client_for(srv)
    answers = [chat(client).choices[0].message.content for _ in range(5)]
    assert answers == ["0", "1", "2", "3", "4"]
    assert [r["messages"] for r in srv.requests] == [MESSAGES] * 5


def test_concurrent_clients(srv: ScriptedLLM) -> None:
    # Every reply waits until all six requests are being served at once: a server that handles
    # them one after another breaks the barrier (a 500), whatever the machine's speed.
    together = threading.Barrier(6, timeout=SAFETY / 2)  # below the clients' time-out

    def wait_for_all(_body: dict[str, Any]):  # type: ignore[no-untyped-def]
        together.wait()
        return text("x")

    srv.script(*(dynamic(wait_for_all) for _ in range(6)))
    results: list[str | None] = []

    def call() -> None:
        results.append(chat(client_for(srv)).choices[0].message.content)

    threads = [threading.Thread(target=call) for _ in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=SAFETY)
    assert results == ["x"] * 6
    assert len(srv.requests) == 6
