"""stepnode's NMT slave and heartbeat producer on vcan, checked against CiA 301 with the
independent master in canopen_master.py: boot-up, the heartbeat period (default and set
over SDO), every NMT state transition confirmed by an immediate heartbeat, SDO silence while
stopped, reset communication vs. reset node, and broadcast NMT to two nodes.

Timing in User-Mode Linux is slow and jittery: periods are checked as the mean of several
intervals (kernel receive timestamps) within +-25 %, never as exact times."""

import statistics
import struct
import time

from canopen_master import (COB_HEARTBEAT, STATE_OPERATIONAL, STATE_PREOPERATIONAL, STATE_STOPPED,
                            decode_heartbeat)

NODE = 21
SIGNATURE_SAVE = 0x65766173  # "save"


def beats_of(master, node, duration):
    """Heartbeat frames (not boot-up) of node seen during duration seconds."""
    return master.collect(duration, lambda m: m.arbitration_id == COB_HEARTBEAT + node and len(m.data) == 1
                          and m.data[0] != 0)


def mean_interval(frames):
    times = [m.timestamp for m in frames]
    return statistics.mean(b - a for a, b in zip(times, times[1:]))


def expect_state_change(master, node, command, state, period_s):
    """Send an NMT command and return the delay (s) until the heartbeat with the new state.

    The heartbeat period is set long (period_s) so that only an immediate confirmation,
    not the next periodic beat, can arrive within the accepted delay."""
    master.flush()
    t0 = time.time()
    command(node)
    msg = master.wait_for(lambda m: decode_heartbeat(m) == (node, state), timeout=period_s)
    assert msg is not None, f"no heartbeat with state 0x{state:02X} from node {node} after the NMT command"
    return msg.timestamp - t0


def test_bootup_frame_then_preoperational(master, start_node):
    node = start_node(NODE)
    # Boot-up: COB-ID 0x700+N, exactly one data byte 0x00 (CiA 301 7.2.8.3.2.1).
    assert node.bootup.arbitration_id == 0x700 + NODE
    assert not node.bootup.is_extended_id and not node.bootup.is_remote_frame
    assert bytes(node.bootup.data) == b"\x00"
    # Then the node is pre-operational: its heartbeats say 0x7F and SDO works.
    assert master.wait_heartbeat(NODE, timeout=2.5, state=STATE_PREOPERATIONAL) == STATE_PREOPERATIONAL
    assert master.read_u16(NODE, 0x1017) == 1000


def test_default_heartbeat_period_is_1000_ms(master, start_node):
    start_node(NODE)
    master.flush()
    beats = beats_of(master, NODE, 4.6)
    assert 3 <= len(beats) <= 6, [m.timestamp for m in beats]
    mean = mean_interval(beats)
    assert 0.75 <= mean <= 1.25, f"mean heartbeat interval {mean:.3f} s, expected 1.000 s +-25 %"
    assert all(bytes(m.data) == bytes([STATE_PREOPERATIONAL]) for m in beats)


def test_heartbeat_period_set_over_sdo(master, start_node):
    start_node(NODE)
    master.write_u16(NODE, 0x1017, 0, 200)
    assert master.read_u16(NODE, 0x1017) == 200
    master.flush()
    beats = beats_of(master, NODE, 2.6)[:11]  # ~10 intervals
    assert len(beats) >= 9, f"only {len(beats)} heartbeats in 2.6 s at 200 ms"
    mean = mean_interval(beats)
    assert 0.150 <= mean <= 0.250, f"mean heartbeat interval {mean * 1000:.0f} ms, expected 200 ms +-25 %"
    # Producer off (0): no heartbeats at all.
    master.write_u16(NODE, 0x1017, 0, 0)
    master.flush()
    assert beats_of(master, NODE, 1.5) == []


def test_nmt_transitions_confirmed_at_once(master, start_node):
    start_node(NODE)
    # A 5 s period: a heartbeat within 1 s of the command is the confirmation, not the
    # periodic beat (which would arrive at a random point of the 5 s).
    master.write_u16(NODE, 0x1017, 0, 5000)
    delays = []
    for command, state in ((master.nmt_start, STATE_OPERATIONAL), (master.nmt_stop, STATE_STOPPED),
                           (master.nmt_preop, STATE_PREOPERATIONAL), (master.nmt_start, STATE_OPERATIONAL),
                           (master.nmt_preop, STATE_PREOPERATIONAL)):
        delays.append(expect_state_change(master, NODE, command, state, period_s=4.0))
    assert max(delays) < 1.0, f"NMT confirmations took {[round(d, 3) for d in delays]} s"
    # An unknown command specifier changes nothing.
    master.flush()
    master.send(0x000, bytes([0x55, NODE]))
    changed = master.wait_for(lambda m: (hb := decode_heartbeat(m)) is not None and hb[0] == NODE
                              and hb[1] != STATE_PREOPERATIONAL, timeout=1.0)
    assert changed is None, f"NMT 0x55 changed the state: {changed}"
    assert master.read_u16(NODE, 0x1017) == 5000


