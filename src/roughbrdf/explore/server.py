"""The local HTTP server of ``roughbrdf explore``: bind, guard, serve until Ctrl-C.

:func:`bind` opens the listening socket first (on ``127.0.0.1`` unless a host is given; port 0
takes a free port), so that a busy port is a clear error naming it before anything else
happens; :class:`Server` wraps the WSGI application in the token/Host/Origin guard
(:class:`roughbrdf.explore.security.Guard`) and serves it with Werkzeug's threaded server (the
server Flask, and so Dash, ships with). Nothing here imports Dash.

Examples
--------
>>> srv = bind(lambda env, start: [b""], port=0)
>>> srv.host, srv.port > 0, srv.url.startswith(f"http://127.0.0.1:{srv.port}/?token=")
('127.0.0.1', True, True)
>>> srv.close()
"""

from __future__ import annotations

import errno
import logging
import os
import socket
import sys
import threading
from typing import Any

from .security import Guard, WSGIApp, is_loopback, new_token

__all__ = ["Server", "bind", "DEFAULT_HOST", "exposure_note", "open_browser"]

#: where the server listens unless ``--host`` is given
DEFAULT_HOST = "127.0.0.1"


class Server:
    """A bound, guarded server (:func:`bind` makes one).

    Attributes
    ----------
    host : str
    port : int
        The bound port (the free one taken when 0 was asked).
    token : str
        The run's token.
    url : str
        The address to open, with the token.
    """

    def __init__(self, wsgi: Any, host: str, port: int, token: str) -> None:
        self._wsgi, self.host, self.port, self.token = wsgi, host, port, token
        shown = f"[{host}]" if ":" in host else host
        self.base = f"http://{shown}:{port}"
        self.url = f"{self.base}/?token={token}"

    def serve_forever(self) -> None:
        """Serve until :meth:`shutdown` or ``KeyboardInterrupt`` (Ctrl-C in the main thread)."""
        self._wsgi.serve_forever(poll_interval=0.2)

    def start_thread(self) -> threading.Thread:
        """Serve in a daemon thread (tests, notebooks); :meth:`shutdown` stops it."""
        thread = threading.Thread(target=self.serve_forever, name="roughbrdf-explore",
                                  daemon=True)
        thread.start()
        return thread

    def shutdown(self) -> None:
        """Stop :meth:`serve_forever` (from another thread) and close the socket."""
        self._wsgi.shutdown()
        self.close()

    def close(self) -> None:
        """Close the listening socket."""
        self._wsgi.server_close()


def bind(app: WSGIApp, *, host: str | None = None, port: int = 0,
         token: str | None = None) -> Server:
    """Bind a guarded server for the WSGI ``app``; nothing is served until
    :meth:`Server.serve_forever`.

    Parameters
    ----------
    app : WSGI application
    host : str, optional
        The address to listen on (default :data:`DEFAULT_HOST`, loopback only).
    port : int
        0 (default) takes a free port.
    token : str, optional
        Default: a new random one (:func:`~roughbrdf.explore.security.new_token`).

    Raises
    ------
    ValueError
        Naming ``--port`` when the port is busy or not a port, ``--host`` when the address
        cannot be bound here.
    """
    from werkzeug.serving import make_server

    host = DEFAULT_HOST if host is None else str(host).strip()
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ValueError(f"--port must be a port number in 0..65535, got {port!r}")
    token = token or new_token()
    holder: dict[str, Guard] = {}

    def guarded(environ: dict[str, Any], start_response: Any) -> Any:
        return holder["guard"](environ, start_response)

    logging.getLogger("werkzeug").setLevel(logging.ERROR)  # no line per request
    sock = _listen(host, port)
    try:  # Werkzeug serves the socket bound here (its own bind exits the process on errors)
        wsgi = make_server(host, int(sock.getsockname()[1]), guarded, threaded=True,
                           fd=sock.fileno())
    finally:
        sock.close()  # Werkzeug holds its own duplicate of the descriptor
    bound = int(wsgi.socket.getsockname()[1])
    holder["guard"] = Guard(app, token=token, host=host, port=bound)
    return Server(wsgi, host, bound, token)


def _listen(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host``:``port``; ``ValueError`` naming the option at
    fault."""
    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, port,
                                                             type=socket.SOCK_STREAM)[0]
    except (socket.gaierror, UnicodeError) as exc:
        raise ValueError(f"--host {host!r}: not an address of this machine ({exc})") from None
    sock = socket.socket(family, kind, proto)
    try:
        # SO_REUSEADDR as every server sets it: a port left in TIME_WAIT by the last run can be
        # taken again; on Linux it never takes a port another socket listens on
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(128)
    except OSError as exc:
        sock.close()
        if exc.errno == errno.EADDRINUSE:
            raise ValueError(f"--port {port}: the port is already in use on {host} (another "
                             "program listens there); choose another --port, or leave it out "
                             "to take a free one") from None
        if exc.errno == errno.EACCES:
            raise ValueError(f"--port {port}: not allowed to listen there (ports below 1024 "
                             "need privileges)") from None
        raise ValueError(f"--host {host!r}: cannot listen on this address "
                         f"({exc.strerror or exc})") from None
    return sock


def exposure_note(host: str) -> str:
    """What listening on ``host`` exposes, for the terminal ("" for loopback)."""
    if is_loopback(host):
        return ""
    where = "every network interface of this machine" if host in ("0.0.0.0", "::") \
        else f"the address {host}"
    return (f"note: --host {host}: listening on {where}: anyone who can reach it and has the "
            "printed address (its token) can evaluate, fit and export models here; the "
            "connection is plain HTTP (not encrypted)")


def open_browser(url: str) -> bool:
    """Open ``url`` in the user's browser when one is available (a graphical session); never
    a text browser in this terminal. Whether it was asked to open."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        return False  # no graphical session: webbrowser would pick a text browser here
    import webbrowser

    try:
        return bool(webbrowser.open(url, new=2))
    except webbrowser.Error:  # no browser registered
        return False
