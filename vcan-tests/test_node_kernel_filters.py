"""The node's kernel receive filters on vcan (issue 13). Paused (SIGSTOP), a node's socket
holds a few hundred frames; frames addressed to other nodes must not take that room, so
an NMT start sent after them still reaches it. Before the filters, 280 frames for another
node and then an NMT start left the node PRE-OPERATIONAL for good. The frames are CiA 301's
pre-defined connection set for node 43: SDO requests 0x600+43, RPDO1 0x200+43, its heartbeat
0x700+43; NMT start = 0x000 [0x01, node]; the node confirms with its heartbeat 0x700+id [0x05]."""

import os
import signal
import time

import can
import pytest

from canopen_master import STATE_OPERATIONAL, STATE_PREOPERATIONAL

NODE = 42
OTHER = 43


def frames_for_the_other_node(count):
    """SDO requests, RPDOs and heartbeats of node OTHER, in turn."""
    kinds = [(0x600 + OTHER, bytes([0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0])),
             (0x200 + OTHER, bytes([1, 2, 3, 4])),
             (0x700 + OTHER, bytes([STATE_PREOPERATIONAL]))]
    for i in range(count):
        cob_id, data = kinds[i % len(kinds)]
        yield can.Message(arbitration_id=cob_id, data=data, is_extended_id=False)


def send_all(bus, messages):
    sent = 0
    for m in messages:
        for _ in range(100):
            try:
                bus.send(m, timeout=1.0)
                sent += 1
                break
            except can.CanError:
                time.sleep(0.001)
    return sent


@pytest.mark.parametrize("count", [280, 1000])
def test_an_nmt_start_after_frames_for_another_node_is_obeyed(master, start_node, bus, count):
    node = start_node(NODE)
    assert master.read_u32(NODE, 0x2F10) == 0
    master.flush()
    os.kill(node.proc.pid, signal.SIGSTOP)
    try:
        assert send_all(bus, frames_for_the_other_node(count)) == count
        master.nmt_start(NODE)
    finally:
        os.kill(node.proc.pid, signal.SIGCONT)
    assert master.wait_heartbeat(NODE, timeout=3.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    # None of the frames for node 43 reached the node's queue: nothing was dropped.
    assert master.read_u32(NODE, 0x2F10) == 0
    assert node.alive


def test_frames_the_node_serves_still_reach_it_after_a_flood(master, start_node, bus):
    node = start_node(NODE)
    master.write_u16(NODE, 0x1017, 0, 0)  # node guarding is answered only while 0x1017 is 0
    master.flush()
    os.kill(node.proc.pid, signal.SIGSTOP)
    try:
        send_all(bus, frames_for_the_other_node(600))
        master.send(0x700 + NODE, remote=True)  # a node guarding request: a remote frame
    finally:
        os.kill(node.proc.pid, signal.SIGCONT)
    answer = master.wait_for(lambda m: m.arbitration_id == 0x700 + NODE and not m.is_remote_frame, timeout=3.0)
    assert answer is not None and answer.data[0] & 0x7F == STATE_PREOPERATIONAL
    assert master.read_u16(NODE, 0x1017) == 0  # SDO on 0x600+id
    assert node.alive
