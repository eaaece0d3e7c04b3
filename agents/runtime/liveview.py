"""What `tspace up` shows: a redrawn terminal screen, or log lines when piped.

On a terminal the screen is redrawn in place with the robots, the processes,
the last rule firings and the last supervisor events. When stdout is not a
terminal (CI, `| tee`), the same information becomes one log line per change,
so nothing is lost and nothing is overwritten.
"""

from __future__ import annotations

import shutil
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import TextIO

from agents.runtime.robotview import Answer, RobotState
from agents.runtime.supervisor import ProcessStatus

REDRAW_EVERY = 0.25


@dataclass(frozen=True)
class Frame:
    """Everything one redraw shows."""

    header: str
    robots: list[RobotState]
    firings: list[Answer]
    processes: list[ProcessStatus]
    footer: str = ""


def robot_line(robot: RobotState) -> str:
    """Return the one-line summary of a robot."""
    battery = robot.battery or "?"
    if robot.charge is not None:
        battery += f" ({robot.charge}%)"
    return (
        f"{robot.name}: task {robot.task_type or '?'}, at {robot.location or '?'}, "
        f"battery {battery}, speed {robot.speed or '?'}"
    )


def devices_line(robot: RobotState) -> str:
    """Return the running mode of every device of a robot on one line."""
    prefix = robot.name + "_"
    return ", ".join(f"{d.name.removeprefix(prefix)} {d.mode or '?'}" for d in robot.devices)


def firing_line(firing: Answer, raw: bool = False) -> str:
    """Return a firing on one line: its sentence and rules, or (`raw`) its triples and cause."""
    if firing.sentence and not raw:
        rules = f" [{', '.join(firing.rules)}]" if firing.rules else ""
        return f"{firing.time} {firing.sentence}{rules}"
    what = "; ".join(firing.added) or "; ".join(f"-{t}" for t in firing.removed)
    because = f" <- {firing.cause_agent}: {'; '.join(firing.cause)}" if firing.cause_agent else ""
    rules = f" [{', '.join(firing.rules)}]" if firing.rules else ""
    return f"{firing.time} {firing.agent}{rules}: {what}{because}"


class LiveView:
    """Show the deployment, either redrawn in place or as log lines.

    Args:
        out: where the view goes (stdout).
        err: where events go in log mode (stderr).
        redraw: True for a terminal screen; False for log lines.
        raw: show firings as their triples and cause, not as sentences.
    """

    def __init__(self, out: TextIO, err: TextIO, redraw: bool, raw: bool = False) -> None:
        self._out = out
        self._err = err
        self._redraw = redraw
        self._raw = raw
        self._lock = threading.Lock()
        self._events: deque[str] = deque(maxlen=8)
        self._last_draw = 0.0
        self._seen_robots: dict[str, tuple[str, str]] = {}
        self._seen_seq = -1

    @classmethod
    def for_terminal(cls, raw: bool = False) -> LiveView:
        """Return a view on stdout that redraws only if stdout is a terminal."""
        return cls(sys.stdout, sys.stderr, sys.stdout.isatty(), raw)

    def event(self, line: str) -> None:
        """Show a supervisor or scenario event; callable from any thread."""
        stamped = f"{time.strftime('%H:%M:%S')} {line}"
        with self._lock:
            self._events.append(stamped)
            if not self._redraw:
                print(f"tspace up: {line}", file=self._err, flush=True)

    @property
    def logs_every_change(self) -> bool:
        """Return True in log mode, where `robots` must be fed every state the robots pass."""
        return not self._redraw

    def robots(self, robots: list[RobotState]) -> None:
        """Log the robots' lines that changed (log mode); callable from any thread.

        Fed after each changeset, so a state that lasts less than a redraw (a
        robot docking) is still in the log; a redraw shows only the latest.
        """
        if self._redraw:
            return
        lines = []
        with self._lock:
            for robot in robots:
                summary = (robot_line(robot), devices_line(robot))
                before = self._seen_robots.get(robot.name)
                if before is None or before[0] != summary[0]:
                    lines.append(summary[0])
                if before is None or before[1] != summary[1]:
                    lines.append(f"{robot.name} devices: {summary[1]}")
                self._seen_robots[robot.name] = summary
            self._write(lines)

    def show(self, frame: Frame, final: bool = False) -> None:
        """Redraw (at most every REDRAW_EVERY s unless `final`) or log new firings."""
        if self._redraw:
            self._draw(frame, final)
        else:
            self._log(frame)

    def close(self) -> None:
        """Leave the terminal with the cursor below the last frame."""
        if self._redraw:
            self._out.write("\n")
            self._out.flush()

    def _log(self, frame: Frame) -> None:
        lines = []
        for firing in reversed(frame.firings):
            if firing.seq > self._seen_seq:
                lines.append(f"firing: {firing_line(firing, self._raw)}")
        if frame.firings:
            self._seen_seq = max(self._seen_seq, frame.firings[0].seq)
        with self._lock:
            self._write(lines)

    def _write(self, lines: list[str]) -> None:
        if lines:
            self._out.write("".join(f"{line}\n" for line in lines))
            self._out.flush()

    def _draw(self, frame: Frame, final: bool) -> None:
        now = time.monotonic()
        if now - self._last_draw < REDRAW_EVERY and not final:
            return
        self._last_draw = now
        width, height = shutil.get_terminal_size()
        lines = [frame.header, ""]
        for robot in frame.robots:
            lines += [robot_line(robot), "  " + devices_line(robot)]
            if robot.announcement:
                lines.append(f"  says: {robot.announcement}")
        lines += ["", "processes:"]
        lines += [
            f"  {p.name:<14} "
            + (f"pid {p.pid}" if p.running else (p.exit_status or "down"))
            + (f", restarted {p.restarts}x" if p.restarts else "")
            for p in frame.processes
        ]
        lines += ["", "rule firings (newest first):"]
        lines += [f"  {firing_line(f, self._raw)}" for f in frame.firings[:8]]
        with self._lock:
            events = list(self._events)
        lines += ["", "events:", *(f"  {e}" for e in events)]
        if frame.footer:
            lines += ["", frame.footer]
        text = "\n".join(line[:width] for line in lines[: height - 1])
        self._out.write("\x1b[H\x1b[2J" + text)
        self._out.flush()
