"""SDO server channels 0x1200..0x1203 on the bus (CiA 301 7.2.4.1, 7.5.2.33): a configured
channel answers on its own server->client COB-ID, a disabled one is silent, a valid
COB-ID cannot change; stepctl and stepbridge on channels of their own; and two stepctl
processes sharing the default channel while the bridge reads on its own for about a
minute, with no wrong value anywhere (contention is reported, never turned into data).

Expected frames are written from CiA 301 7.2.4.3 byte layouts, not taken from our client."""

import os
import random
import threading
import time

import pytest

from bridge_helpers import node_line, stepbridge_bin, start_bridge, domain, stepwatch_bin, wait_for_snapshot  # noqa: F401
from canopen_master import SdoAbort
from conftest import wait_for_frame
from test_stepctl import stepctl  # noqa: F401 (stepctl_bin is in conftest.py)

NODE = 5
BRIDGE_RX, BRIDGE_TX = 0x690, 0x6D0   # 0x1201
SECOND_RX, SECOND_TX = 0x691, 0x6D1   # 0x1202
ABORT_INVALID_VALUE = 0x06090030
CONTENTION = f"stepctl: another master is using node {NODE}'s SDO channel"
SECONDS = float(os.environ.get("VCAN_CONTENTION_SECONDS", "60"))


def node_config(tmp_path):
    path = tmp_path / "node.toml"
    path.write_text(f'[defaults]\n"1201:1" = {BRIDGE_RX}\n"1201:2" = {BRIDGE_TX}\n"1201:3" = 0x7E\n')
    return path


def frames_on(master, cob_id, duration):
    return master.collect(duration, lambda m: m.arbitration_id == cob_id)


def test_configured_channel_answers_on_its_own_cob_id(master, start_node):
    start_node(NODE)
    assert master.read_u32(NODE, 0x1201, 1) == 0x80000000  # disabled by default
    master.write_u32(NODE, 0x1201, 1, BRIDGE_RX)
    master.write_u32(NODE, 0x1201, 2, BRIDGE_TX)
    master.flush()
    # Expedited upload request of 0x1017:00 (ccs 2 = 0x40) on 0x1201:1 ...
    master.send(BRIDGE_RX, bytes([0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0]))
    r = wait_for_frame(master, lambda m: m.arbitration_id == BRIDGE_TX, timeout=2.0)
    # ... answered on 0x1201:2: scs 2, n = 2, e, s (0x4B), 1000 ms = 0x03E8.
    assert r is not None and bytes(r.data) == bytes([0x4B, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0])
    assert not frames_on(master, 0x580 + NODE, 0.3), "the default channel stayed silent"


def test_disabled_channel_is_silent_and_a_valid_cob_id_does_not_change(master, start_node):
    start_node(NODE)
    master.send(SECOND_RX, bytes([0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0]))  # 0x1202 is disabled
    assert not frames_on(master, SECOND_TX, 0.5)
    master.write_u32(NODE, 0x1202, 1, SECOND_RX)
    master.write_u32(NODE, 0x1202, 2, SECOND_TX)
    with pytest.raises(SdoAbort) as e:
        master.write_u32(NODE, 0x1202, 1, SECOND_RX + 1)  # valid: set bit 31 first
    assert e.value.code == ABORT_INVALID_VALUE
    master.write_u32(NODE, 0x1202, 1, 0x80000000 | SECOND_RX)
    master.write_u32(NODE, 0x1202, 1, SECOND_RX + 1)
    assert master.read_u32(NODE, 0x1202, 1) == SECOND_RX + 1


def test_stepctl_on_its_own_channel(stepctl, master, start_node):
    start_node(NODE)
    master.write_u32(NODE, 0x1202, 1, SECOND_RX)
    master.write_u32(NODE, 0x1202, 2, SECOND_TX)
    master.flush()
    r = stepctl("--sdo-cob-ids", f"{SECOND_RX:#x},{SECOND_TX:#x}", "write", NODE, "0x2F00:4", "0x1234")
    assert r.returncode == 0, r.stderr
    seen = master.collect(0.3)
    assert any(m.arbitration_id == SECOND_TX for m in seen)
    assert not any(m.arbitration_id in (0x600 + NODE, 0x580 + NODE) for m in seen)
    assert master.read_u32(NODE, 0x2F00, 4) == 0x1234
    r = stepctl("--sdo-cob-ids", "0x691", "read", NODE, "0x1017")
    assert r.returncode == 2 and "CLIENT_TO_SERVER,SERVER_TO_CLIENT" in r.stderr


class Worker(threading.Thread):
    """One stepctl process after another on the default channel: writes its own register,
    reads it back. A read must show the value it wrote (or, after a write that reported
    contention, the value before or after it); contention is the one allowed error."""

    def __init__(self, stepctl, sub, stop_at):
        super().__init__(daemon=True)
        self.stepctl, self.sub, self.stop_at = stepctl, sub, stop_at
        self.possible = {0}
        self.problems, self.contended, self.reads = [], 0, 0

    def run(self):
        try:
            self.work()
        except Exception as e:  # a dead worker must fail the test, not pass it by silence
            self.problems.append(f"sub {self.sub}: {e!r}")

    def work(self):
        rng = random.Random(self.sub)
        while time.monotonic() < self.stop_at and len(self.problems) < 5:
            value = rng.randrange(1, 1 << 31)
            r = self.stepctl("write", NODE, f"0x2F00:{self.sub}", str(value))
            if r.returncode == 0:
                self.possible = {value}
            elif self.check_contention(r):
                self.possible = self.possible | {value}
            r = self.stepctl("read", NODE, f"0x2F00:{self.sub}")
            if r.returncode == 0:
                self.reads += 1
                got = int(r.stdout.split("=")[1].split()[0], 0)
                if got not in self.possible:
                    self.problems.append(f"sub {self.sub}: read {got:#x}, expected one of {sorted(self.possible)}")
                self.possible = {got}
            else:
                self.check_contention(r)

    def check_contention(self, r):
        if r.returncode == 1 and r.stderr.strip() == CONTENTION:
            self.contended += 1
            return True
        self.problems.append(f"sub {self.sub}: exit {r.returncode}: {r.stderr.strip()!r}")
        return False


def test_two_stepctl_and_the_bridge_work_one_node_at_once(stepctl, master, start_node, start_bridge,
                                                         stepwatch_bin, domain, tmp_path):
    start_node(NODE, ["--config", node_config(tmp_path)])
    master.nmt_start(NODE)
    bridge = start_bridge("--sdo-channel", f"{NODE}:{BRIDGE_RX:#x},{BRIDGE_TX:#x}")
    stop_at = time.monotonic() + SECONDS
    workers = [Worker(stepctl, sub, stop_at) for sub in (1, 2)]
    for w in workers:
        w.start()
    # Meanwhile a supervisor looks every few seconds: the bridge, reading on its own
    # channel, has the node discovered and no SDO failure.
    while time.monotonic() < stop_at:
        lines = wait_for_snapshot(stepwatch_bin, domain, lambda ls: (n := node_line(ls, NODE)) and n.get("discovered"),
                                  timeout=20)
        time.sleep(3)
    for w in workers:
        w.join(timeout=60)
    assert bridge.alive
    problems = [p for w in workers for p in w.problems]
    assert not problems, "\n".join(problems)
    assert all(w.reads > 0 for w in workers), [(w.reads, w.contended) for w in workers]
    print(f"reads {[w.reads for w in workers]}, contention reported {[w.contended for w in workers]}")
    health = node_line(lines, NODE)
    assert health["sdo_failures"] == 0, health  # nothing disturbed the bridge's channel
