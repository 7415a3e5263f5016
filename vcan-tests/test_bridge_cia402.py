"""The DDS bridge and a CiA 402 drive (issue 10): a real `profiles = ["cia402"]` stepnode
(no Horner objects 0x2n00 at all), stepbridge, and stepwatch as the subscriber (`--json`:
one line per DriveStatus sample as it arrives; `--once --json`: what a late joiner gets).
The master is cia402_master.py (written from CiA 402-2): it enables the drive with the
controlword on RPDO1 (0x200 + id = {6040h, 6060h}: 0x06, 0x07, 0x0F) and records the
statuswords the node puts on TPDO1; the bridge must publish the same words, decoded into
the standard's state names.

Binaries: $STEPNODE_BIN, $STEPBRIDGE_BIN, $STEPWATCH_BIN (see bridge_helpers.py)."""

from __future__ import annotations

import json
import subprocess
import threading
import time
from pathlib import Path
from typing import Callable, List, Optional

import pytest

from axis_helpers import HeartbeatSender
from bridge_helpers import DDS_TIMEOUT, axis_line, domain, node_line, start_bridge, stepbridge_bin, stepwatch_bin
from bridge_helpers import wait_for_snapshot
from canopen_master import STATE_OPERATIONAL
from cia402_master import (
    CW_DISABLE_VOLTAGE, CW_FAULT_RESET, FAULT, MODE_PP, MODE_PV, OPERATION_ENABLED, SWITCH_ON_DISABLED, Node402,
    state_of,
)

_ = (domain, start_bridge, stepbridge_bin, stepwatch_bin)  # fixtures

NODE = 43
MASTER_ID = 0x7F
EMCY_HEARTBEAT = 0x8130


