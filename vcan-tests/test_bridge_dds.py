"""vcan tests of the DDS bridge (issue 5): stepnode on vcan0, stepbridge, and DDS
subscribers in other processes: stepwatch (Fast DDS) and cyclone_sub (Cyclone DDS, built
from the IDL alone). Each test uses its own random DDS domain.

Binaries: STEPBRIDGE_BIN (build/bridge/stepbridge), STEPWATCH_BIN (build/tools/stepwatch),
CYCLONE_SUB_BIN (build/bridge/interop/cyclone_sub); a test whose binary is missing skips."""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import time
from pathlib import Path
from typing import List, Optional, Tuple

import pytest

from axis_helpers import NODE, boot, clear_and_profile
from conftest import CHANNEL, REPO_ROOT


def _bin(var: str, default: str) -> Path:
    p = Path(os.environ.get(var, default))
    p = p if p.is_absolute() else REPO_ROOT / p
    if not p.exists():
        pytest.skip(f"{p.name} not found at {p}: build it or set {var}")
    return p


@pytest.fixture
def stepbridge_bin() -> Path:
    return _bin("STEPBRIDGE_BIN", "build/bridge/stepbridge")


@pytest.fixture
def stepwatch_bin() -> Path:
    return _bin("STEPWATCH_BIN", "build/tools/stepwatch")


@pytest.fixture
def domain() -> int:
    return random.randint(50, 229)


@pytest.fixture
def node_config(tmp_path) -> Path:
    """Two axes, heartbeat every 200 ms (so a lost node is seen within about a second)."""
    p = tmp_path / "node.toml"
    p.write_text('axes = 2\n[defaults]\n"1017" = 200\n')
    return p


@pytest.fixture
def start_bridge(stepbridge_bin, tmp_path):
    """Factory: start_bridge(domain, *extra_args) -> Popen of stepbridge on vcan0. Every
    bridge still running at the end is stopped (SIGTERM, then SIGKILL); logs are printed."""
    procs: List[Tuple[subprocess.Popen, Path]] = []

    def _start(domain: int, *extra: str) -> subprocess.Popen:
        log = tmp_path / f"bridge-{len(procs) + 1}.log"
        argv = [str(stepbridge_bin), "--iface", CHANNEL, "--domain", str(domain), *extra]
        with open(log, "wb") as f:
            proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=f, stderr=subprocess.STDOUT,
                                    start_new_session=True)
        procs.append((proc, log))
        time.sleep(0.3)
        assert proc.poll() is None, f"stepbridge exited at once: {log.read_text()}"
        return proc

    yield _start

    for proc, log in procs:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        print(f"--- stepbridge log {log} ---\n{log.read_text()[-4000:]}")


def watch_once(stepwatch_bin: Path, domain: int, *extra: str, wait_ms: int = 8000) -> Tuple[int, List[dict], str]:
    """stepwatch --once --json: (exit status, one dict per line, stderr)."""
    r = subprocess.run([str(stepwatch_bin), "--once", "--json", "--domain", str(domain), "--wait-ms", str(wait_ms),
                        *extra], capture_output=True, text=True, timeout=wait_ms / 1000 + 10)
    return r.returncode, [json.loads(line) for line in r.stdout.splitlines() if line.strip()], r.stderr


def wait_for_snapshot(stepwatch_bin, domain, predicate, timeout=10.0, extra=()) -> List[dict]:
    """Repeats stepwatch --once until predicate(lines) holds; returns the last lines."""
    deadline = time.monotonic() + timeout
    lines: List[dict] = []
    while time.monotonic() < deadline:
        _, lines, _ = watch_once(stepwatch_bin, domain, *extra, wait_ms=3000)
        if predicate(lines):
            return lines
        time.sleep(0.3)
    pytest.fail(f"stepwatch never showed the expected state within {timeout} s; last: {lines}", pytrace=False)


def node_line(lines: List[dict], node: int) -> Optional[dict]:
    return next((l for l in lines if l["type"] == "node" and l["node"] == node), None)


def axis_line(lines: List[dict], node: int, axis: int) -> Optional[dict]:
    return next((l for l in lines if l["type"] == "axis" and l["node"] == node and l["axis"] == axis), None)


def operational_with_axis(lines: List[dict]) -> bool:
    n = node_line(lines, NODE)
    a = axis_line(lines, NODE, 1)
    return bool(n and n["state"] == "OPERATIONAL" and a and a["status"])


