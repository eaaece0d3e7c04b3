"""SIGINT and SIGTERM become a call on a thread of their own (`space.on_stop_signals`), so a
signal that lands while the main thread holds a lock cannot hang the process."""

from __future__ import annotations

import subprocess
import sys

SCRIPT = """
import os, signal, threading
from space import on_stop_signals

called = []
done = threading.Event()
lock = threading.Lock()
def stop():
    with lock:  # called in the handler, in the main thread, this would wait for ever
        called.append(threading.current_thread().name)
    done.set()

with on_stop_signals(stop):
    with lock:  # the signal lands while the main thread holds a lock the call takes
        os.kill(os.getpid(), signal.SIGTERM)
        os.kill(os.getpid(), signal.SIGINT)
    assert done.wait(5), "not called"
print(called)
print(signal.getsignal(signal.SIGTERM) is signal.SIG_DFL, signal.set_wakeup_fd(-1))
"""


def test_each_stop_signal_calls_the_action_off_the_main_thread_and_the_block_puts_back_what_was():
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=30
    )
    assert done.returncode == 0, done.stderr
    called, restored = done.stdout.splitlines()
    assert called == "['stop-signals', 'stop-signals']"
    assert restored == "True -1"
