"""The HMI's web server: the page, a server-sent event stream of state and history, commands.

Standard library only (`http.server`): one thread per connection, so a
browser's long-lived event stream does not hold up other requests. The server
never touches the space: it reads the latest state and history from a
`StateBoard` and hands commands (and `why` questions) to the agent's thread
through a `Commands` queue. State-changing requests pass `guard.Guard` first.

Routes:
    GET  /             the page (index.html, hmi.js, plots.js, why.js, hmi.css, vendor/ here)
    GET  /api/state    the state as JSON
    GET  /api/history  the history events kept, as a JSON list
    GET  /api/why?t=[s,p,o]...  why each triple (N-Triples, null for any) holds
    GET  /events       server-sent events: `state` per change, `history` with new events
    POST /api/task     {"robot": "robot1", "task": "AttendingPatient"}: request a task
    POST /api/battery  {"robot": "robot1", "level": "very low"}: set the simulated battery
"""

from __future__ import annotations

import json
import queue
import threading
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass, field
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from urllib.parse import parse_qs, urlsplit

from agents.hmi_web.guard import Guard, Refused
from space import SpaceError

KEEPALIVE = 15.0
COMMAND_TIMEOUT = 10.0
HISTORY_KEPT = 20_000  # history events the board keeps for pages that (re)load
PAGE = "index.html"
STATIC = {
    "/hmi.js": ("hmi.js", "text/javascript; charset=utf-8"),
    "/plots.js": ("plots.js", "text/javascript; charset=utf-8"),
    "/why.js": ("why.js", "text/javascript; charset=utf-8"),
    "/hmi.css": ("hmi.css", "text/css; charset=utf-8"),
    "/vendor/uPlot.iife.min.js": ("vendor/uPlot.iife.min.js", "text/javascript; charset=utf-8"),
    "/vendor/uPlot.min.css": ("vendor/uPlot.min.css", "text/css; charset=utf-8"),
}


class CommandError(Exception):
    """A command from the page could not be carried out; the message is shown to the user."""


class StateBoard:
    """The latest state as JSON text and the history events, and a way to wait; thread-safe."""

    def __init__(self) -> None:
        self._changed = threading.Condition()
        self._text = json.dumps({"connected": False, "robots": [], "firings": []})
        self._version = 0
        self._closed = False
        self._events: deque[tuple[int, str]] = deque(maxlen=HISTORY_KEPT)
        self._count = 0

    def publish(self, state: dict, events: Sequence[dict] = ()) -> None:
        """Replace the state and add history events; wake every event stream if anything is new."""
        text = json.dumps(state)
        with self._changed:
            if text == self._text and not events:
                return
            for event in events:
                self._count += 1
                self._events.append((self._count, json.dumps({**event, "i": self._count})))
            self._text = text
            self._version += 1
            self._changed.notify_all()

    def events_after(self, index: int) -> tuple[int, list[str]]:
        """Return the index of the newest event and the events (JSON texts) after `index`."""
        with self._changed:
            return self._count, [text for i, text in self._events if i > index]

    def latest(self) -> tuple[int, str]:
        """Return the current version and state."""
        with self._changed:
            return self._version, self._text

    def wait(self, after: int, timeout: float) -> tuple[int, str] | None:
        """Block until a version newer than `after` (return it) or timeout/close (None)."""
        with self._changed:
            self._changed.wait_for(lambda: self._version > after or self._closed, timeout)
            if self._version > after and not self._closed:
                return self._version, self._text
            return None

    @property
    def closed(self) -> bool:
        """Return whether `close` was called."""
        with self._changed:
            return self._closed

    def close(self) -> None:
        """End every event stream."""
        with self._changed:
            self._closed = True
            self._changed.notify_all()


@dataclass
class Command:
    """A request from the page, run on the agent's thread; `done` gets its result."""

    name: str
    params: dict
    done: Future = field(default_factory=Future)


class Commands:
    """Commands from HTTP threads to the agent's thread."""

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[Command] = queue.SimpleQueue()

    def submit(self, name: str, params: dict, timeout: float = COMMAND_TIMEOUT) -> object:
        """Queue a command and block until the agent ran it; return its result.

        Raises:
            CommandError: the agent refused it, or did not run it within `timeout`.
        """
        command = Command(name, params)
        self._queue.put(command)
        try:
            return command.done.result(timeout)
        except FutureTimeout as exc:
            raise CommandError(f"the HMI agent did not answer in {timeout:.0f} s") from exc

    def run_pending(self, handler: Callable[[str, dict], object]) -> None:
        """Run every queued command with `handler` (on the caller's thread), settling each."""
        while True:
            try:
                command = self._queue.get_nowait()
            except queue.Empty:
                return
            try:
                command.done.set_result(handler(command.name, command.params))
            except Exception as exc:  # handed to the waiting HTTP thread, which reports it
                command.done.set_exception(exc)


