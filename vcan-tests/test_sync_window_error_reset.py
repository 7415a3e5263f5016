"""The synchronous window 0x1007 and the EMCY error reset on vcan: real SYNC frames whose
kernel arrival time the node measures the window from, and EMCY frames as CiA 301
7.2.7.3.1 gives them (code LE, error register, 5 manufacturer bytes)."""

import struct
import time

from test_node_pdo import NODE, RPDO1, TPDO1, USER_REGISTER_1, USER_REGISTER_2, frames, go_operational, remap

EMCY = 0x80 + NODE
RESET = bytes(8)  # EMCY 0x0000, error register 0, no manufacturer bytes


def test_sync_window(master, start_node):
    start_node(NODE)
    remap(master, 0x1800, [USER_REGISTER_1], 1)
    remap(master, 0x1400, [USER_REGISTER_2], 1)
    master.write_u32(NODE, 0x2F00, 1, 0x11223344)
    go_operational(master)
    master.flush()
    master.sync()  # no window: the TPDO of this SYNC
    got = master.wait_for(lambda m: m.arbitration_id == TPDO1, timeout=1.0)
    assert got is not None and bytes(got.data) == struct.pack("<I", 0x11223344)

    # 1 us: every SYNC is handled later than that after it reached the interface, so no
    # TPDO is sent, and RPDO data after the SYNC is discarded.
    master.write_u32(NODE, 0x1007, 0, 1)
    master.flush()
    for _ in range(3):
        master.sync()
        time.sleep(0.1)
    master.send(RPDO1, struct.pack("<I", 0xAAAA0001))
    time.sleep(0.1)
    master.sync()
    assert frames(master, TPDO1, 0.4) == []
    assert master.read_u32(NODE, 0x2F00, 2) == 0

    # 0.5 s: within it again.
    master.write_u32(NODE, 0x1007, 0, 500_000)
    master.flush()
    master.sync()
    assert master.wait_for(lambda m: m.arbitration_id == TPDO1, timeout=1.0) is not None
    master.send(RPDO1, struct.pack("<I", 0xAAAA0002))
    time.sleep(0.05)
    master.sync()
    time.sleep(0.1)
    assert master.read_u32(NODE, 0x2F00, 2) == 0xAAAA0002


def test_error_reset_after_rpdo_length_and_heartbeat_loss(master, start_node):
    start_node(NODE)
    remap(master, 0x1400, [USER_REGISTER_2], 254)
    go_operational(master)
    master.flush()
    master.send(RPDO1, b"\x01\x02")  # 2 bytes for a 4-byte mapping
    e = master.wait_for(lambda m: m.arbitration_id == EMCY, timeout=1.5)
    assert e is not None and bytes(e.data) == bytes([0x10, 0x82, 0x11, RPDO1 & 0xFF, RPDO1 >> 8, 2, 0, 0]), e
    master.send(RPDO1, struct.pack("<I", 7))  # the right length: the condition ends
    e = master.wait_for(lambda m: m.arbitration_id == EMCY, timeout=1.5)
    assert e is not None and bytes(e.data) == RESET, e
    assert master.read_u8(NODE, 0x1001, 0) == 0
    assert master.read_u32(NODE, 0x1003, 1) & 0xFFFF == 0x8210  # the error, not the reset

    # A watched node that is not the master (0x2F11 = 1): its loss is EMCY 0x8130 only.
    master.write_u8(NODE, 0x2F11, 0, 1)
    master.write_u32(NODE, 0x1016, 1, (0x30 << 16) | 200)
    for _ in range(3):
        master.send(0x730, b"\x05")
        time.sleep(0.1)
    master.flush()
    e = master.wait_for(lambda m: m.arbitration_id == EMCY, timeout=2.0)
    assert e is not None and bytes(e.data) == bytes([0x30, 0x81, 0x11, 0x30, 0, 0, 0, 0]), e
    master.send(0x730, b"\x05")
    e = master.wait_for(lambda m: m.arbitration_id == EMCY, timeout=1.5)
    assert e is not None and bytes(e.data) == RESET, e
    assert master.read_u8(NODE, 0x1001, 0) == 0
