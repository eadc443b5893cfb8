"""Who may open the page, and which requests the server answers at all.

- Local by default; the network only with an access token of at least 64 bits of strength,
  read from a file or an environment variable (not the parameter server), compared in
  constant time.
- Whatever the token: the server answers only requests addressed to its own name (the Host
  header: a loopback name or the configured host) and, for the page's live connection
  (socket.io), only from its own page (the Origin header). A web page elsewhere that has
  its name resolve to 127.0.0.1 (DNS rebinding) can therefore neither read the page nor
  press a control on it.
"""

import hmac
import math
import os
import string
from collections.abc import Iterable
from urllib.parse import urlsplit

from motion_common.errors import ParameterError

__all__ = [
    "LOCAL_HOSTS",
    "MIN_TOKEN_BITS",
    "TOKEN_ENV",
    "check_access_config",
    "token_accepted",
    "token_strength",
    "load_token",
    "allowed_hosts",
    "host_allowed",
    "origin_allowed",
    "HostOriginGuard",
]

LOCAL_HOSTS = frozenset({"127.0.0.1", "localhost", "::1"})
MIN_TOKEN_BITS = 64
TOKEN_ENV = "MOTION_DASHBOARD_TOKEN"
_TOKEN_HINT = (
    "e.g. openssl rand -hex 16 > ~/.dashboard_token; chmod 600 ~/.dashboard_token; "
    "dashboard_token_file:=~/.dashboard_token"
)


def token_strength(token: str) -> float:
    """Bits of a token as a guesser sees them: its length times log2 of the alphabet its
    character classes span (lower, upper, digits, the rest); a token that repeats few
    characters counts as its distinct characters only."""
    if not token:
        return 0.0
    classes = [string.ascii_lowercase, string.ascii_uppercase, string.digits]
    alphabet = sum(len(c) for c in classes if any(ch in c for ch in token))
    if any(not any(ch in c for c in classes) for ch in token):
        alphabet += 32
    distinct = len(set(token))
    return min(len(token), distinct * 2) * math.log2(max(alphabet, 2))


def load_token(param_token: str, token_file: str, environ=None) -> str:
    """The access token: ``token_file`` (its first line; the file must not be readable by
    others), else the environment variable MOTION_DASHBOARD_TOKEN, else the parameter.
    ParameterError saying what to fix."""
    environ = os.environ if environ is None else environ
    if token_file:
        path = os.path.expanduser(token_file)
        try:
            mode = os.stat(path).st_mode
            with open(path, encoding="utf-8") as stream:
                token = stream.readline().strip()
        except OSError as exc:
            raise ParameterError(f"dashboard_token_file {path}: cannot read: {exc.strerror or exc}") from None
        if mode & 0o077:
            raise ParameterError(
                f"dashboard_token_file {path} is readable by others (mode {mode & 0o777:o}); chmod 600 {path}"
            )
        if not token:
            raise ParameterError(f"dashboard_token_file {path} is empty")
        return token
    return environ.get(TOKEN_ENV, "") or param_token


def check_access_config(host: str, token: str) -> None:
    """Refuse to serve beyond this machine without a strong enough token (ParameterError
    saying what to do)."""
    if token and token_strength(token) < MIN_TOKEN_BITS:
        raise ParameterError(
            f"the dashboard token is too weak ({token_strength(token):.0f} bits, at least "
            f"{MIN_TOKEN_BITS} needed: 16 random hex digits or more); {_TOKEN_HINT}"
        )
    if host not in LOCAL_HOSTS and not token:
        raise ParameterError(
            f"dashboard_host:={host} opens the dashboard (and its robot controls) to the network: "
            f"also give an access token ({_TOKEN_HINT}, or the environment variable {TOKEN_ENV}), "
            "and open http://<this machine>:<port>/?token=<token>; or keep the default "
            "dashboard_host:=127.0.0.1"
        )


def token_accepted(expected: str, given: str) -> bool:
    """True when no token is configured, or ``given`` matches it (constant-time compare)."""
    if not expected:
        return True
    return hmac.compare_digest(expected.encode(), (given or "").encode())


def allowed_hosts(host: str) -> frozenset:
    """The names the server answers to: the loopback names, and the configured address
    unless it is a wildcard (0.0.0.0 or ::, which no browser puts in a Host header)."""
    names = set(LOCAL_HOSTS)
    if host and host not in ("0.0.0.0", "::"):
        names.add(host.lower())
    return frozenset(names)


def _hostname(authority: str) -> str | None:
    """The host part of a Host header value or a URL's authority, lower case, without the
    port or IPv6 brackets; None when it cannot be parsed."""
    try:
        parsed = urlsplit("//" + authority.strip())
        name = parsed.hostname
        parsed.port  # noqa: B018 - raises ValueError on a malformed port
    except ValueError:
        return None
    return name.lower() if name else None


def host_allowed(header: str | None, allowed: Iterable[str], extra: Iterable[str] = ()) -> bool:
    """Whether a request's Host header names this server (``extra``: more names, e.g. the
    machine's own name when serving the network)."""
    if not header:
        return False
    name = _hostname(header)
    return name is not None and (name in allowed or name in {e.lower() for e in extra})


def origin_allowed(origin: str | None, allowed: Iterable[str], extra: Iterable[str] = ()) -> bool:
    """Whether a request's Origin header is this server's own page (no Origin: not a
    browser page, allowed; the Host check still applies)."""
    if origin is None:
        return True
    try:
        parts = urlsplit(origin)
    except ValueError:
        return False
    if parts.scheme not in ("http", "https") or not parts.netloc:
        return False
    return host_allowed(parts.netloc, allowed, extra)


class HostOriginGuard:
    """ASGI middleware: answers 403 to a request whose Host (or, when present, Origin) is not
    this server's, for plain HTTP and for websocket upgrades alike, before the page or
    socket.io sees it. ``refused`` counts the refusals."""

    def __init__(self, app, host: str, extra_hosts: Iterable[str] = ()):
        self.app = app
        self.allowed = allowed_hosts(host)
        self.extra = tuple(extra_hosts)
        self.refused = 0

    def reason(self, scope) -> str | None:
        """Why the request is refused, or None."""
        headers = {}
        for key, value in scope.get("headers") or []:
            headers.setdefault(key.decode("latin-1").lower(), value.decode("latin-1"))
        if not host_allowed(headers.get("host"), self.allowed, self.extra):
            return f"Host {headers.get('host')!r} is not this dashboard"
        if not origin_allowed(headers.get("origin"), self.allowed, self.extra):
            return f"Origin {headers.get('origin')!r} is not this dashboard's page"
        return None

    async def __call__(self, scope, receive, send):
        if scope["type"] not in ("http", "websocket"):
            return await self.app(scope, receive, send)
        why = self.reason(scope)
        if why is None:
            return await self.app(scope, receive, send)
        self.refused += 1
        body = f"403 Forbidden: {why}\n".encode()
        if scope["type"] == "websocket":
            await receive()  # the websocket.connect message
            await send({"type": "websocket.close", "code": 1008, "reason": why[:120]})
            return None
        await send(
            {
                "type": "http.response.start",
                "status": 403,
                "headers": [
                    (b"content-type", b"text/plain; charset=utf-8"),
                    (b"content-length", str(len(body)).encode()),
                ],
            }
        )
        await send({"type": "http.response.body", "body": body})
        return None
