"""Many nodes in one process (issue 13): one stepnode with `--node-id 1-127` on vcan0
behaves on the bus as 127 separate nodes would. Frames from CiA 301: boot-up and heartbeat
on 0x700+id (one byte: 0x00 boot-up, 0x04 stopped, 0x05 operational, 0x7F pre-operational),
NMT on 0x000 (command specifier, node-ID; 0 = all nodes), expedited SDO on 0x600+id and
0x580+id.

Heartbeat tolerance: a master watching a node with 0x1016 is given a consumer time above
the producer time (CiA 301: "should be higher"); masters derive it with a factor (ros2_canopen
and lely's dcfgen: `heartbeat_multiplier`). This test takes a factor of 2, so with 0x1017 =
100 ms every gap between two heartbeats of a node must stay below 200 ms (measured on the kernel receive
timestamps candump records, so the test's own scheduling does not count). The gaps are
printed (`-s`).

User-Mode Linux has one CPU for the node, the bridge, candump and the test. The bridge is
supervisory and the node is the device that must keep its timing, so the bridge runs as a
deployment would run it beside a node: at a lower priority (nice 10) and logging at info
(its debug log of 127 discoveries costs more CPU than the discoveries). At the same
priority the node's heartbeat gaps reached 170-299 ms in two of four runs, around the NMT
start, when 127 nodes send their TPDOs at once and the bridge publishes them; without the
bridge the largest gap was 132-137 ms."""

from __future__ import annotations

import re
import struct
import subprocess
import time
from pathlib import Path
from typing import Dict, List, Tuple

import pytest

from bridge_helpers import DDS_TIMEOUT, domain, node_line, start_bridge, stepbridge_bin, stepwatch_bin, watch_once
from canopen_master import STATE_OPERATIONAL, STATE_PREOPERATIONAL, STATE_STOPPED
from conftest import CHANNEL

_ = (domain, start_bridge, stepbridge_bin, stepwatch_bin)  # fixtures

PERIOD_S = 0.100
TOLERANCE_S = 2.0 * PERIOD_S  # the consumer time a master gives 0x1016
# NMT start of all 127 nodes: each enters OPERATIONAL and sends its event-driven TPDOs and a
# heartbeat at once, 635 frames in all (`multi_node_bench --operational` counts them), each
# at most about 135 bits with stuffing. On a 500 kbit/s bus that burst alone takes the bus
# for 635 * 135 / 500e3 = 0.171 s, and a heartbeat (COB-ID 0x700 + id, the lowest priority)
# due in it waits behind the TPDOs. A gap that spans the NMT start is allowed the consumer
# time plus the burst: a master starting 127 nodes at once must allow that much.
NMT_BURST_S = 635 * 135 / 500e3
ALL = range(1, 128)
# 127 nodes inside User-Mode Linux start slower than one; allow for it.
BOOT_TIMEOUT_S = 60.0
DISCOVERY_TIMEOUT_S = 180.0


@pytest.fixture
def node_config(tmp_path) -> Path:
    p = tmp_path / "nodes.toml"
    p.write_text('[defaults]\n"1017" = 100\n')  # producer heartbeat time, ms
    return p


class Candump:
    """candump (can-utils, C) recording the heartbeats (0x700..0x77F) and NMT (0x000) to a
    file: Python reading 1,270 frames/s itself would take the CPU of the single-CPU UML
    from the node under test. Kernel receive timestamps (-L: "(sec.usec) vcan0 ID#DATA")."""

    def __init__(self, path: Path):
        self.path = path
        with open(path, "wb") as out:
            self.proc = subprocess.Popen(["candump", "-L", f"{CHANNEL},700:780,000:7FF"], stdout=out,
                                         stderr=subprocess.STDOUT)

    def frames(self) -> List[Tuple[float, int, bytes]]:
        out = []
        for line in self.path.read_text(errors="replace").splitlines():
            m = re.match(r"\((\d+\.\d+)\) \S+ ([0-9A-F]{3})#([0-9A-F]*)$", line.strip())
            if m:
                out.append((float(m[1]), int(m[2], 16), bytes.fromhex(m[3])))
        return out

    def stop(self):
        self.proc.terminate()
        self.proc.wait(5)


