"""vcan tests of the DDS bridge (issue 5): stepnode on vcan0, stepbridge, and DDS
subscribers in other processes: stepwatch (Fast DDS) and cyclone_sub (Cyclone DDS, built
from the IDL alone). Each test uses its own DDS domain (bridge_helpers).

Binaries: STEPBRIDGE_BIN (build/bridge/stepbridge), STEPWATCH_BIN (build/tools/stepwatch),
CYCLONE_SUB_BIN (build/bridge/interop/cyclone_sub); a missing binary fails the test."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path
from typing import List

import pytest

from axis_helpers import NODE, boot, clear_and_profile
from bridge_helpers import (
    LiveWatch, axis_line, cyclone_sub_bin, domain, node_line, start_bridge, stepbridge_bin, stepwatch_bin, wait_for_snapshot,
    watch_once,
)
from conftest import CHANNEL

_ = (domain, start_bridge, stepbridge_bin, stepwatch_bin)  # fixtures


@pytest.fixture
def node_config(tmp_path) -> Path:
    """Two axes, heartbeat every 200 ms (so a lost node is seen within about a second)."""
    p = tmp_path / "node.toml"
    p.write_text('axes = 2\n[defaults]\n"1017" = 200\n')
    return p


def operational_with_axis(lines: List[dict]) -> bool:
    n = node_line(lines, NODE)
    a = axis_line(lines, NODE, 1)
    return bool(n and n["state"] == "OPERATIONAL" and a and a["status"])


def test_bridge_publishes_a_move_and_a_late_joiner_gets_the_final_status(
        master, start_node, start_bridge, stepwatch_bin, node_config, domain, tmp_path):
    start_bridge()
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
    cyclone = cyclone_sub_bin()
    start_bridge()
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
    start_bridge()
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
    first = start_bridge()
    start_node(NODE, ["--config", node_config])
    master.nmt_start(NODE)
    wait_for_snapshot(stepwatch_bin, domain, operational_with_axis)
    assert first.terminate() == 0
    rc, lines, _ = watch_once(stepwatch_bin, domain, wait_ms=1500)
    assert not [l for l in lines if l["type"] == "axis"], f"axes of a stopped bridge still alive: {lines}"
    start_bridge()  # the node keeps running: found again by its heartbeat
    wait_for_snapshot(stepwatch_bin, domain, operational_with_axis)


def test_ros2_names(master, start_node, start_bridge, stepwatch_bin, node_config, domain):
    start_bridge("--ros2", "--ros2-prefix", "cell4")
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
    start_bridge()
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
