"""stepnode's node guarding and life guarding (CiA 301 7.2.8.3.1) on vcan, from the
master's side as CiA 301 describes it: a remote frame on 0x700+N is answered with one byte,
the NMT state in bits 0..6 and a toggle bit 7 that starts at 0 and alternates; only while
the heartbeat producer time 0x1017 is 0. With guard time 0x100C x life time factor 0x100D
set, a master that stops guarding is a life guarding event: EMCY 0x8130, and the node
leaves operational (0x1029 = 0); the next request ends it."""

import time

import can

from canopen_master import COB_HEARTBEAT, STATE_OPERATIONAL, STATE_PREOPERATIONAL, STATE_STOPPED

NODE = 23


def guard(master, node=NODE, timeout=1.0):
    """One guarding request; the answer's byte, or None."""
    master.flush()
    # The remote frame carries the length of the answer it asks for (1), no data.
    master.bus.send(can.Message(arbitration_id=COB_HEARTBEAT + node, is_remote_frame=True, dlc=1,
                                is_extended_id=False))
    msg = master.wait_for(lambda m: m.arbitration_id == COB_HEARTBEAT + node and not m.is_remote_frame,
                          timeout)
    if msg is None:
        return None
    assert len(msg.data) == 1, bytes(msg.data).hex()
    return msg.data[0]


def test_guarding_answers_state_and_toggle(master, start_node):
    start_node(NODE)
    # A heartbeat every 10 s (none comes during the check): heartbeat is in use, so no answer.
    master.write_u16(NODE, 0x1017, 0, 10000)
    assert guard(master, timeout=0.5) is None, "no guarding while the heartbeat is produced"
    master.write_u16(NODE, 0x1017, 0, 0)
    assert [guard(master) for _ in range(3)] == [STATE_PREOPERATIONAL, 0x80 | STATE_PREOPERATIONAL,
                                                 STATE_PREOPERATIONAL]
    master.nmt_start(NODE)
    assert guard(master) == 0x80 | STATE_OPERATIONAL
    master.nmt_stop(NODE)
    assert guard(master) == STATE_STOPPED
    master.nmt_preop(NODE)
    assert guard(master) == 0x80 | STATE_PREOPERATIONAL
    # Reset communication puts the toggle back to 0 (and 0x1017 back to 1000: set it again).
    master.nmt_reset_comm(NODE)
    assert master.wait_bootup(NODE, timeout=5.0) is not None
    master.write_u16(NODE, 0x1017, 0, 0)
    assert guard(master) == STATE_PREOPERATIONAL


def test_life_guarding_loss_and_recovery(master, start_node):
    start_node(NODE)
    master.write_u16(NODE, 0x1017, 0, 0)
    master.write_u16(NODE, 0x100C, 0, 200)  # guard time 200 ms
    master.write_u8(NODE, 0x100D, 0, 3)     # node life time 600 ms
    master.nmt_start(NODE)
    for _ in range(8):                      # guarded every 200 ms: no event
        assert guard(master) is not None
        time.sleep(0.2)
    assert master.collect(0.05, lambda m: m.arbitration_id == 0x80 + NODE) == []
    # The master stops guarding.
    t0 = time.monotonic()
    emcy = master.wait_emcy(NODE, timeout=3.0)
    assert emcy is not None and emcy.error_code == 0x8130, emcy
    assert emcy.error_register & 0x10, "communication error bit"
    assert time.monotonic() - t0 > 0.3, "not before the node life time"
    assert master.read_u8(NODE, 0x1001) & 0x10, "error register: communication error"
    # 0x1029 sub 1 = 0: an operational node goes pre-operational. The next request ends the
    # event: the communication bit of the error register clears (the axes' own EMCYs for the
    # lost master, the device's policy, are theirs to clear).
    assert guard(master) & 0x7F == STATE_PREOPERATIONAL
    assert master.read_u8(NODE, 0x1001) & 0x10 == 0
    assert guard(master) is not None  # still within the node life time