@pytest.fixture
def candump(tmp_path):
    c = Candump(tmp_path / "candump.log")
    time.sleep(0.3)  # its socket is bound before the node starts
    yield c
    if c.proc.poll() is None:
        c.stop()


def bootups(frames) -> Dict[int, float]:
    seen: Dict[int, float] = {}
    for t, cob, data in frames:
        if 0x701 <= cob <= 0x77F and data == b"\x00":
            assert cob - 0x700 not in seen, f"node {cob - 0x700} booted twice"
            seen[cob - 0x700] = t
    return seen


def heartbeats(frames, after: float) -> Dict[int, List[Tuple[float, int]]]:
    """(timestamp, state) of every heartbeat per node, boot-ups excluded, after `after`."""
    out: Dict[int, List[Tuple[float, int]]] = {}
    for t, cob, data in frames:
        if 0x701 <= cob <= 0x77F and len(data) == 1 and data != b"\x00" and t >= after:
            out.setdefault(cob - 0x700, []).append((t, data[0]))
    return out


def start_set(start_node, ids: str, config: Path):
    # start_node puts the text after --node-id; it waits for one id's boot-up only.
    return start_node(ids, ["--config", config, "--log-level", "info"], wait_bootup=False)


def test_127_nodes_in_one_process_keep_their_heartbeats_and_the_bridge_discovers_them(
        start_node, start_bridge, stepwatch_bin, domain, node_config, candump, master):
    bridge = start_bridge("--log-level", "info", niceness=10)  # see the module text
    started = time.monotonic()
    proc = start_set(start_node, "1-127", node_config)
    deadline = time.monotonic() + BOOT_TIMEOUT_S
    while len(bootups(candump.frames())) < 127 and time.monotonic() < deadline and proc.alive:
        time.sleep(0.2)
    booted = bootups(candump.frames())
    assert sorted(booted) == list(ALL), f"no boot-up from {sorted(set(ALL) - set(booted))}\n{proc.log()[-3000:]}"
    print(f"\n127 boot-ups within {max(booted.values()) - min(booted.values()):.3f} s, "
          f"{time.monotonic() - started:.2f} s after start")

    buffer = next((l for l in proc.log().splitlines() if "receive buffer" in l), None)
    print(f"stepnode: {buffer}")
    assert buffer, "the granted receive buffer is logged"
    time.sleep(5.0)
    master.send(0x000, bytes([0x01, 0]))  # NMT start remote node, all nodes
    time.sleep(1.5)
    candump.stop()
    frames = candump.frames()
    nmt_at = next(t for t, cob, data in frames if cob == 0 and data == b"\x01\x00")
    beats = heartbeats(frames, after=max(booted.values()))
    assert sorted(beats) == list(ALL), f"no heartbeat from {sorted(set(ALL) - set(beats))}"
    gaps = sorted(b[0] - a[0] for n in ALL for a, b in zip(beats[n], beats[n][1:]))
    steady = sorted(b[0] - a[0] for n in ALL for a, b in zip(beats[n], beats[n][1:])
                    if not (a[0] <= nmt_at + NMT_BURST_S and b[0] >= nmt_at))
    print(f"heartbeat gaps away from the NMT start: max {steady[-1] * 1e3:.1f} ms")
    print(f"heartbeat gaps of 127 nodes: {len(gaps)}, median {gaps[len(gaps) // 2] * 1e3:.1f} ms, "
          f"p99 {gaps[len(gaps) * 99 // 100] * 1e3:.1f} ms, max {gaps[-1] * 1e3:.1f} ms "
          f"(tolerance {TOLERANCE_S * 1e3:.0f} ms)")
    late = {}  # asserted last, so the figures below are printed whatever happens
    for n in ALL:
        for a, b in zip(beats[n], beats[n][1:]):
            spans_nmt_start = a[0] <= nmt_at + NMT_BURST_S and b[0] >= nmt_at
            allowed = TOLERANCE_S + (NMT_BURST_S if spans_nmt_start else 0)
            if b[0] - a[0] >= allowed:
                late[n] = max(late.get(n, 0), round((b[0] - a[0]) * 1e3, 1))
        before = [s for t, s in beats[n] if t < nmt_at]
        after = [s for t, s in beats[n] if t > nmt_at + 2 * PERIOD_S]
        assert len(before) >= 5.0 / TOLERANCE_S and set(before) == {STATE_PREOPERATIONAL}, f"node {n}: {before}"
        assert after and set(after) == {STATE_OPERATIONAL}, f"node {n} after NMT start: {after}"

    # The bridge discovers every node (stepwatch: one "node" line per node it knows).
    deadline = time.monotonic() + DISCOVERY_TIMEOUT_S
    missing = list(ALL)
    while missing and time.monotonic() < deadline and bridge.alive:
        _, lines, _ = watch_once(stepwatch_bin, domain, wait_ms=3000)
        missing = [n for n in ALL if node_line(lines, n) is None]
        if missing:
            time.sleep(1.0)
    print(f"bridge: {127 - len(missing)} nodes discovered {time.monotonic() - started:.1f} s after start")
    assert not missing, f"the bridge did not discover nodes {missing}\n{bridge.log()[-3000:]}"
    assert proc.alive
    assert not late, (f"heartbeat gaps above {TOLERANCE_S * 1e3:.0f} ms (around the NMT start "
                      f"{(TOLERANCE_S + NMT_BURST_S) * 1e3:.0f} ms) (node: ms): {late}")