def test_stopped_node_answers_no_sdo_but_keeps_heartbeat(master, start_node):
    start_node(NODE)
    master.write_u16(NODE, 0x1017, 0, 300)
    expect_state_change(master, NODE, master.nmt_stop, STATE_STOPPED, period_s=2.0)
    # Upload 0x1017 and download 0x2F00:1: no answer of any kind while stopped.
    assert master.sdo_request(NODE, struct.pack("<BHB", 0x40, 0x1017, 0), timeout=1.0) is None
    assert master.sdo_request(NODE, struct.pack("<BHBI", 0x23, 0x2F00, 1, 99), timeout=1.0) is None
    # Error control goes on: stopped heartbeats at the set period.
    master.flush()
    beats = beats_of(master, NODE, 1.6)
    assert len(beats) >= 3 and all(m.data[0] == STATE_STOPPED for m in beats), beats
    # Back to pre-operational: SDO answers again and the download above was not applied.
    expect_state_change(master, NODE, master.nmt_preop, STATE_PREOPERATIONAL, period_s=2.0)
    assert master.read_u32(NODE, 0x2F00, 1) == 0


def test_reset_communication_restores_communication_parameters_only(master, start_node):
    start_node(NODE)
    # Stored: 0x1017 = 400 (communication group, 0x1010:2). Then not stored: 300.
    master.write_u16(NODE, 0x1017, 0, 400)
    master.write_u32(NODE, 0x1010, 2, SIGNATURE_SAVE)
    master.write_u16(NODE, 0x1017, 0, 300)
    master.write_u32(NODE, 0x1016, 1, (100 << 16) | 2000)
    master.write_u32(NODE, 0x2F00, 1, 77)  # application area: untouched by reset-comm
    master.nmt_start(NODE)
    assert master.wait_heartbeat(NODE, timeout=1.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    master.flush()
    master.nmt_reset_comm(NODE)
    boot = master.wait_bootup(NODE, timeout=2.0)
    assert boot is not None and bytes(boot.data) == b"\x00"
    assert master.wait_heartbeat(NODE, timeout=1.0, state=STATE_PREOPERATIONAL) == STATE_PREOPERATIONAL
    assert master.read_u16(NODE, 0x1017) == 400          # stored value, not the unsaved 300
    assert master.read_u32(NODE, 0x1016, 1) == 0         # default
    assert master.read_u32(NODE, 0x2F00, 1) == 77        # application parameter kept
    # Without a stored value the default comes back.
    master.write_u32(NODE, 0x1011, 2, 0x64616F6C)        # "load": forget stored communication values
    master.write_u16(NODE, 0x1017, 0, 300)
    master.nmt_reset_comm(NODE)
    assert master.wait_bootup(NODE, timeout=2.0) is not None
    assert master.read_u16(NODE, 0x1017) == 1000


def test_reset_node_brings_everything_back(master, start_node):
    start_node(NODE)
    master.write_u16(NODE, 0x1017, 0, 300)
    master.write_u32(NODE, 0x2F00, 1, 0x12345678)
    master.write_u32(NODE, 0x2F00, 8, 0xFFFFFFFF)
    master.sdo_download(NODE, 0x2F01, 0, b"not saved, lost on reset")
    master.write_u32(NODE, 0x1800, 1, 0x80000180 + NODE)
    master.nmt_start(NODE)
    assert master.wait_heartbeat(NODE, timeout=1.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    master.flush()
    master.nmt_reset_node(NODE)
    assert master.wait_bootup(NODE, timeout=2.0) is not None
    assert master.wait_heartbeat(NODE, timeout=1.5, state=STATE_PREOPERATIONAL) == STATE_PREOPERATIONAL
    assert master.read_u16(NODE, 0x1017) == 1000
    assert master.read_u32(NODE, 0x2F00, 1) == 0
    assert master.read_u32(NODE, 0x2F00, 8) == 0
    assert master.sdo_upload(NODE, 0x2F01, 0) == b""
    assert master.read_u32(NODE, 0x1800, 1) & 0x800007FF == 0x180 + NODE  # TPDO1 valid again


def test_broadcast_nmt_reaches_both_nodes(master, start_node):
    a, b = NODE, NODE + 1
    start_node(a)
    start_node(b)
    for n in (a, b):
        master.write_u16(n, 0x1017, 0, 5000)
    for command, state in ((master.nmt_start, STATE_OPERATIONAL), (master.nmt_stop, STATE_STOPPED),
                           (master.nmt_preop, STATE_PREOPERATIONAL)):
        master.flush()
        command(0)
        for n in (a, b):
            assert master.wait_heartbeat(n, timeout=2.0, state=state) == state, f"node {n}, state 0x{state:02X}"
    master.write_u32(a, 0x2F00, 1, 1)
    master.write_u32(b, 0x2F00, 1, 2)
    master.flush()
    master.nmt_reset_node(0)
    for n in (a, b):
        assert master.wait_bootup(n, timeout=2.0) is not None, f"no boot-up from node {n}"
    assert master.read_u32(a, 0x2F00, 1) == 0 and master.read_u32(b, 0x2F00, 1) == 0
    # Addressed NMT reaches only its node.
    master.write_u16(b, 0x1017, 0, 300)
    master.flush()
    master.nmt_start(a)
    assert master.wait_heartbeat(a, timeout=2.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    beats_b = beats_of(master, b, 1.0)
    assert beats_b and all(m.data[0] == STATE_PREOPERATIONAL for m in beats_b)
