"""`stepctl lss` (an LSS master, CiA 305 V3.0) against stepnode on vcan. Every request
stepctl puts on 0x7E5 is checked byte for byte against the frame CiA 305 gives for the
service (8 bytes: the command specifier, 32-bit values little-endian in bytes 1..4,
unused bytes 0), recorded by a socket of the test's own; the slave's state is checked
through the independent master (lss_master.py, canopen_master.py)."""

import struct
import subprocess
import time

import pytest

from conftest import CHANNEL, REPO_ROOT, collect_frames, open_bus
from lss_master import LssMaster
from test_lss import PRODUCT, REVISION, VENDOR, start_unconfigured, wait_unconfigured

NODE = 0x2D


@pytest.fixture
def recorder():
    bus = open_bus()
    yield bus
    bus.shutdown()


@pytest.fixture
def lss_ctl(stepctl_bin, recorder, tmp_path):
    """Runs `stepctl lss ARGS`; returns (completed process, the 0x7E5 frames it sent, the
    0x7E4 answers), all as bytes."""
    def run(*args, timeout=120):
        collect_frames(recorder, 0.05)  # what came before
        # Recorded while stepctl runs: a fast scan's few hundred frames would overflow a
        # socket queue read only afterwards.
        proc = subprocess.Popen([str(stepctl_bin), "--iface", CHANNEL, "lss", *map(str, args)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=str(tmp_path),
                                stdin=subprocess.DEVNULL)
        frames = []
        deadline = time.monotonic() + timeout
        while proc.poll() is None and time.monotonic() < deadline:
            frames += collect_frames(recorder, 0.05, lambda m: m.arbitration_id in (0x7E4, 0x7E5))
        out, err = proc.communicate(timeout=5)
        p = subprocess.CompletedProcess(proc.args, proc.returncode, out, err)
        frames += collect_frames(recorder, 0.2, lambda m: m.arbitration_id in (0x7E4, 0x7E5))
        requests = [bytes(m.data) for m in frames if m.arbitration_id == 0x7E5]
        answers = [bytes(m.data) for m in frames if m.arbitration_id == 0x7E4]
        assert all(m.dlc == 8 for m in frames)
        return p, requests, answers
    return run


@pytest.fixture
def lss():
    bus = open_bus()
    yield LssMaster(bus)
    bus.shutdown()


def frame(cs, *rest):
    return bytes([cs, *rest]) + bytes(7 - len(rest))


def u32_frame(cs, value):
    return bytes([cs]) + struct.pack("<I", value) + bytes(3)


def test_configure_store_and_inquire_one_node(lss_ctl, lss, master, start_node, tmp_path):
    serial = 0x5EED0101
    state = tmp_path / "state"
    node = start_unconfigured(start_node, serial, state)
    assert wait_unconfigured(lss, 1) == 1, node.log()

    p, sent, answers = lss_ctl("switch", "selective", hex(VENDOR), hex(PRODUCT), hex(REVISION), hex(serial))
    assert p.returncode == 0, p.stderr
    assert sent == [u32_frame(0x40, VENDOR), u32_frame(0x41, PRODUCT), u32_frame(0x42, REVISION),
                    u32_frame(0x43, serial)]
    assert answers == [frame(0x44)]

    p, sent, _ = lss_ctl("inquire", "identity")
    assert p.returncode == 0, p.stderr
    assert sent == [frame(0x5A), frame(0x5B), frame(0x5C), frame(0x5D)]
    assert p.stdout.splitlines() == [f"vendor-ID 0x{VENDOR:08X}", f"product code 0x{PRODUCT:08X}",
                                     f"revision number 0x{REVISION:08X}", f"serial number 0x{serial:08X}"]
    p, sent, _ = lss_ctl("inquire", "node-id")
    assert (p.returncode, sent, p.stdout.strip()) == (0, [frame(0x5E)], "node-ID none (0xFF)")

    p, sent, _ = lss_ctl("configure", "node-id", "0")  # refused before the bus
    assert (p.returncode, sent) == (2, [])
    p, sent, answers = lss_ctl("configure", "node-id", hex(NODE))
    assert p.returncode == 0, p.stderr
    assert (sent, answers) == ([frame(0x11, NODE)], [frame(0x11, 0)])
    p, sent, answers = lss_ctl("configure", "bit-timing", "250")  # table 0, index 3
    assert p.returncode == 0, p.stderr
    assert (sent, answers) == ([frame(0x13, 0, 3)], [frame(0x13, 0)])
    p, sent, answers = lss_ctl("store")
    assert (p.returncode, sent, answers) == (0, [frame(0x17)], [frame(0x17, 0)])
    assert (state / f"lss-{VENDOR:08x}-{PRODUCT:08x}-{serial:08x}.conf").is_file()
    # The stored bit timing is not applied by the node: the hook says what it would take, and
    # that vcan has no bit rate.
    hook = subprocess.run([str(REPO_ROOT / "tools" / "lss-bit-timing"), str(state), CHANNEL], capture_output=True,
                          text=True, timeout=30)
    assert hook.returncode == 0, hook.stderr
    assert "virtual CAN interface" in hook.stdout and "250 kbit/s" in hook.stdout, hook.stdout
    p, sent, _ = lss_ctl("activate-bit-timing", "--delay", "300")
    assert (p.returncode, sent) == (0, [frame(0x15, 0x2C, 0x01)])  # 300 ms, little-endian

    master.flush()
    p, sent, _ = lss_ctl("switch", "global", "waiting")
    assert (p.returncode, sent) == (0, [frame(0x04, 0)])
    boot = master.wait_bootup(NODE, timeout=5.0)
    assert boot is not None and bytes(boot.data) == b"\x00", node.log()
    assert master.read_u32(NODE, 0x1018, 4) == serial

    # Nobody in configuration now: a confirmed service gets no answer, exit 1.
    p, _, _ = lss_ctl("inquire", "node-id")
    assert p.returncode == 1 and "no LSS slave answered" in p.stderr, p.stderr


def test_fast_scan_assigns_ids_to_identical_nodes(lss_ctl, lss, master, start_node, tmp_path):
    serials = [0x5CA20002, 0x5CA20001]
    state = tmp_path / "shared"
    nodes = [start_unconfigured(start_node, s, state) for s in serials]
    assert wait_unconfigured(lss, 2) == 2, [n.log() for n in nodes]
    master.flush()
    p, sent, _ = lss_ctl("fast-scan", "--assign", "0x30", "--store", "--scan-timeout", "150")
    # The master's socket was not read while the scan ran: its few hundred frames filled the
    # socket's queue, which would drop the SDO answers below.
    master.flush()
    assert p.returncode == 0, p.stderr + "".join(n.log() for n in nodes)
    # The scan starts with BitChecked 0x80 (every non-configured slave answers and resets its
    # scan); each request: IDNumber, BitChecked 0..31, LSSSub and LSSNext 0..3.
    assert sent[0] == frame(0x51, 0, 0, 0, 0, 0x80, 0, 0)
    scans = [f for f in sent if f[0] == 0x51]
    assert all(f[5] <= 31 or f[5] == 0x80 for f in scans) and all(f[6] <= 3 and f[7] <= 3 for f in scans)
    # After the bits of a part, the part is confirmed with LSSNext = the next part.
    assert [f[6:8] for f in scans if f[6] != f[7]] == [bytes([0, 1]), bytes([1, 2]), bytes([2, 3]), bytes([3, 0])] * 2
    # Each found slave: configure node-ID, store, switch to waiting (CiA 305 frames).
    assert [f for f in sent if f[0] != 0x51] == [frame(0x11, 0x30), frame(0x17), frame(0x04, 0),
                                                 frame(0x11, 0x31), frame(0x17), frame(0x04, 0)]
    out = p.stdout.splitlines()
    assert f"serial number 0x{min(serials):08X}" in out and "2 non-configured slaves found" in out
    # The lowest identity first: a 0 bit is tried before a 1.
    assert master.read_u32(0x30, 0x1018, 4) == min(serials)
    assert master.read_u32(0x31, 0x1018, 4) == max(serials)
    assert wait_unconfigured(lss, 1, timeout=0.5) == 0