class DriveWatch:
    """stepwatch --json on the test's domain; its DriveStatus lines collected by a thread."""

    def __init__(self, stepwatch: Path, dom: int, log_path: Path):
        self.log_path = log_path
        self.proc = subprocess.Popen([str(stepwatch), "--json", "--domain", str(dom)], stdin=subprocess.DEVNULL,
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
        self.lines: List[str] = []
        self.samples: List[dict] = []  # type drive_status and disposed
        self.healths: List[dict] = []
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self):
        for raw in self.proc.stdout:
            line = raw.decode(errors="replace").rstrip("\n")
            with self._lock:
                self.lines.append(line)
                if line.startswith("{"):
                    j = json.loads(line)
                    if j.get("type") == "node_health":
                        self.healths.append(j)
                    if j.get("type") == "drive_status" or (j.get("type") == "disposed"
                                                           and j.get("topic") == "DriveStatus"):
                        self.samples.append(j)

    def mark(self) -> int:
        with self._lock:
            return len(self.samples)

    def since(self, mark: int = 0, axis: Optional[int] = None) -> List[dict]:
        with self._lock:
            out = self.samples[mark:]
        return [s for s in out if s["type"] == "drive_status" and s["node"] == NODE
                and (axis is None or s["axis"] == axis)]

    def discovered(self) -> bool:
        with self._lock:
            return any(h["node"] == NODE and h["discovered"] for h in self.healths)

    def wait(self, pred: Callable[[], bool], what: str, timeout: float = DDS_TIMEOUT) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if pred():
                return
            time.sleep(0.02)
        if not pred():
            with self._lock:
                tail = self.lines[-20:]
            pytest.fail(f"stepwatch: {what} not seen within {timeout} s; last lines:\n" + "\n".join(tail),
                        pytrace=False)

    def close(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._thread.join(2)
        with self._lock:
            self.log_path.write_text("\n".join(self.lines) + "\n")


@pytest.fixture
def watch(stepwatch_bin, domain, tmp_path):
    w = DriveWatch(stepwatch_bin, domain, tmp_path / "stepwatch.log")
    yield w
    w.close()
    print("--- stepwatch (last lines) ---\n" + "\n".join(w.lines[-30:]))


def boot(master, start_node, tmp_path, axes: int = 1) -> Node402:
    path = tmp_path / "cia402.toml"
    path.write_text(f'axes = {axes}\nprofiles = ["cia402"]\n')
    start_node(NODE, ["--config", path])
    node = Node402(master, NODE, range(1, axes + 1))
    master.nmt_start(NODE)
    if master.wait_heartbeat(NODE, timeout=3.0, state=STATE_OPERATIONAL) != STATE_OPERATIONAL:
        pytest.fail(f"node {NODE} did not confirm NMT operational")
    node.pump(0.3)  # TPDOs sent on entering operational
    return node


def wait_discovered(watch: DriveWatch, node: Node402) -> None:
    """The bridge has read the node over SDO: the master's own SDO transfers may start. The
    bridge's requests and the node's answers seen meanwhile are taken off the master's
    socket, so an old answer is not taken for the master's."""
    watch.wait(watch.discovered, f"NodeHealth of node {NODE} discovered")
    node.pump(0.2)


def changes(values: List[int]) -> List[int]:
    out: List[int] = []
    for v in values:
        if not out or out[-1] != v:
            out.append(v)
    return out


def test_drive_status_follows_the_enable_sequence_and_a_move(master, start_node, start_bridge, watch, tmp_path):
    start_bridge()  # before the node: discovered from its boot-up
    node = boot(master, start_node, tmp_path)
    drive = node[1]
    watch.wait(lambda: any(s["state"] == SWITCH_ON_DISABLED.name for s in watch.since(axis=1)),
               "DriveStatus axis 1 in Switch on disabled")
    wait_discovered(watch, node)
    first = watch.since(axis=1)[0]
    assert first["remote"] and first["switch_on_disabled"] and not first["operation_enabled"], first

    # Controlword 0x06, 0x07, 0x0F on RPDO1: transitions 2, 3, 4, each state seen on TPDO1.
    drive.profile(velocity=4000, acceleration=40000, deceleration=40000)
    before = drive.sw
    mark, bus_mark = watch.mark(), drive.mark()
    drive.enable(MODE_PP)
    on_bus = changes([f.sw for f in drive.status_log[bus_mark:]])
    watch.wait(lambda: [s["statusword"] for s in watch.since(mark, 1)][-1:] == on_bus[-1:],
               f"the statusword 0x{on_bus[-1]:04X} of Operation enabled")
    # (samples of the state before may still have been on their way at the mark)
    published = [s for s in watch.since(mark, 1)]
    while published and published[0]["statusword"] == before:
        published.pop(0)
    assert changes([s["statusword"] for s in published]) == on_bus, (published, on_bus)
    assert changes([s["state"] for s in published]) == ["Ready to switch on", "Switched on", "Operation enabled"]
    for s in published:
        assert s["state"] == state_of(s["statusword"]).name, s
    last = published[-1]
    assert last["operation_enabled"] and last["switched_on"] and last["ready_to_switch_on"] and last["quick_stop"]
    assert last["voltage_enabled"] and last["remote"] and not last["fault"], last
    assert last["mode_display"] == MODE_PP and last["error_code"] == 0
    assert last["can_time_ns"] > 0 and last["publish_time_ns"] >= last["can_time_ns"], last

    # A relative move of 1000 steps: 6064h/606Ch on TPDO2 become position_actual/velocity_actual.
    mark, mmark = watch.mark(), drive.motion_mark()
    ack = drive.set_point(1000, relative=True)
    drive.wait_target_reached(3.0, mark=drive.status_log.index(ack))
    drive.wait_motion(lambda m: m.position == 1000 and m.velocity == 0, 2.0, mmark, "at 1000")
    watch.wait(lambda: any(s["position_actual"] == 1000 and s["velocity_actual"] == 0 and s["target_reached"]
                           for s in watch.since(mark, 1)), "DriveStatus at 1000, target reached")
    moving = [s for s in watch.since(mark, 1) if 0 < s["position_actual"] < 1000]
    assert moving and all(s["velocity_actual"] > 0 for s in moving), watch.since(mark, 1)
    assert any(s["bit12"] for s in watch.since(mark, 1)), "pp set-point acknowledge (bit 12) published"


def test_a_late_joiner_sees_both_drives_and_axis_2_alone(master, start_node, start_bridge, stepwatch_bin, domain,
                                                         watch, tmp_path):
    node = boot(master, start_node, tmp_path, axes=2)
    start_bridge()  # after the node: discovered from its heartbeat, idle drives from its snapshot
    lines = wait_for_snapshot(stepwatch_bin, domain, lambda ls: all(
        (a := axis_line(ls, NODE, n)) is not None and "drive" in a for n in (1, 2)), timeout=DDS_TIMEOUT)
    health = node_line(lines, NODE)
    assert health and health["is_stepnode"] and health["axes"] == 2 and health["discovered"], health
    for n in (1, 2):
        d = axis_line(lines, NODE, n)
        assert d["status"] is None and d["position"] is None, d  # no Horner topics for this node
        assert d["drive"]["state"] == SWITCH_ON_DISABLED.name, d

    # Axis 2 on RPDO3 (0x400 + id) and TPDO3/4 (0x380/0x480 + id): its instance only.
    wait_discovered(watch, node)
    mark = watch.mark()
    node[2].enable(MODE_PV)
    watch.wait(lambda: any(s["state"] == OPERATION_ENABLED.name for s in watch.since(mark, 2)),
               "DriveStatus axis 2 in Operation enabled")
    assert all(s["state"] == SWITCH_ON_DISABLED.name for s in watch.since(mark, 1)), watch.since(mark, 1)
    assert watch.since(mark, 2)[-1]["mode_display"] == MODE_PV


def test_a_fault_brings_its_error_code_and_the_reset_clears_it(master, start_node, start_bridge, watch, tmp_path):
    start_bridge()
    node = boot(master, start_node, tmp_path)
    drive = node[1]
    watch.wait(lambda: bool(watch.since(axis=1)), "the first DriveStatus")
    wait_discovered(watch, node)
    hb = HeartbeatSender(MASTER_ID, 0.05).start()
    try:
        # 1016h: consume the master's heartbeat (200 ms); 6007h = 1: a lost master is a fault.
        master.write_u32(NODE, 0x1016, 1, (MASTER_ID << 16) | 200)
        master.write_u8(NODE, 0x1029, 1, 1)
        # CiA 301: a heartbeat consumer starts watching at the first heartbeat it receives
        # after it was configured; stopped before one arrived, nothing is lost. Let beats in.
        time.sleep(0.3)
        drive.enable(MODE_PP)
        mark, bus_mark = watch.mark(), drive.mark()
        hb.stop()
        hb.close()
        drive.wait_state(FAULT, 2.0, bus_mark)
        # 603Fh is in no default TPDO: the bridge reads it when the fault bit comes.
        watch.wait(lambda: any(s["state"] == FAULT.name and s["error_code"] == EMCY_HEARTBEAT
                               for s in watch.since(mark, 1)), "DriveStatus Fault with error code 0x8130")
        faulted = [s for s in watch.since(mark, 1) if s["state"] == FAULT.name][-1]
        assert faulted["fault"] and not faulted["operation_enabled"], faulted

        hb = HeartbeatSender(MASTER_ID, 0.05).start()
        time.sleep(0.4)
        mark = watch.mark()
        drive.controlword(CW_DISABLE_VOLTAGE)
        drive.command(CW_FAULT_RESET, SWITCH_ON_DISABLED)  # transition 15
        drive.controlword(CW_DISABLE_VOLTAGE)
        watch.wait(lambda: any(s["state"] == SWITCH_ON_DISABLED.name and s["error_code"] == 0
                               for s in watch.since(mark, 1)), "DriveStatus Switch on disabled, error code 0")
    finally:
        hb.close()
