"""Who may talk to ``roughbrdf explore``: the run's token, and the bound Host and Origin.

The server of ``roughbrdf explore`` runs Python on request (model evaluations, fits, exports
into the ``--out`` folder), so it answers only the browser tab its user opened:

* **the token.** Each run draws a random token (:func:`new_token`, 256 bits from
  :mod:`secrets`) and prints it in its address, ``http://127.0.0.1:PORT/?token=...``. The first
  page load carries it as a query parameter; the answer is a redirect to the same page without
  it, setting a cookie ``roughbrdf-explore-PORT`` (``HttpOnly``, ``SameSite=Strict``, path
  ``/``) that the page's own requests then carry. A client may instead send the header
  ``X-Roughbrdf-Token``. Every other request gets **403**. Another local user, or a script in
  another web page, does not know the token;
* **the Host header** must name the bound address and port (``127.0.0.1:PORT``, also
  ``localhost:PORT`` on loopback; on a wildcard ``--host 0.0.0.0`` an IP literal or this
  machine's own name): a foreign name is **403**. This stops DNS rebinding (a web page whose
  domain is made to resolve to 127.0.0.1);
* **the Origin header**, when present (browsers send it with every POST and cross-origin
  request), must be the server's own origin: a foreign one is **403**.

The guard is WSGI middleware (:class:`Guard`) around the Dash (Flask) application; it needs no
Dash and is tested on its own (``tests/explore/test_explore_server.py``).

Examples
--------
>>> g = Guard(lambda env, start: [b"ok"], token="t0k", host="127.0.0.1", port=8050)
>>> g.allowed_hosts == {"127.0.0.1:8050", "localhost:8050"}
True
>>> g.check({"HTTP_HOST": "127.0.0.1:8050", "QUERY_STRING": "token=t0k"})
''
>>> g.check({"HTTP_HOST": "evil.example:8050"})
"Host 'evil.example:8050' is not this server's address"
"""

from __future__ import annotations

import hmac
import ipaddress
import secrets
import socket
from collections.abc import Callable, Iterable
from http.cookies import CookieError, SimpleCookie
from typing import Any
from urllib.parse import parse_qs, urlencode

__all__ = ["Guard", "new_token", "is_loopback", "TOKEN_HEADER", "cookie_name"]

#: the header a client other than the page may send the token in
TOKEN_HEADER = "X-Roughbrdf-Token"
_ENV_HEADER = "HTTP_" + TOKEN_HEADER.upper().replace("-", "_")

WSGIApp = Callable[[dict[str, Any], Callable[..., Any]], Iterable[bytes]]


def new_token() -> str:
    """A fresh random token for one run (32 bytes, URL-safe text)."""
    return secrets.token_urlsafe(32)


