"""Ctrl-C sent to a child process, as a user presses it: shared by the tests of interruption."""

from __future__ import annotations

import signal
import subprocess
import time

import pytest


def ctrl_c(p: subprocess.Popen[str], after_s: float, timeout_s: float) -> tuple[str, str, float]:
    """Wait for the child's ``ready`` line, let it work ``after_s`` seconds, send SIGINT; return
    its stdout, its stderr and the seconds it took to end. Fails the test (and kills the child)
    when it is still running ``timeout_s`` seconds after the signal."""
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "ready"
    time.sleep(after_s)
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    try:
        out, err = p.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        pytest.fail(f"still running {timeout_s} s after Ctrl-C")
    return out, err, time.monotonic() - sent
