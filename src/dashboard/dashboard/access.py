"""Who may open the page: local by default; the network only with an access token."""
import hmac

from motion_common.errors import ParameterError

LOCAL_HOSTS = frozenset({"127.0.0.1", "localhost", "::1"})
MIN_TOKEN_LENGTH = 16


def check_access_config(host: str, token: str) -> None:
    """Refuse to serve beyond this machine without a long enough token (ParameterError
    saying what to do)."""
    if token and len(token) < MIN_TOKEN_LENGTH:
        raise ParameterError(f"dashboard_token is {len(token)} characters; use at least {MIN_TOKEN_LENGTH}, "
                             "e.g. dashboard_token:=$(openssl rand -hex 16)")
    if host not in LOCAL_HOSTS and not token:
        raise ParameterError(f"dashboard_host:={host} opens the dashboard (and its robot controls) to the network: "
                             "also give an access token, e.g. dashboard_token:=$(openssl rand -hex 16), and open "
                             "http://<this machine>:<port>/?token=<token>; or keep the default "
                             "dashboard_host:=127.0.0.1")


def token_accepted(expected: str, given: str) -> bool:
    """True when no token is configured, or ``given`` matches it (constant-time compare)."""
    if not expected:
        return True
    return hmac.compare_digest(expected.encode(), (given or "").encode())