def cookie_name(port: int) -> str:
    """The cookie that carries the token of the server on ``port`` (cookies are shared by all
    the ports of a host: one name per port keeps two servers apart)."""
    return f"roughbrdf-explore-{int(port)}"


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a name or an address) is this machine's loopback interface.

    Examples
    --------
    >>> is_loopback("127.0.0.1"), is_loopback("localhost"), is_loopback("0.0.0.0")
    (True, True, False)
    """
    if host.strip("[]").lower() in ("localhost", "localhost.localdomain"):
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:  # a name other than localhost: not known to be loopback
        return False


def _is_wildcard(host: str) -> bool:
    try:
        return ipaddress.ip_address(host.strip("[]")).is_unspecified
    except ValueError:
        return False


def _is_ip(host: str) -> bool:
    try:
        ipaddress.ip_address(host.strip("[]"))
    except ValueError:
        return False
    return True


def _split_host(value: str) -> tuple[str, str]:
    """``"h:p"`` or ``"[v6]:p"`` -> ``(h, p)`` (port "" when absent)."""
    if value.startswith("["):
        name, _, rest = value[1:].partition("]")
        return name, rest[1:] if rest.startswith(":") else ""
    name, _, port = value.rpartition(":") if value.count(":") == 1 else (value, "", "")
    return name, port


class Guard:
    """WSGI middleware: only requests with the run's token and a matching Host/Origin pass.

    Parameters
    ----------
    app : WSGI application
        The application behind the guard (Dash's Flask server).
    token : str
        The run's token (:func:`new_token`).
    host : str
        The address the server is bound to (``--host``, default ``127.0.0.1``).
    port : int
        The bound port.
    """

    def __init__(self, app: WSGIApp, *, token: str, host: str, port: int) -> None:
        if not token:
            raise ValueError("the token must not be empty")
        self.app, self.token, self.host, self.port = app, token, host, int(port)
        self.cookie = cookie_name(port)
        names = {host.lower()}
        if is_loopback(host):
            names |= {"127.0.0.1", "localhost"}
        self.wildcard = _is_wildcard(host)
        if self.wildcard:  # the machine's own names; any IP literal is checked in _host_ok
            names |= {"localhost", socket.gethostname().lower(), socket.getfqdn().lower()}
        self.names = names
        self.allowed_hosts = {f"{n}:{self.port}" if ":" not in n else f"[{n}]:{self.port}"
                              for n in names}

    # -- checks -----------------------------------------------------------------------------
    def _host_ok(self, value: str) -> bool:
        name, port = _split_host(value.strip().lower())
        if port != str(self.port):
            return False
        return name in self.names or (self.wildcard and _is_ip(name))

    def _given_token(self, environ: dict[str, Any]) -> tuple[str, bool]:
        """The token the request carries and whether it came in the query string."""
        query = parse_qs(environ.get("QUERY_STRING", ""))
        if query.get("token"):
            return query["token"][0], True
        header = environ.get(_ENV_HEADER)
        if header:
            return str(header), False
        try:
            jar = SimpleCookie(environ.get("HTTP_COOKIE", ""))
        except CookieError:  # a malformed cookie header carries no token
            return "", False
        morsel = jar.get(self.cookie)
        return (morsel.value if morsel is not None else ""), False

    def check(self, environ: dict[str, Any]) -> str:
        """Why the request must be refused ("" when it may pass)."""
        host = environ.get("HTTP_HOST", "")
        if not self._host_ok(host):
            return f"Host {host!r} is not this server's address"
        origin = environ.get("HTTP_ORIGIN")
        if origin is not None:
            scheme, _, rest = origin.partition("://")
            if scheme != "http" or not self._host_ok(rest.rstrip("/")):
                return f"Origin {origin!r} is not this server's page"
        given, _ = self._given_token(environ)
        # compare_digest: the time taken does not tell how much of a guess was right
        if not given or not hmac.compare_digest(given.encode(), self.token.encode()):
            return "no valid token (open the address printed when the server started)"
        return ""

    # -- WSGI -------------------------------------------------------------------------------
    def __call__(self, environ: dict[str, Any], start_response: Callable[..., Any]
                 ) -> Iterable[bytes]:
        why = self.check(environ)
        if why:
            body = f"403 Forbidden: roughbrdf explore: {why}\n".encode()
            start_response("403 Forbidden", [("Content-Type", "text/plain; charset=utf-8"),
                                             ("Content-Length", str(len(body))),
                                             ("Cache-Control", "no-store")])
            return [body]
        _, in_query = self._given_token(environ)
        if in_query and environ.get("REQUEST_METHOD", "GET") in ("GET", "HEAD"):
            return self._redirect(environ, start_response)
        return self.app(environ, start_response)

    def _redirect(self, environ: dict[str, Any], start_response: Callable[..., Any]
                  ) -> Iterable[bytes]:
        """The same page without the token in its address, the token set as the cookie."""
        query = {k: v for k, v in parse_qs(environ.get("QUERY_STRING", "")).items()
                 if k != "token"}
        location = (environ.get("SCRIPT_NAME", "") + environ.get("PATH_INFO", "/")) or "/"
        if query:
            location += "?" + urlencode(query, doseq=True)
        cookie = f"{self.cookie}={self.token}; Path=/; HttpOnly; SameSite=Strict"
        start_response("303 See Other", [("Location", location), ("Set-Cookie", cookie),
                                         ("Content-Length", "0"),
                                         ("Cache-Control", "no-store"),
                                         ("Referrer-Policy", "no-referrer")])
        return [b""]
