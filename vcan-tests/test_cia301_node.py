"""stepnode as a CiA 301 slave on a real vcan interface: boot-up, heartbeat, NMT, every SDO
transfer type, abort codes, PDO remapping and reception, store/restore across a kill, two
nodes on one bus, and bad command lines. The master here is canopen_master.py (written
from CiA 301, independent of the node's C++ code)."""

import os
import signal
import statistics
import subprocess
import time

import pytest

from canopen_master import (ABORT_NO_OBJECT, ABORT_NO_SUBINDEX, ABORT_READ_ONLY, ABORT_TYPE_LENGTH_HIGH,
                            SdoAbort, STATE_OPERATIONAL, STATE_PREOPERATIONAL, STATE_STOPPED, decode_emcy)
from conftest import CHANNEL, collect_frames

NODE = 11


def heartbeats(master, node, duration):
    return [m for m in master.collect(duration, lambda m: m.arbitration_id == 0x700 + node)]


def test_bootup_and_heartbeat_period(master, start_node):
    node = start_node(NODE)
    assert bytes(node.bootup.data) == b"\x00"
    master.write_u16(NODE, 0x1017, 0, 200)
    master.flush()  # the boot-up frame is in the backlog
    beats = heartbeats(master, NODE, 2.5)
    times = [m.timestamp for m in beats]
    gaps = [b - a for a, b in zip(times, times[1:])]
    assert len(gaps) >= 8, gaps
    assert 0.15 <= statistics.mean(gaps) <= 0.25, gaps  # 200 ms, loose for User-Mode Linux
    assert all(m.data[0] == STATE_PREOPERATIONAL for m in beats)


def test_nmt_transitions_confirmed_and_sdo_silent_when_stopped(master, start_node):
    start_node(NODE)
    master.write_u16(NODE, 0x1017, 0, 1000)
    for command, state in ((master.nmt_start, STATE_OPERATIONAL), (master.nmt_stop, STATE_STOPPED),
                           (master.nmt_preop, STATE_PREOPERATIONAL), (master.nmt_start, STATE_OPERATIONAL)):
        t0 = time.monotonic()
        command(NODE)
        assert master.wait_heartbeat(NODE, timeout=0.4, state=state) == state, f"no heartbeat {state:#x}"
        assert time.monotonic() - t0 < 0.4
    master.nmt_stop(NODE)
    master.wait_heartbeat(NODE, timeout=0.4, state=STATE_STOPPED)
    assert master.sdo_request(NODE, bytes([0x40, 0x17, 0x10, 0, 0, 0, 0, 0]), timeout=0.5) is None
    # Reset communication: boot-up, pre-operational, communication parameters back.
    master.nmt_preop(NODE)
    master.wait_heartbeat(NODE, timeout=0.4, state=STATE_PREOPERATIONAL)
    master.write_u16(NODE, 0x1017, 0, 300)
    master.nmt_reset_comm(NODE)
    assert master.wait_bootup(NODE, timeout=1.0) is not None
    assert master.read_u16(NODE, 0x1017) == 1000
    master.write_u32(NODE, 0x2F00, 1, 77)
    master.nmt_reset_node(NODE)
    assert master.wait_bootup(NODE, timeout=1.0) is not None
    assert master.read_u32(NODE, 0x2F00, 1) == 0


def test_sdo_transfers_of_every_kind(master, start_node, stepnode_bin):
    start_node(NODE)
    assert master.read_u32(NODE, 0x1018, 2) == 0x53544550            # expedited
    assert master.sdo_upload(NODE, 0x1008, 0) == b"stepnode"         # segmented
    eds = master.sdo_block_upload(NODE, 0x1021, 0)                   # block, CRC
    printed = subprocess.run([str(stepnode_bin), "--print-eds"], capture_output=True, check=True).stdout
    assert eds == printed and eds.startswith(b"[FileInfo]") and len(eds) > 50_000
    data = os.urandom(4096)
    master.sdo_download(NODE, 0x2F01, 0, data)                       # segmented download
    assert master.sdo_upload(NODE, 0x2F01, 0) == data
    data = os.urandom(4096)
    master.sdo_block_download(NODE, 0x2F01, 0, data)                 # block download
    assert master.sdo_block_upload(NODE, 0x2F01, 0, blksize=7) == data
    with pytest.raises(SdoAbort) as e:
        master.sdo_download(NODE, 0x2F01, 0, b"x" * 4097)
    assert e.value.code == ABORT_TYPE_LENGTH_HIGH


