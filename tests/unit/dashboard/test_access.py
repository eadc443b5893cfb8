"""The dashboard answers only its own page: Host and Origin checks (against DNS
rebinding), token strength and where the token comes from."""

import asyncio
import os

import pytest

from dashboard.access import (
    HostOriginGuard,
    allowed_hosts,
    check_access_config,
    host_allowed,
    load_token,
    origin_allowed,
    token_strength,
)
from motion_common.errors import ParameterError

LOCAL = allowed_hosts("127.0.0.1")


@pytest.mark.parametrize("header", ["127.0.0.1:8080", "localhost:8080", "LOCALHOST", "[::1]:8080", "127.0.0.1"])
def test_loopback_names_are_answered(header):
    assert host_allowed(header, LOCAL)


@pytest.mark.parametrize(
    "header",
    [
        "evil.example:8080",
        "evil.example",
        "127.0.0.1.evil.example:8080",
        "",
        None,
        "127.0.0.1:notaport",
        "10.0.0.5:8080",
    ],
)
def test_foreign_or_malformed_hosts_are_refused(header):
    assert not host_allowed(header, LOCAL)


def test_a_network_host_adds_only_its_own_names():
    assert host_allowed("robot-pc:8080", allowed_hosts("0.0.0.0"), extra=["robot-pc"])
    assert not host_allowed("evil.example:8080", allowed_hosts("0.0.0.0"), extra=["robot-pc"])
    assert host_allowed("192.168.1.20:8080", allowed_hosts("192.168.1.20"))


def test_origin_must_be_the_page_itself():
    assert origin_allowed(None, LOCAL)  # not a browser page: the Host check still applies
    assert origin_allowed("http://127.0.0.1:8080", LOCAL)
    assert not origin_allowed("http://evil.example:8080", LOCAL)
    assert not origin_allowed("null", LOCAL)
    assert not origin_allowed("file://", LOCAL)


def run_guard(headers, kind="http"):
    reached, sent = [], []

    async def app(scope, receive, send):
        reached.append(scope)

    async def receive():
        return {"type": "websocket.connect"}

    async def send(message):
        sent.append(message)

    guard = HostOriginGuard(app, "127.0.0.1")
    scope = {"type": kind, "headers": [(k.encode(), v.encode()) for k, v in headers.items()]}
    asyncio.run(guard(scope, receive, send))
    return reached, sent, guard


def test_guard_passes_the_own_page_through():
    reached, sent, guard = run_guard({"host": "127.0.0.1:8080", "origin": "http://127.0.0.1:8080"})
    assert reached and not sent and guard.refused == 0


def test_guard_refuses_a_rebound_name_before_the_app_sees_it():
    reached, sent, guard = run_guard({"host": "evil.example:8080"})
    assert not reached and sent[0]["status"] == 403 and b"Host" in sent[1]["body"] and guard.refused == 1


def test_guard_closes_a_websocket_from_a_foreign_page():
    reached, sent, _ = run_guard({"host": "127.0.0.1:8080", "origin": "http://evil.example:8080"}, "websocket")
    assert not reached and sent == [{"type": "websocket.close", "code": 1008, "reason": sent[0]["reason"]}]


def test_weak_tokens_are_refused():
    for weak in ("a" * 16, "aaaaaaaabbbbbbbb", "password12345678"[:10], "abababababababababab"):
        with pytest.raises(ParameterError, match="too weak"):
            check_access_config("0.0.0.0", weak)
    check_access_config("0.0.0.0", "0123456789abcdef")  # 16 hex digits: 64 bits
    assert token_strength("a" * 16) < 64 <= token_strength(os.urandom(16).hex())


def test_token_comes_from_a_private_file_then_the_environment(tmp_path):
    path = tmp_path / "token"
    path.write_text("f00dfeedcafe0123456789abcdef0000\n")
    path.chmod(0o600)
    assert load_token("param", str(path), environ={}) == "f00dfeedcafe0123456789abcdef0000"
    assert load_token("param", "", environ={"MOTION_DASHBOARD_TOKEN": "env"}) == "env"
    assert load_token("param", "", environ={}) == "param"
    path.chmod(0o644)
    with pytest.raises(ParameterError, match="chmod 600"):
        load_token("", str(path), environ={})
    with pytest.raises(ParameterError, match="cannot read"):
        load_token("", str(tmp_path / "missing"), environ={})
