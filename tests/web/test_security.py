"""Token, host and origin checks, CORS, secrets, and refusing to serve beyond loopback."""

from __future__ import annotations

import io
from collections.abc import Callable, Iterator

import httpx
import pytest
from fastapi.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from shadowhound import RobotAgent, ShadowHoundConfig
from shadowhound.web import WebServer, create_app, serve_main
from shadowhound.web.server import ServeError, check_binding, serve
from tests.web.conftest import TOKEN, make_agent

AUTH = {"Authorization": f"Bearer {TOKEN}"}


@pytest.fixture
def secured(agent: RobotAgent) -> Iterator[TestClient]:
    with TestClient(create_app(agent, token=TOKEN), base_url="http://127.0.0.1") as c:
        yield c


def test_token_is_required_on_api_and_mutations(secured: TestClient) -> None:
    assert secured.get("/api/health").status_code == 200  # liveness stays open
    assert secured.get("/").status_code == 200  # the page itself, to enter the token
    for method, path in [
        ("POST", "/api/estop"),
        ("POST", "/api/mission"),
        ("POST", "/api/estop/release"),
        ("GET", "/api/status"),
        ("GET", "/api/missions"),
        ("GET", "/api/camera/latest"),
    ]:
        reply = secured.request(method, path, json={"command": "stand"})
        assert reply.status_code == 401, (method, path)
        assert reply.headers["www-authenticate"] == "Bearer"
        assert "Bearer" in reply.json()["detail"]
    wrong = secured.post("/api/estop", headers={"Authorization": "Bearer nope"})
    assert wrong.status_code == 401
    assert secured.post("/api/estop", headers=AUTH).status_code == 200
    assert secured.post("/api/estop/release", headers=AUTH).status_code == 200


def test_query_token_works_for_reads_only(secured: TestClient) -> None:
    assert secured.get(f"/api/status?token={TOKEN}").status_code == 200
    assert secured.post(f"/api/estop?token={TOKEN}").status_code == 401


def test_websocket_needs_the_token(secured: TestClient) -> None:
    with pytest.raises(WebSocketDisconnect), secured.websocket_connect("/ws/status"):
        pass
    with secured.websocket_connect(f"/ws/status?token={TOKEN}") as ws:
        assert ws.receive_json()["kind"] == "snapshot"
    with secured.websocket_connect(
        "/ws/status", subprotocols=["shadowhound", f"bearer.{TOKEN}"]
    ) as ws:
        assert ws.accepted_subprotocol == "shadowhound"
        assert ws.receive_json()["kind"] == "snapshot"


def test_secrets_never_appear_in_answers(
    agent: RobotAgent, monkeypatch: pytest.MonkeyPatch
) -> None:
    key = "sk-test-secret-value-1234567890"
    monkeypatch.setenv("OPENAI_API_KEY", key)
    app = create_app(agent, token=TOKEN)
    with TestClient(app, base_url="http://127.0.0.1", headers=AUTH) as client:
        # Put both secrets where answers quote the user's own words.
        client.post("/api/mission", json={"command": f"say {key} and {TOKEN}"})
        client.post("/api/chat", json={"text": f"what is {key}?"})
        texts = [
            client.get(p).text
            for p in ("/api/missions", "/api/diagnostics", "/api/status", "/openapi.json")
        ]
        texts.append(client.post("/api/mission", json={"command": "x" * 3000, "k": key}).text)
        with client.websocket_connect("/ws/status") as ws:
            texts.append(ws.receive_text())
    for text in texts:
        assert key not in text and TOKEN not in text


def test_foreign_hosts_and_cross_origin_requests_are_refused(client: TestClient) -> None:
    assert client.get("/api/status", headers={"host": "attacker.example"}).status_code == 400
    assert client.get("/api/status", headers={"host": "localhost:8080"}).status_code == 200
    cross = client.post("/api/estop", headers={"origin": "http://attacker.example"})
    assert cross.status_code == 403 and "cross-origin" in cross.json()["detail"]
    same = client.post("/api/estop", headers={"origin": "http://127.0.0.1"})
    assert same.status_code == 200
    with (
        pytest.raises(WebSocketDisconnect),
        client.websocket_connect(
            "ws://127.0.0.1/ws/status", headers={"origin": "http://attacker.example"}
        ),
    ):
        pass