def test_abort_codes(master, start_node):
    start_node(NODE)
    for call, code in ((lambda: master.sdo_upload(NODE, 0x1F00, 0), ABORT_NO_OBJECT),
                       (lambda: master.sdo_upload(NODE, 0x1018, 9), ABORT_NO_SUBINDEX),
                       (lambda: master.write_u32(NODE, 0x1000, 0, 1), ABORT_READ_ONLY),
                       (lambda: master.write_u32(NODE, 0x1010, 1, 0x1234), 0x08000020),
                       (lambda: master.write_u32(NODE, 0x1A00, 1, 0x2F000120), 0x08000022),
                       (lambda: master.write_u8(NODE, 0x2009, 1, 7), 0x06090031)):
        with pytest.raises(SdoAbort) as e:
            call()
        assert e.value.code == code, hex(e.value.code)
    master.write_u32(NODE, 0x1800, 1, 0xC0000180 + NODE)
    master.write_u8(NODE, 0x1A00, 0, 0)
    for word, code in ((0x10080008, 0x06040041), (0x2F000110, 0x06040043)):
        with pytest.raises(SdoAbort) as e:
            master.write_u32(NODE, 0x1A00, 1, word)
        assert e.value.code == code, hex(e.value.code)


def remap_tpdo1(master, words, transmission_type):
    master.write_u32(NODE, 0x1800, 1, 0xC0000180 + NODE)   # CiA 301: destroy,
    master.write_u8(NODE, 0x1A00, 0, 0)                     # disable the mapping,
    for i, w in enumerate(words, 1):
        master.write_u32(NODE, 0x1A00, i, w)                # write it,
    master.write_u8(NODE, 0x1A00, 0, len(words))            # enable,
    master.write_u8(NODE, 0x1800, 2, transmission_type)
    master.write_u32(NODE, 0x1800, 1, 0x40000180 + NODE)    # create.


def test_tpdo_remapped_then_on_sync_and_on_change_and_rpdo_applied(master, start_node):
    start_node(NODE)
    remap_tpdo1(master, [0x2F000120, 0x10010008], 1)
    master.write_u32(NODE, 0x2F00, 1, 0xC0FFEE42)
    master.nmt_start(NODE)
    master.wait_heartbeat(NODE, timeout=1.0, state=STATE_OPERATIONAL)
    master.flush()
    for _ in range(3):
        master.sync()
    got = master.collect(0.5, lambda m: m.arbitration_id == 0x180 + NODE)
    assert [bytes(m.data) for m in got] == [bytes.fromhex("42eeffc000")] * 3
    # Event-driven: a change goes out at once, no SYNC needed.
    master.nmt_preop(NODE)
    remap_tpdo1(master, [0x2F000220], 254)
    master.nmt_start(NODE)
    # RPDO1 -> user register 2; the TPDO mapping it fires on the change.
    master.write_u32(NODE, 0x1400, 1, 0x80000200 + NODE)
    master.write_u8(NODE, 0x1600, 0, 0)
    master.write_u32(NODE, 0x1600, 1, 0x2F000220)
    master.write_u8(NODE, 0x1600, 0, 1)
    master.write_u32(NODE, 0x1400, 1, 0x00000200 + NODE)
    master.flush()
    master.send(0x200 + NODE, bytes.fromhex("dec0175a"))
    tpdo = master.wait_for(lambda m: m.arbitration_id == 0x180 + NODE and bytes(m.data) == bytes.fromhex("dec0175a"), 1.0)
    assert tpdo is not None
    assert master.read_u32(NODE, 0x2F00, 2) == 0x5A17C0DE
    # Shorter than the mapping: not applied, EMCY 0x8210.
    master.send(0x200 + NODE, b"\x01\x02")
    emcy = master.wait_emcy(NODE, timeout=1.0)
    assert emcy is not None and emcy.error_code == 0x8210
    assert master.read_u32(NODE, 0x2F00, 2) == 0x5A17C0DE