class LiveWatch:
    """stepwatch --json streaming every sample to a file until stopped."""

    def __init__(self, stepwatch_bin: Path, domain: int, path: Path, *extra: str):
        self.path = path
        with open(path, "wb") as f:
            self.proc = subprocess.Popen([str(stepwatch_bin), "--json", "--domain", str(domain), *extra],
                                         stdin=subprocess.DEVNULL, stdout=f, stderr=subprocess.STDOUT)

    def stop(self) -> List[dict]:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            self.proc.wait(5)
        return [json.loads(l) for l in self.path.read_text().splitlines() if l.startswith("{")]


def test_bridge_publishes_a_move_and_a_late_joiner_gets_the_final_status(
        master, start_node, start_bridge, stepwatch_bin, node_config, domain, tmp_path):
    start_bridge(domain)
    live = LiveWatch(stepwatch_bin, domain, tmp_path / "live.jsonl")
    link = boot(master, start_node, NODE, ["--config", node_config])
    ax = link.axes[1]
    clear_and_profile(ax)
    wait_for_snapshot(stepwatch_bin, domain, operational_with_axis)
    time.sleep(0.5)  # the live subscriber has matched by now
    ax.move("rel", 500)
    time.sleep(0.5)
    samples = live.stop()

    # Position samples track the move from start to target.
    positions = [s["motor_position"] for s in samples
                 if s["type"] == "axis_position" and s["node"] == NODE and s["axis"] == 1]
    assert positions and positions[-1] == 500, f"positions: {positions}"
    assert positions == sorted(positions), f"not monotonic: {positions}"
    assert any(0 < p < 500 for p in positions), f"no position between start and target: {positions}"
    # Every sample carries the CAN receive time and the publish time, in that order.
    for s in samples:
        if s["type"] == "axis_position":
            assert 0 < s["can_time_ns"] <= s["publish_time_ns"] <= s["recv_time_ns"], s
    # The status goes moving, then stopped, in order.
    moving = [s["moving"] for s in samples if s["type"] == "axis_status" and s["node"] == NODE and s["axis"] == 1]
    assert True in moving and moving[-1] is False, f"moving: {moving}"
    assert moving.index(True) < len(moving) - 1

    # A subscriber started after the move gets the final status at once (TRANSIENT_LOCAL).
    rc, lines, err = watch_once(stepwatch_bin, domain)
    assert rc == 0, err
    n = node_line(lines, NODE)
    assert n["state"] == "OPERATIONAL" and n["is_stepnode"] and n["device_name"] == "stepnode", n
    a = axis_line(lines, NODE, 1)
    assert a["status"]["moving"] is False and a["status"]["status_bits"] == ax.status, (a, hex(ax.status))
    assert a["position"] is None  # AxisPosition is VOLATILE: nothing for a late joiner


def test_cyclone_dds_subscriber_receives_status_and_position(
        master, start_node, start_bridge, domain, node_config, tmp_path):
    cyclone = _bin("CYCLONE_SUB_BIN", "build/bridge/interop/cyclone_sub")
    start_bridge(domain)
    link = boot(master, start_node, NODE, ["--config", node_config])
    ax = link.axes[1]
    clear_and_profile(ax)
    time.sleep(1.0)  # the bridge has published the status: Cyclone joins late for it
    out = tmp_path / "cyclone.out"
    with open(out, "wb") as f:
        proc = subprocess.Popen([str(cyclone), "--domain", str(domain), "--timeout-ms", "30000"],
                                stdout=f, stderr=subprocess.STDOUT)
    want = (f"AxisStatus node={NODE} axis=1 ", f"AxisPosition node={NODE} axis=1 motor_position=")
    deadline = time.monotonic() + 20
    while proc.poll() is None and time.monotonic() < deadline and not all(w in out.read_text() for w in want):
        ax.move("rel", 100)  # positions are VOLATILE: keep them coming until Cyclone has one
        time.sleep(0.2)
    proc.send_signal(signal.SIGTERM)
    rc = proc.wait(5)
    text = out.read_text()
    assert rc == 0, f"cyclone_sub exit status {rc}:\n{text}"
    for w in want:
        assert w in text, text