def test_an_origin_of_another_scheme_is_another_origin(client: TestClient) -> None:
    """Issue 32: `Origin: https://host:port` was taken as the page of an http server."""
    other = client.post("/api/estop", headers={"origin": "https://127.0.0.1"})
    assert other.status_code == 403 and "cross-origin" in other.json()["detail"]
    with (
        pytest.raises(WebSocketDisconnect),
        client.websocket_connect(
            "ws://127.0.0.1/ws/status", headers={"origin": "https://127.0.0.1"}
        ),
    ):
        pass
    assert client.post("/api/estop", headers={"origin": "http://127.0.0.1"}).status_code == 200
    with client.websocket_connect(
        "ws://127.0.0.1/ws/status", headers={"origin": "http://127.0.0.1"}
    ) as ws:
        assert ws.receive_json()["kind"] == "snapshot"


def test_behind_a_tls_proxy_the_https_page_is_the_origin(serve: Callable[..., WebServer]) -> None:
    """A TLS proxy on loopback says the page's scheme with X-Forwarded-Proto (docs/web.md)."""
    server = serve(make_agent())
    page = f"https://127.0.0.1:{server.port}"
    proxied = {"origin": page, "x-forwarded-proto": "https"}
    assert httpx.post(server.url + "/api/estop", headers=proxied).status_code == 200
    assert httpx.post(server.url + "/api/estop", headers={"origin": page}).status_code == 403


def test_no_cors_headers_for_other_sites(client: TestClient) -> None:
    preflight = client.options(
        "/api/mission",
        headers={"origin": "http://attacker.example", "access-control-request-method": "POST"},
    )
    assert "access-control-allow-origin" not in preflight.headers
    reply = client.get("/api/status", headers={"origin": "http://attacker.example"})
    assert "access-control-allow-origin" not in reply.headers


def test_binding_beyond_loopback_needs_a_strong_token() -> None:
    check_binding("127.0.0.1", None)
    with pytest.raises(ServeError, match="needs a token"):
        check_binding("0.0.0.0", None)
    with pytest.raises(ServeError, match="at least 16"):
        check_binding("0.0.0.0", "short")
    with pytest.raises(ServeError, match="may contain only"):
        check_binding("0.0.0.0", "a token with spaces in it!!")
    check_binding("0.0.0.0", TOKEN)