def test_store_kill_restart_retains(master, start_node, tmp_path):
    state = tmp_path / "kept"
    node = start_node(NODE, state_dir=state)
    master.write_u16(NODE, 0x1017, 0, 333)
    master.write_u32(NODE, 0x2F00, 1, 0xDEADBEEF)
    master.write_u32(NODE, 0x1010, 1, 0x65766173)   # "save"
    node.send_signal(signal.SIGKILL)
    node.wait(5)
    start_node(NODE, state_dir=state)
    assert master.read_u16(NODE, 0x1017) == 333
    assert master.read_u32(NODE, 0x2F00, 1) == 0xDEADBEEF
    assert master.read_u8(NODE, 0x1001) == 0
    master.write_u32(NODE, 0x1011, 1, 0x64616F6C)   # "load": defaults after a reset
    master.nmt_reset_node(NODE)
    master.wait_bootup(NODE, timeout=1.0)
    assert master.read_u16(NODE, 0x1017) == 1000


def test_two_nodes_do_not_interfere(master, start_node):
    start_node(12)
    start_node(13)
    master.write_u32(12, 0x2F00, 1, 12)
    master.write_u32(13, 0x2F00, 1, 13)
    assert master.read_u32(12, 0x2F00, 1) == 12
    assert master.read_u32(13, 0x2F00, 1) == 13
    master.flush()
    master.sdo_upload(12, 0x1000, 0)
    answers = master.collect(0.3, lambda m: 0x580 < m.arbitration_id < 0x600)
    assert all(m.arbitration_id == 0x58C for m in answers)
    master.nmt_start(0)
    assert master.wait_heartbeat(12, timeout=1.5, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    assert master.wait_heartbeat(13, timeout=1.5, state=STATE_OPERATIONAL) == STATE_OPERATIONAL


@pytest.mark.parametrize("args", [["--iface", CHANNEL, "--node-id", "0"], ["--iface", CHANNEL, "--node-id", "128"],
                                  ["--node-id", "5"], ["--iface", "nosuch0", "--node-id", "5"],
                                  ["--iface", CHANNEL, "--node-id", "5", "--config", "/nonexistent.toml"]])
def test_bad_command_line_exits_2_with_one_line(stepnode_bin, args):
    r = subprocess.run([str(stepnode_bin), *args], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2, r
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_stepctl_reads_writes_and_fails_clearly(master, start_node):
    ctl = os.environ.get("STEPCTL_BIN", "build/tools/stepctl")
    start_node(NODE)
    run = lambda *a: subprocess.run([ctl, "--iface", CHANNEL, *a], capture_output=True, text=True, timeout=60)
    r = run("read", str(NODE), "0x1008")
    assert r.returncode == 0 and '"stepnode"' in r.stdout and "VISIBLE_STRING" in r.stdout
    assert run("write", str(NODE), "0x1017", "250").returncode == 0
    master.flush()  # stepctl's SDO answers are in this master's backlog too
    assert master.read_u16(NODE, 0x1017) == 250
    r = run("write", str(NODE), "0x1000", "1")
    assert r.returncode == 1 and "0x06010002" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert run("read", str(NODE), "zz").returncode == 2
    r = run("nmt", "start", "--node", str(NODE))
    assert r.returncode == 0 and "confirmed" in r.stdout


def test_stepctl_watch_decodes_the_bus(master, start_node):
    ctl = os.environ.get("STEPCTL_BIN", "build/tools/stepctl")
    watch = subprocess.Popen([ctl, "--iface", CHANNEL, "watch", "--seconds", "6"], stdout=subprocess.PIPE, text=True)
    time.sleep(2.5)  # python and the tool start slowly inside User-Mode Linux
    start_node(NODE)
    time.sleep(1.0)  # the watch reads the node's PDO mapping once it sees it
    master.nmt_start(NODE)
    master.wait_heartbeat(NODE, timeout=1.0, state=STATE_OPERATIONAL)
    master.write_u32(NODE, 0x1016, 1, (0x7E << 16) | 200)
    master.send(0x77E, b"\x05")  # a heartbeat from node 126, then silence: EMCY 0x8130
    assert master.wait_emcy(NODE, timeout=2.0) is not None
    out, _ = watch.communicate(timeout=30)
    assert f"heartbeat node {NODE}: boot-up" in out
    assert f"NMT start node {NODE}" in out
    assert f"heartbeat node {NODE}: operational" in out
    assert f"EMCY node {NODE}: 0x8130 life guard or heartbeat error" in out
    # TPDO1 of axis 1 decoded by the mapping read from the node.
    assert f"TPDO1 node {NODE}: Axis 1 status bits" in out, out[-3000:]
