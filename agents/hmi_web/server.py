"""The HMI's web server: the page, a server-sent event stream of state, two commands.

Standard library only (`http.server`): one thread per connection, so a
browser's long-lived event stream does not hold up other requests. The server
never touches the space: it reads the latest state from a `StateBoard` and
hands commands to the agent's thread through a `Commands` queue.

Routes:
    GET  /             the page (index.html, hmi.js, hmi.css beside this module)
    GET  /api/state    the state as JSON
    GET  /events       the state as server-sent events, one `state` event per change
    POST /api/task     {"robot": "robot1", "task": "AttendingPatient"}: request a task
    POST /api/battery  {"robot": "robot1", "level": "very low"}: set the simulated battery
"""

from __future__ import annotations

import json
import queue
import threading
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass, field
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources

from space import SpaceError

KEEPALIVE = 15.0
COMMAND_TIMEOUT = 10.0
STATIC = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/index.html": ("index.html", "text/html; charset=utf-8"),
    "/hmi.js": ("hmi.js", "text/javascript; charset=utf-8"),
    "/hmi.css": ("hmi.css", "text/css; charset=utf-8"),
}


class CommandError(Exception):
    """A command from the page could not be carried out; the message is shown to the user."""


class StateBoard:
    """The latest state as JSON text, and a way to wait for the next one; thread-safe."""

    def __init__(self) -> None:
        self._changed = threading.Condition()
        self._text = json.dumps({"connected": False, "robots": [], "firings": []})
        self._version = 0
        self._closed = False

    def publish(self, state: dict) -> None:
        """Replace the state, waking every event stream if it differs."""
        text = json.dumps(state)
        with self._changed:
            if text == self._text:
                return
            self._text = text
            self._version += 1
            self._changed.notify_all()

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
        path = self.path.split("?", 1)[0]
        if path in STATIC:
            name, kind = STATIC[path]
            body = resources.files(__package__).joinpath(name).read_bytes()
            self._send(HTTPStatus.OK, body, kind)
        elif path == "/api/state":
            self._send(HTTPStatus.OK, self.server.board.latest()[1].encode(), "application/json")
        elif path == "/events":
            self._stream()
        else:
            self._send(HTTPStatus.NOT_FOUND, b"not found\n", "text/plain")

    def do_POST(self) -> None:
        name = {"/api/task": "task", "/api/battery": "battery"}.get(self.path)
        length = int(self.headers.get("Content-Length") or 0)
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

    def _send(self, status: HTTPStatus, body: bytes, kind: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
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
        try:
            self.wfile.write(f"event: state\ndata: {text}\n\n".encode())
            self.wfile.flush()
            while not board.closed:
                news = board.wait(version, KEEPALIVE)
                if news is None:
                    self.wfile.write(b": keep-alive\n\n")
                else:
                    version, text = news
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
    """

    daemon_threads = True

    def __init__(
        self,
        address: tuple[str, int],
        board: StateBoard,
        commands: Commands,
        log: Callable[[str], None],
    ) -> None:
        self.board = board
        self.commands = commands
        self.log = log
        super().__init__(address, _Handler)

    @property
    def port(self) -> int:
        """Return the port the server listens on."""
        return int(self.server_address[1])