def test_killed_node_turns_lost_and_its_axes_are_disposed_then_it_is_rediscovered(
        master, start_node, start_bridge, stepwatch_bin, node_config, domain, tmp_path):
    start_bridge(domain)
    node = start_node(NODE, ["--config", node_config])
    master.nmt_start(NODE)
    wait_for_snapshot(stepwatch_bin, domain, operational_with_axis)
    live = LiveWatch(stepwatch_bin, domain, tmp_path / "live.jsonl")
    time.sleep(1.0)
    node.kill()
    lines = wait_for_snapshot(stepwatch_bin, domain,
                              lambda ls: (node_line(ls, NODE) or {}).get("state") == "LOST")
    assert not [l for l in lines if l["type"] == "axis"], f"axes not disposed: {lines}"
    time.sleep(0.5)
    disposed = [(s["topic"], s["axis"]) for s in live.stop() if s["type"] == "disposed" and s["node"] == NODE]
    assert ("AxisStatus", 1) in disposed and ("AxisPosition", 1) in disposed, disposed

    # The same node started again is discovered again.
    start_node(NODE, ["--config", node_config])
    master.nmt_start(NODE)
    wait_for_snapshot(stepwatch_bin, domain, operational_with_axis)


def test_bridge_restart_recovers_without_restarting_the_node(
        master, start_node, start_bridge, stepwatch_bin, node_config, domain):
    first = start_bridge(domain)
    start_node(NODE, ["--config", node_config])
    master.nmt_start(NODE)
    wait_for_snapshot(stepwatch_bin, domain, operational_with_axis)
    first.send_signal(signal.SIGTERM)
    assert first.wait(5) == 0
    rc, lines, _ = watch_once(stepwatch_bin, domain, wait_ms=1500)
    assert not [l for l in lines if l["type"] == "axis"], f"axes of a stopped bridge still alive: {lines}"
    start_bridge(domain)  # the node keeps running: found again by its heartbeat
    wait_for_snapshot(stepwatch_bin, domain, operational_with_axis)


def test_ros2_names(master, start_node, start_bridge, stepwatch_bin, node_config, domain):
    start_bridge(domain, "--ros2", "--ros2-prefix", "cell4")
    start_node(NODE, ["--config", node_config])
    master.nmt_start(NODE)
    wait_for_snapshot(stepwatch_bin, domain, operational_with_axis, extra=("--ros2", "--ros2-prefix", "cell4"))
    # Plain names see nothing of it; nor does another prefix.
    assert watch_once(stepwatch_bin, domain, wait_ms=1500)[0] == 1
    assert watch_once(stepwatch_bin, domain, "--ros2", wait_ms=1500)[0] == 1


@pytest.mark.parametrize("args, message", [
    ([], "no CAN interface"),
    (["--iface", CHANNEL, "--domain", "300"], "domain 300: must be 0..232"),
    (["--iface", "nosuch9"], "nosuch9"),
    (["--iface", CHANNEL, "--ros2", "--ros2-prefix", "a//b"], "empty segment"),
    (["--iface", CHANNEL, "--bogus"], "bogus"),
])
def test_stepbridge_bad_arguments_exit_2_with_one_line(stepbridge_bin, args, message):
    r = subprocess.run([str(stepbridge_bin), *args], capture_output=True, text=True, timeout=20)
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith("stepbridge: ") and r.stderr.count("\n") == 1, r.stderr
    assert message in r.stderr, r.stderr


def test_two_nodes_with_three_axes_each_are_all_published(
        master, start_node, start_bridge, stepwatch_bin, domain, tmp_path):
    config = tmp_path / "three-axes.toml"
    config.write_text('axes = 3\n[defaults]\n"1017" = 200\n')
    start_bridge(domain)
    for node in (NODE, NODE + 1):
        start_node(node, ["--config", config])
    master.nmt_start(0)  # all nodes

    def all_six(lines):
        nodes = [l for l in lines if l["type"] == "node" and l["state"] == "OPERATIONAL"]
        axes = {(l["node"], l["axis"]) for l in lines if l["type"] == "axis" and l["status"]}
        return len(nodes) == 2 and axes == {(n, a) for n in (NODE, NODE + 1) for a in (1, 2, 3)}

    lines = wait_for_snapshot(stepwatch_bin, domain, all_six, timeout=15.0)
    for node in (NODE, NODE + 1):
        assert node_line(lines, node)["axes"] == 3, node_line(lines, node)