class _Handler(BaseHTTPRequestHandler):
    server: HmiServer
    protocol_version = "HTTP/1.1"

    def log_message(self, format: str, *args: object) -> None:
        self.server.log(format % args)

    def do_GET(self) -> None:
        url = urlsplit(self.path)
        path = url.path
        try:
            self.server.guard.check_host(self.headers.get("Host"))
        except Refused as exc:
            self._json(HTTPStatus.FORBIDDEN, {"error": str(exc)})
            return
        if path in ("/", "/index.html"):
            self._page()
        elif path in STATIC:
            name, kind = STATIC[path]
            body = resources.files(__package__).joinpath(name).read_bytes()
            self._send(HTTPStatus.OK, body, kind)
        elif path == "/api/state":
            self._send(HTTPStatus.OK, self.server.board.latest()[1].encode(), "application/json")
        elif path == "/api/history":
            events = self.server.board.events_after(0)[1]
            self._send(HTTPStatus.OK, f"[{','.join(events)}]".encode(), "application/json")
        elif path == "/api/why":
            self._why(parse_qs(url.query).get("t", []))
        elif path == "/events":
            self._stream()
        else:
            self._send(HTTPStatus.NOT_FOUND, b"not found\n", "text/plain")

    def _page(self) -> None:
        """Serve the page with its session's token (a new session gets its cookie)."""
        guard = self.server.guard
        sid, new = guard.session(self.headers.get("Cookie"))
        text = resources.files(__package__).joinpath(PAGE).read_text(encoding="utf-8")
        body = text.replace("{{token}}", guard.token(sid)).encode()
        self._send(
            HTTPStatus.OK,
            body,
            "text/html; charset=utf-8",
            {"Set-Cookie": guard.set_cookie(sid)} if new else {},
        )

    def _why(self, wanted: list[str]) -> None:
        try:
            triples = [json.loads(t) for t in wanted]
            if not triples or not all(isinstance(t, list) and len(t) == 3 for t in triples):
                raise ValueError("give t=[s, p, o] (N-Triples terms, null for any) at least once")
            trees = self.server.commands.submit("why", {"templates": triples})
            self._json(HTTPStatus.OK, {"explanations": trees})
        except (ValueError, CommandError) as exc:
            self._json(HTTPStatus.BAD_REQUEST, {"error": str(exc)})
        except SpaceError as exc:
            self._json(HTTPStatus.SERVICE_UNAVAILABLE, {"error": str(exc)})

    def do_POST(self) -> None:
        name = {"/api/task": "task", "/api/battery": "battery"}.get(self.path)
        length = int(self.headers.get("Content-Length") or 0)
        try:
            self.server.guard.check({k.lower(): v for k, v in self.headers.items()})
        except Refused as exc:
            self.server.log(f"refused {self.path}: {exc}")
            self._json(HTTPStatus.FORBIDDEN, {"error": f"refused: {exc}"})
            return
        try:
            params = json.loads(self.rfile.read(length) or b"{}")
            if name is None:
                self._json(HTTPStatus.NOT_FOUND, {"error": f"no command at {self.path}"})
                return
            if not isinstance(params, dict):
                raise ValueError("the body must be a JSON object")
            result = self.server.commands.submit(name, params)
            self._json(HTTPStatus.OK, {"ok": True, "changeset": result})
        except (ValueError, CommandError) as exc:
            self._json(HTTPStatus.BAD_REQUEST, {"error": str(exc)})
        except SpaceError as exc:
            self._json(HTTPStatus.SERVICE_UNAVAILABLE, {"error": str(exc)})

    def _json(self, status: HTTPStatus, value: dict) -> None:
        self._send(status, json.dumps(value).encode(), "application/json")

    def _send(
        self, status: HTTPStatus, body: bytes, kind: str, extra: dict[str, str] | None = None
    ) -> None:
        self.send_response(status)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        for name, value in (extra or {}).items():
            self.send_header(name, value)
        self.end_headers()
        self.wfile.write(body)

    def _stream(self) -> None:
        """Send the state now and after each change until the client or the server goes."""
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.send_header("Connection", "close")
        self.end_headers()
        self.close_connection = True
        board = self.server.board
        version, text = board.latest()
        sent, events = board.events_after(0)
        try:
            # The whole history first: a page that reconnects starts it again.
            self.wfile.write(f"event: history-all\ndata: [{','.join(events)}]\n\n".encode())
            self.wfile.write(f"event: state\ndata: {text}\n\n".encode())
            self.wfile.flush()
            while not board.closed:
                news = board.wait(version, KEEPALIVE)
                if news is None:
                    self.wfile.write(b": keep-alive\n\n")
                else:
                    version, text = news
                    sent, events = board.events_after(sent)
                    if events:
                        data = f"[{','.join(events)}]"
                        self.wfile.write(f"event: history\ndata: {data}\n\n".encode())
                    self.wfile.write(f"event: state\ndata: {text}\n\n".encode())
                self.wfile.flush()
        except (BrokenPipeError, ConnectionResetError):
            self.server.log("an event stream closed")


class HmiServer(ThreadingHTTPServer):
    """The HMI's HTTP server; `serve_forever` on a thread of its own, `shutdown` to stop.

    Args:
        address: (host, port) to listen on; port 0 picks a free one (see `port`).
        board: where the state to show comes from.
        commands: where the page's commands go.
        log: gets one line per request (e.g. a logger's debug).
        guard: checks state-changing requests (a new `Guard()` by default).
    """

    daemon_threads = True

    def __init__(
        self,
        address: tuple[str, int],
        board: StateBoard,
        commands: Commands,
        log: Callable[[str], None],
        guard: Guard | None = None,
    ) -> None:
        self.board = board
        self.commands = commands
        self.log = log
        self.guard = guard or Guard()
        super().__init__(address, _Handler)

    @property
    def port(self) -> int:
        """Return the port the server listens on."""
        return int(self.server_address[1])
