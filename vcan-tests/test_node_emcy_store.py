"""stepnode's EMCY producer and error history, and store/restore of parameters across a
kill -9, on vcan. The EMCY is provoked through the bus alone: the node consumes the
heartbeat of a (fake) node 127 that falls silent."""

import contextlib
import os
import threading
import time

import can

import pytest

from canopen_master import ABORT_NO_OBJECT, STATE_OPERATIONAL, SdoAbort, decode_emcy
from conftest import open_bus

NODE = 24
WATCHED = 0x7F
SAVE, LOAD = 0x65766173, 0x64616F6C  # "save", "load"


def emcys(master, node, duration):
    return [decode_emcy(m) for m in master.collect(duration, lambda m: m.arbitration_id == 0x80 + node)]


@contextlib.contextmanager
def heartbeat_of(node, period):
    """A fake node that sends operational heartbeats every period seconds (own socket)."""
    stop = threading.Event()

    def beat():
        bus = open_bus()
        try:
            while not stop.is_set():
                bus.send(can.Message(arbitration_id=0x700 + node, data=b"\x05", is_extended_id=False))
                stop.wait(period)
        finally:
            bus.shutdown()

    thread = threading.Thread(target=beat, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join(5)


def count_axes(master):
    """Axes present: 0x2n00 (command bits of axis n+1) exists for each."""
    for n in range(8):
        try:
            master.read_u16(NODE, 0x2000 + 0x100 * n)
        except SdoAbort as e:
            assert e.code == ABORT_NO_OBJECT, e
            return n
    return 8


def clear_axis_errors(master, axes):
    """Clear Errors (%Q14, bit 13 of 0x2n00) on every axis: the command acts on the edge."""
    for n in range(axes):
        for word in (0, 1 << 13, 0):
            master.write_u16(NODE, 0x2000 + 0x100 * n, 0, word)


def test_heartbeat_consumer_timeout_raises_emcy_and_history(master, start_node):
    start_node(NODE)
    axes = count_axes(master)
    assert axes >= 1
    clear_axis_errors(master, axes)  # power-up errors off, so the register starts at 0
    assert master.read_u8(NODE, 0x1001) == 0
    master.nmt_start(NODE)
    assert master.wait_heartbeat(NODE, timeout=2.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    master.write_u32(NODE, 0x1016, 1, (WATCHED << 16) | 300)
    assert master.read_u32(NODE, 0x1016, 1) == (WATCHED << 16) | 300
    master.flush()
    # Monitoring starts with the first heartbeat received: none yet, so no EMCY.
    assert emcys(master, NODE, 1.0) == []
    master.send(0x700 + WATCHED, b"\x05")
    t_beat = time.time()
    emcy = master.wait_emcy(NODE, timeout=1.5)
    assert emcy is not None, "no EMCY within 1.5 s of node 127 falling silent (300 ms consumer time)"
    assert emcy.error_code == 0x8130, hex(emcy.error_code)
    assert emcy.error_register & 0x11 == 0x11, hex(emcy.error_register)  # generic + communication (bit 4)
    assert emcy.manufacturer[0] == WATCHED, emcy.manufacturer
    assert emcy.timestamp - t_beat >= 0.25, f"EMCY {emcy.timestamp - t_beat:.3f} s after the heartbeat"
    # The lost master also latches the power-up/watchdog error of every axis (README):
    # EMCY 0xFF00+axis, error register bit 7. One EMCY per error, not one per tick.
    later = emcys(master, NODE, 1.5)
    assert sorted(e.error_code for e in later) == [0xFF01 + n for n in range(axes)], later
    assert master.read_u8(NODE, 0x1001) == 0x91  # generic, communication, manufacturer
    # The pre-defined error field holds them newest first; 0x8130 carries node 127.
    sent = [emcy.error_code] + [e.error_code for e in later]
    assert master.read_u8(NODE, 0x1003, 0) == len(sent)
    history = [master.read_u32(NODE, 0x1003, i) for i in range(1, len(sent) + 1)]
    assert [h & 0xFFFF for h in history] == sent[::-1], [hex(h) for h in history]
    assert history[-1] == (WATCHED << 16) | 0x8130, hex(history[-1])
    # Writing 0 to 0x1003:0 clears the history.
    master.write_u8(NODE, 0x1003, 0, 0)
    assert master.read_u8(NODE, 0x1003, 0) == 0
    # The heartbeat comes back (node 127 beats every 50 ms from now on): the communication
    # bit clears, the axes' errors stay latched until Clear Errors; then EMCY 0x0000.
    with heartbeat_of(WATCHED, 0.05):
        time.sleep(0.5)
        assert master.read_u8(NODE, 0x1001) == 0x81
        master.flush()
        clear_axis_errors(master, axes)
        reset = emcys(master, NODE, 1.0)
        assert [(e.error_code, e.error_register) for e in reset] == [(0x0000, 0)], reset
    assert master.read_u8(NODE, 0x1001) == 0
    assert master.read_u8(NODE, 0x1003, 0) == 0


def test_disabling_the_consumer_clears_its_heartbeat_error(master, start_node):
    """Once the master stops watching the silent node (0x1016:1 = 0), the heartbeat error is
    gone: error register bit 4 clears and, with no other error, EMCY 0x0000 is sent."""
    start_node(NODE)
    axes = count_axes(master)
    master.write_u32(NODE, 0x1016, 1, (WATCHED << 16) | 200)
    master.send(0x700 + WATCHED, b"\x7f")
    e = master.wait_emcy(NODE, timeout=1.5)
    assert e is not None and e.error_code == 0x8130, e
    time.sleep(0.3)
    clear_axis_errors(master, axes)  # only the heartbeat error is left
    assert master.read_u8(NODE, 0x1001) == 0x11
    master.flush()
    master.write_u32(NODE, 0x1016, 1, 0)
    back = master.wait_emcy(NODE, timeout=1.5)
    assert back is not None and (back.error_code, back.error_register) == (0x0000, 0), back
    assert master.read_u8(NODE, 0x1001) == 0


def test_store_survives_kill_9_and_restore_brings_defaults(master, start_node, tmp_path):
    state = tmp_path / "state"
    node = start_node(NODE, state_dir=state)
    blob = os.urandom(300)
    master.write_u16(NODE, 0x1017, 0, 333)
    master.write_u32(NODE, 0x2F00, 1, 0xDEADBEEF)
    master.sdo_download(NODE, 0x2F01, 0, blob)
    master.write_u32(NODE, 0x1010, 1, SAVE)
    assert (state / f"node-{NODE}.params").is_file()
    master.write_u32(NODE, 0x2F00, 2, 5)            # written after the save: not kept
    assert node.kill() == -9

    master.flush()
    node = start_node(NODE, state_dir=state)
    assert master.read_u16(NODE, 0x1017) == 333
    assert master.read_u32(NODE, 0x2F00, 1) == 0xDEADBEEF
    assert master.read_u32(NODE, 0x2F00, 2) == 0
    assert master.sdo_upload(NODE, 0x2F01, 0) == blob
    assert master.read_u8(NODE, 0x1001) == 0
    # The stored period is in force (333 ms +- 25 %), and no EMCY was sent at boot.
    beats = master.collect(2.2, lambda m: m.arbitration_id == 0x700 + NODE and bytes(m.data) == b"\x7f")
    gaps = [b.timestamp - a.timestamp for a, b in zip(beats, beats[1:])]
    assert len(gaps) >= 4 and 0.25 <= sum(gaps) / len(gaps) <= 0.42, gaps
    # Every frame since the restart is in the backlog or on the socket: no EMCY among them.
    assert [m for m in master.collect(0.1) if m.arbitration_id == 0x80 + NODE] == [], "EMCY at boot"

    # Restore defaults: in force after the next reset, and persistent.
    master.write_u32(NODE, 0x1011, 1, LOAD)
    assert master.read_u16(NODE, 0x1017) == 333
    master.flush()
    master.nmt_reset_node(NODE)
    assert master.wait_bootup(NODE, timeout=2.0) is not None
    assert master.read_u16(NODE, 0x1017) == 1000
    assert master.read_u32(NODE, 0x2F00, 1) == 0
    assert master.sdo_upload(NODE, 0x2F01, 0) == b""
    assert node.kill() == -9
    start_node(NODE, state_dir=state)
    assert master.read_u16(NODE, 0x1017) == 1000
    assert master.read_u32(NODE, 0x2F00, 1) == 0


def test_store_groups_keep_their_own_range(master, start_node, tmp_path):
    """0x1010:2 stores communication (0x1000-0x1FFF) only, 0x1010:4 manufacturer objects
    (0x2000-0x5FFF) only."""
    state = tmp_path / "state"
    node = start_node(NODE, state_dir=state)
    master.write_u16(NODE, 0x1017, 0, 444)
    master.write_u32(NODE, 0x2F00, 1, 0x44)
    master.write_u32(NODE, 0x1010, 2, SAVE)
    master.write_u16(NODE, 0x1017, 0, 555)
    master.write_u32(NODE, 0x2F00, 1, 0x55)
    master.write_u32(NODE, 0x1010, 4, SAVE)
    node.kill()
    start_node(NODE, state_dir=state)
    assert master.read_u16(NODE, 0x1017) == 444
    assert master.read_u32(NODE, 0x2F00, 1) == 0x55


@pytest.mark.parametrize("bad", [b"", b"# stepnode stored parameters v1\nzzzz not a line\n1017:00 4d\n"])
def test_damaged_parameter_file_falls_back_to_defaults(master, start_node, tmp_path, bad):
    state = tmp_path / "state"
    state.mkdir()
    (state / f"node-{NODE}.params").write_bytes(bad)
    node = start_node(NODE, state_dir=state)  # boots (fixture asserts the boot-up frame)
    assert node.alive
    assert master.read_u16(NODE, 0x1017) == 1000  # "4d" is one byte: does not fit a U16