def sdo(master, node: int, data: bytes) -> bytes:
    answer = master.sdo_request(node, data)
    assert answer is not None, f"node {node} did not answer {data.hex()}"
    return answer


def test_nodes_of_one_process_are_independent(start_node, node_config, master):
    proc = start_set(start_node, "3-5", node_config)
    assert master.wait_for(lambda m: m.arbitration_id == 0x705 and bytes(m.data) == b"\x00", 10.0), proc.log()
    # Expedited download of 0x1017 (UNSIGNED16) = 400 ms to node 3 (ccs 1, n = 2: 0x2B).
    assert sdo(master, 3, struct.pack("<BHBH2x", 0x2B, 0x1017, 0, 400)) == struct.pack("<BHB4x", 0x60, 0x1017, 0)
    # Upload of 0x1017 from node 4: its own value, 100 (scs 2, e = s = 1, n = 2: 0x4B).
    assert sdo(master, 4, struct.pack("<BHB4x", 0x40, 0x1017, 0)) == struct.pack("<BHBH2x", 0x4B, 0x1017, 0, 100)
    assert sdo(master, 3, struct.pack("<BHB4x", 0x40, 0x1017, 0)) == struct.pack("<BHBH2x", 0x4B, 0x1017, 0, 400)

    master.send(0x000, bytes([0x02, 5]))  # NMT stop remote node 5
    time.sleep(0.5)
    master.flush()
    beats: Dict[int, List[int]] = {}
    for m in master.collect(1.0, lambda m: 0x703 <= m.arbitration_id <= 0x705 and len(m.data) == 1):
        beats.setdefault(m.arbitration_id - 0x700, []).append(m.data[0])
    assert beats.get(5) and set(beats[5]) == {STATE_STOPPED}, beats
    assert beats.get(4) and set(beats[4]) == {STATE_PREOPERATIONAL}, beats
    assert beats.get(3) and set(beats[3]) == {STATE_PREOPERATIONAL}, beats
    assert 2 <= len(beats[3]) <= 3 and len(beats[4]) >= 9, beats  # 400 ms and 100 ms in 1 s
    # A stopped node answers no SDO; the others still do.
    assert master.sdo_request(5, struct.pack("<BHB4x", 0x40, 0x1017, 0), timeout=0.5) is None
    assert sdo(master, 4, struct.pack("<BHB4x", 0x40, 0x1000, 0))[0] == 0x43
    assert proc.alive


@pytest.mark.parametrize("ids", ["0-3", "1-128", "1-5,5", "1,none", "9-3"])
def test_a_bad_node_id_list_is_one_line_and_status_2(stepnode_bin, tmp_path, ids):
    r = subprocess.run([str(stepnode_bin), "--iface", CHANNEL, "--node-id", ids, "--state-dir", str(tmp_path)],
                       capture_output=True, text=True, timeout=20)
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"stepnode: --node-id {ids}: "), r.stderr