def test_serve_refuses_with_a_clear_message_and_exit_2(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("SHADOWHOUND_TOKEN", raising=False)
    assert serve_main(ShadowHoundConfig(), host="0.0.0.0", port=0) == 2
    assert "needs a token" in capsys.readouterr().err
    out = io.StringIO()
    agent = make_agent()
    from shadowhound.web.server import bind

    taken = bind("127.0.0.1", 0)
    try:
        code = serve(ShadowHoundConfig(), "127.0.0.1", taken.getsockname()[1], agent=agent, out=out)
    finally:
        taken.close()
        agent.cleanup()
    assert code == 2 and "cannot listen" in out.getvalue()


# -- the Host header and the loopback rule ------------------------------------------------------

# What a Host header may be (RFC 9110): a name or a bracketed IPv6 literal, then ":" and digits.
_HOST_CHARS = "abcdefghijklmnopqrstuvwxyz0123456789.-_~:[]@#/?%! "
_ALLOWED = ("127.0.0.1", "localhost", "[::1]")


def _host_reference(value: str) -> bool:
    """Accepted without a token iff the value is an allowed name, maybe with a numeric port."""
    for name in _ALLOWED:
        rest = value.lower()[len(name) :] if value.lower().startswith(name) else None
        if rest is not None and (
            rest == ""
            or rest[:1] == ":"
            and rest[1:].isdigit()
            and len(rest) <= 6
            and int(rest[1:] or 0) <= 65535
            or rest == ":"
        ):
            return True
    return False


@pytest.mark.parametrize(
    ("host", "allowed"),
    [
        ("127.0.0.1", True),
        ("127.0.0.1:8080", True),
        ("LOCALHOST:80", True),
        ("[::1]:8080", True),
        ("[::1]", True),
        ("127.0.0.1:8080.evil.example", False),
        ("localhost:80.evil.example", False),
        ("127.0.0.1:8080:9090", False),
        ("127.0.0.1:99999", False),
        ("127.0.0.1@evil.example", False),
        ("127.0.0.1.evil.example", False),
        ("[::1].evil.example", False),
        ("127.0.0.1 ", True),
        ("evil.example:127", False),
        ("", False),
        ("127.0.0.1:80 evil", False),
    ],
)
def test_the_host_header_is_parsed_strictly(client: TestClient, host: str, allowed: bool) -> None:
    reply = client.get("/api/status", headers={"host": host})
    assert reply.status_code == (200 if allowed else 400), (host, reply.text)
    if not allowed:
        assert "is not allowed" in reply.json()["detail"]


def test_host_check_matches_the_rfc_reading_for_any_header(client: TestClient) -> None:
    """Property: without a token, a Host header is accepted only when it is an allowed name,
    optionally followed by ':' and a port number; nothing else (suffixes, user info, paths)."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    values = st.one_of(
        st.text(alphabet=_HOST_CHARS, max_size=30),
        st.builds(
            lambda name, rest: name + rest,
            st.sampled_from(_ALLOWED),
            st.text(alphabet=_HOST_CHARS, max_size=20),
        ),
        st.builds(
            lambda name, port: f"{name}:{port}", st.sampled_from(_ALLOWED), st.integers(0, 70000)
        ),
    )

    @settings(
        max_examples=300,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.function_scoped_fixture],
    )
    @given(values)
    def check(value: str) -> None:
        value = value.strip()
        reply = client.get("/api/status", headers={"host": value})
        assert (reply.status_code == 200) == _host_reference(value), (value, reply.text)

    check()


@pytest.mark.parametrize(
    "host",
    [
        "127.attacker.example",
        "127.0.0.1.nip.io",
        "127.0.0.1.",
        "localhost.attacker.example",
        "127.1",
        "::ffff:127.0.0.1",
    ],
)
def test_only_literal_loopback_addresses_count_as_loopback(host: str) -> None:
    # Names are not resolved: what "127.x" resolves to is whoever owns the name.
    with pytest.raises(ServeError, match="needs a token"):
        check_binding(host, None)


@pytest.mark.parametrize("host", ["127.0.0.1", "127.1.2.3", "localhost", "::1", "[::1]"])
def test_literal_loopback_addresses_need_no_token(host: str) -> None:
    check_binding(host, None)


def test_serve_on_a_127_name_is_refused_without_resolving_it(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("SHADOWHOUND_TOKEN", raising=False)
    # .invalid never resolves (RFC 2606): refused for the missing token, not a failed lookup.
    assert serve_main(ShadowHoundConfig(), host="127.0.0.1.invalid", port=0) == 2
    assert "needs a token" in capsys.readouterr().err


def test_a_body_whose_client_went_away_reaches_no_route() -> None:
    """A client that leaves mid-upload is nobody to answer: before, the route read a body that
    never came and the server logged a failed request for every one (ClientDisconnect)."""
    import asyncio

    from shadowhound.web.security import Gate

    called, sent = [], []

    async def app(*_args: object) -> None:
        called.append(True)

    async def receive() -> dict[str, object]:
        return messages.pop(0)

    async def send(message: dict[str, object]) -> None:
        sent.append(message)

    messages: list[dict[str, object]] = [
        {"type": "http.request", "body": b"RIFF", "more_body": True},
        {"type": "http.disconnect"},
    ]
    scope = {
        "type": "http",
        "method": "POST",
        "path": "/api/speech",
        "scheme": "http",
        "headers": [(b"host", b"127.0.0.1"), (b"content-type", b"audio/wav")],
    }
    gate = Gate(app, token=None, allowed_hosts=["127.0.0.1"], max_body=1000)
    asyncio.run(gate(scope, receive, send))
    assert called == [] and sent == []
