"""Keep other web pages from driving the robot through the HMI (CSRF and DNS rebinding).

Any page a person has open can make their browser POST to
`http://127.0.0.1:8080/api/task`. So a state-changing request is taken only
when it carries:

- the session's token in an `X-HMI-Token` header: the page gets it when it is
  served (a cookie names the session), and a page of another origin can neither
  read it nor send a custom header without a CORS preflight this server never
  grants;
- an `Origin` that is this server's own (`http://<Host>`);
- a `Host` that names this machine (an IP address, `localhost`, its host name),
  so that a name an attacker re-points at 127.0.0.1 is refused too.

Everything else gets 403 and changes nothing.
"""

from __future__ import annotations

import hashlib
import hmac
import ipaddress
import secrets
import socket
from collections.abc import Iterable
from http.cookies import CookieError, SimpleCookie

COOKIE = "tspace_hmi"
TOKEN_HEADER = "X-HMI-Token"


class Refused(Exception):
    """A state-changing request failed a check; the message says which (sent with the 403)."""


class Guard:
    """Issue per-session tokens and check requests against them.

    Args:
        hosts: extra host names the HMI is reached by (besides IP addresses,
            `localhost` and this machine's names).
    """

    def __init__(self, hosts: Iterable[str] = ()) -> None:
        self._secret = secrets.token_bytes(32)
        names = {"localhost", socket.gethostname(), socket.getfqdn(), *hosts}
        self._hosts = {n.lower() for n in names if n}

    def session(self, cookie_header: str | None) -> tuple[str, bool]:
        """Return the session id of a request's cookie, or a new one (and True: set it)."""
        sid = _cookie(cookie_header)
        if sid is not None and len(sid) == 32:
            return sid, False
        return secrets.token_hex(16), True

    def token(self, sid: str) -> str:
        """Return the token the page of session `sid` must send back."""
        return hmac.new(self._secret, sid.encode(), hashlib.sha256).hexdigest()[:32]

    def set_cookie(self, sid: str) -> str:
        """Return the Set-Cookie value for a new session."""
        return f"{COOKIE}={sid}; Path=/; HttpOnly; SameSite=Strict"

    def check_host(self, host: str | None) -> None:
        """Refuse a Host header that does not name this machine.

        Raises:
            Refused: no Host, or a name that is not an IP address nor one of this machine's.
        """
        if not host:
            raise Refused("no Host header")
        name = _hostname(host)
        if name in self._hosts:
            return
        try:
            ipaddress.ip_address(name)
        except ValueError:
            raise Refused(f"unknown host {name!r}") from None

    def check(self, headers: dict[str, str]) -> None:
        """Let a state-changing request through, or raise why not.

        `headers` maps lower-case header names to values.

        Raises:
            Refused: wrong host, missing or foreign Origin, missing session or token.
        """
        host = headers.get("host")
        self.check_host(host)
        origin = headers.get("origin")
        if origin is None:
            raise Refused("no Origin header")
        if origin.lower() != f"http://{host}".lower():
            raise Refused(f"cross-origin request from {origin}")
        sid = _cookie(headers.get("cookie"))
        sent = headers.get(TOKEN_HEADER.lower(), "")
        if sid is None or not hmac.compare_digest(sent, self.token(sid)):
            raise Refused("missing or wrong session token (reload the page)")


def _cookie(header: str | None) -> str | None:
    if not header:
        return None
    try:
        jar = SimpleCookie(header)
    except CookieError:
        return None
    morsel = jar.get(COOKIE)
    return morsel.value if morsel is not None else None


def _hostname(host: str) -> str:
    """Return the host part of a Host header (`[::1]:8080` -> `::1`), lower-case."""
    host = host.strip().lower()
    if host.startswith("["):
        return host[1:].split("]", 1)[0]
    return host.rsplit(":", 1)[0] if host.count(":") == 1 else host
