"""The edge filter on a real message bus (issue 13 point 3): a local mosquitto broker, the
pipeline `mosquitto_sub -t in | thermerr-edge model.json | mosquitto_pub -t out -l` and a run
published row by row. Every compensation value arrives, in order, while the pipeline is still
running (the filter flushes every line), and equals the library's.

No sleeps: the broker is awaited by connecting to its port, and the subscribers are registered
before anything is published as persistent QoS 1 sessions (`-c -i ID`, `-E` returns once the
broker acknowledged the subscription), so the broker queues every message for them until they
(re)connect. Every wait has a deadline and a failure says what was received."""

from __future__ import annotations

import shutil
import socket
import subprocess
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

import thermerr_rs as tr

SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13"]
SHAPE = "limit=20,rate=1,unit=0.1,bits=16"
TIMEOUT = 60.0  # seconds for any one wait; a healthy run takes well under a second


def _tool(name: str) -> str | None:
    found = shutil.which(name)
    if found is None and Path(f"/usr/sbin/{name}").exists():  # Debian puts the broker there
        found = f"/usr/sbin/{name}"
    return found


MOSQUITTO, PUB, SUB = _tool("mosquitto"), _tool("mosquitto_pub"), _tool("mosquitto_sub")


@pytest.fixture
def procs():
    """Start processes that are killed (and reaped) at teardown, whatever happened."""
    started: list[subprocess.Popen] = []

    def _start(args: list[str], **kw) -> subprocess.Popen:
        p = subprocess.Popen(args, **kw)
        started.append(p)
        return p

    yield _start
    for p in reversed(started):
        if p.poll() is None:
            p.kill()
        try:
            p.wait(timeout=10)
        except subprocess.TimeoutExpired:  # pragma: no cover - a process that ignores SIGKILL
            pass


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def broker(procs, tmp_path: Path) -> tuple[str, int]:
    """A mosquitto of our own on 127.0.0.1 and a free port: no persistence, anonymous clients."""
    if MOSQUITTO is None or PUB is None or SUB is None:
        pytest.skip("mosquitto is not installed: apt-get install mosquitto mosquitto-clients")
    log = tmp_path / "mosquitto.log"
    for _attempt in range(3):  # the free port can be taken between probing and binding
        port = _free_port()
        conf = tmp_path / "mosquitto.conf"
        conf.write_text(f"listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\n"
                        "max_queued_messages 100000\nlog_dest stderr\n")
        with open(log, "w") as err:
            proc = procs([MOSQUITTO, "-c", str(conf)], stdout=err, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + TIMEOUT
        while proc.poll() is None and time.monotonic() < deadline:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                return "127.0.0.1", port
            except OSError:
                time.sleep(0.05)  # polling with a deadline, not a guess
        if proc.poll() is None:
            pytest.fail(f"mosquitto did not listen on port {port} within {TIMEOUT} s: {log.read_text()}")
    pytest.fail(f"mosquitto did not start (3 ports tried); its log: {log.read_text()}")


def _register(broker: tuple[str, int], client_id: str, topic: str) -> list[str]:
    """Create a persistent QoS 1 session subscribed to topic; returns the arguments that resume it."""
    host, port = broker
    args = [SUB, "-h", host, "-p", str(port), "-q", "1", "-c", "-i", client_id, "-t", topic]
    r = subprocess.run([*args, "-E"], capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 0, f"subscribing {client_id} to {topic!r} failed: {r.stdout}{r.stderr}"
    return args


def _run_over_mqtt(broker, procs, tmp_path: Path, edge_bin: Path, model_path: Path, run_csv: Path,
                   edge_args: list[str]) -> list[str]:
    """Publish run_csv (header, then a row per message) to `in` through the edge pipeline and
    return the lines received on `out`."""
    host, port = broker
    tag = uuid.uuid4().hex[:8]
    edge_in = _register(broker, f"edge-in-{tag}", "in")
    collect = _register(broker, f"collect-{tag}", "out")
    lines = [line for line in run_csv.read_text().splitlines() if line.strip()]
    expected = len(lines)  # the edge's header, then one line per row

    # the gateway's pipeline; it never sees the end of its input (it runs until killed)
    errs = {name: open(tmp_path / f"{name}.err", "w") for name in ("sub", "edge", "pub")}
    sub = procs(edge_in, stdout=subprocess.PIPE, stderr=errs["sub"])
    edge = procs([str(edge_bin), str(model_path), *edge_args], stdin=sub.stdout, stdout=subprocess.PIPE,
                 stderr=errs["edge"])
    pub = procs([PUB, "-h", host, "-p", str(port), "-q", "1", "-t", "out", "-l"], stdin=edge.stdout,
                stderr=errs["pub"])
    assert sub.stdout is not None and edge.stdout is not None
    sub.stdout.close()  # the children hold their ends
    edge.stdout.close()
    for f in errs.values():
        f.close()

    received = tmp_path / "out.txt"
    with open(received, "w") as f, open(tmp_path / "collect.err", "w") as e:
        collector = procs([*collect, "-C", str(expected)], stdout=f, stderr=e)
    r = subprocess.run([PUB, "-h", host, "-p", str(port), "-q", "1", "-t", "in", "-l"],
                       input="\n".join(lines) + "\n", capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 0, f"publishing the run failed: {r.stderr}"

    def what_happened(why: str) -> str:
        got = received.read_text().splitlines()
        pipeline = "; ".join(f"{n} (exit {p.poll()}): {(tmp_path / f'{n}.err').read_text()!r}"
                             for n, p in (("sub", sub), ("edge", edge), ("pub", pub), ("collect", collector)))
        return f"{why}: {len(got)} of {expected} messages on 'out', last {got[-3:]}; {pipeline}"

    # wait for the collector; give up at the deadline or as soon as a stage of the pipeline dies
    deadline = time.monotonic() + TIMEOUT
    while collector.poll() is None:
        if any(p.poll() is not None for p in (sub, edge, pub)):
            pytest.fail(what_happened("the pipeline stopped"))
        if time.monotonic() > deadline:
            pytest.fail(what_happened(f"no complete answer within {TIMEOUT} s"))
        try:
            collector.wait(timeout=0.1)
        except subprocess.TimeoutExpired:
            pass
    got = received.read_text().splitlines()
    assert collector.returncode == 0 and len(got) == expected, what_happened(f"collector exit {collector.returncode}")
    # streamed, not batched at the end: the whole pipeline is still up, its input still open
    assert (sub.poll(), edge.poll(), pub.poll()) == (None, None, None), what_happened("the pipeline stopped")
    return got


def _fit(example_run1: Path, tmp_path: Path) -> tuple[tr.MLR, Path]:
    model = tr.MLR().fit_run(tr.read_run(example_run1), "E_z", SENSORS, inputs="rise")
    return model, model.save(tmp_path / "model.json")


def _table(got: list[str], header: str, ncol: int) -> np.ndarray:
    assert got[0] == header, f"first message on 'out': {got[0]!r}"
    rows = [line.split(",") for line in got[1:]]
    bad = [(i, line) for i, line in enumerate(got[1:]) if len(line.split(",")) != ncol]
    assert not bad, f"messages that are not {ncol} numbers: {bad[:3]}"
    return np.array([[float(v) for v in row] for row in rows])


def test_every_compensation_arrives_in_order(broker, procs, tmp_path, edge_bin, example_run1, example_run2):
    model, path = _fit(example_run1, tmp_path)
    run = tr.read_run(example_run2)
    got = _run_over_mqtt(broker, procs, tmp_path, edge_bin, path, example_run2, [])
    table = _table(got, "time_s,E_z_pred", 2)
    want = model.predict_run(run)
    assert len(table) == len(run.time_s) == len(want)
    np.testing.assert_array_equal(table[:, 0], run.time_s)  # every row, in order, none twice
    np.testing.assert_allclose(table[:, 1], want, rtol=1e-9, atol=1e-12)


def test_shaped_offsets_over_mqtt(broker, procs, tmp_path, edge_bin, example_run1, example_run2):
    model, path = _fit(example_run1, tmp_path)
    run = tr.read_run(example_run2)
    got = _run_over_mqtt(broker, procs, tmp_path, edge_bin, path, example_run2, ["--shape", SHAPE])
    table = _table(got, "time_s,E_z_pred,E_z_offset", 3)
    y = model.predict_run(run)
    offsets = tr.shape_offsets(run.time_s, y, SHAPE)
    assert np.abs(y).max() > 20 and np.any(offsets != 0)  # the clamp and the offsets have work to do
    np.testing.assert_array_equal(table[:, 0], run.time_s)
    np.testing.assert_allclose(table[:, 1], y, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(table[:, 2], offsets)
