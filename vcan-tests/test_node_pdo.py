"""stepnode's PDOs on vcan: a TPDO remapped over SDO by the CiA 301 procedure and sent on
SYNC, the same TPDO event-driven (type 254), an RPDO mapped to a user register that is
applied in operational only and fires a TPDO mapping the same register, and an RPDO shorter
than its mapping (EMCY 0x8210, value not applied)."""

import struct
import time

from canopen_master import STATE_OPERATIONAL, STATE_PREOPERATIONAL

NODE = 23
TPDO1, TPDO2, RPDO1 = 0x180 + NODE, 0x280 + NODE, 0x200 + NODE
USER_REGISTER_1 = 0x2F000120  # 0x2F00:1, 32 bits
USER_REGISTER_2 = 0x2F000220
ERROR_REGISTER = 0x10010008   # 0x1001:0, 8 bits


def remap(master, comm, words, transmission_type):
    """The CiA 301 7.5.2.36 procedure: invalidate (bit 31 of sub 1), disable the mapping
    (sub 0 = 0), write the entries, enable (sub 0 = count), transmission type, validate."""
    mapping = comm + 0x200
    cob = master.read_u32(NODE, comm, 1) & 0x7FF
    master.write_u32(NODE, comm, 1, 0x80000000 | cob)
    master.write_u8(NODE, mapping, 0, 0)
    for i, word in enumerate(words, 1):
        master.write_u32(NODE, mapping, i, word)
    master.write_u8(NODE, mapping, 0, len(words))
    master.write_u8(NODE, comm, 2, transmission_type)
    master.write_u32(NODE, comm, 1, cob)
    assert master.read_u8(NODE, mapping, 0) == len(words)
    assert [master.read_u32(NODE, mapping, i) for i in range(1, len(words) + 1)] == list(words)
    assert master.read_u32(NODE, comm, 1) & 0x80000000 == 0


def go_operational(master):
    master.nmt_start(NODE)
    assert master.wait_heartbeat(NODE, timeout=2.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL


def frames(master, cob, duration):
    return master.collect(duration, lambda m: m.arbitration_id == cob)


def test_tpdo_remapped_and_sent_once_per_sync(master, start_node):
    start_node(NODE)
    remap(master, 0x1800, [USER_REGISTER_1, ERROR_REGISTER], 1)
    master.write_u32(NODE, 0x2F00, 1, 0x11223344)
    go_operational(master)
    master.flush()
    # Nothing without SYNC (transmission type 1 is synchronous only).
    assert frames(master, TPDO1, 0.8) == []
    error_register = master.read_u8(NODE, 0x1001)
    for k in range(5):
        master.flush()
        master.sync()
        got = master.wait_for(lambda m: m.arbitration_id == TPDO1, timeout=1.0)
        assert got is not None, f"no TPDO1 after SYNC {k + 1}"
        assert bytes(got.data) == struct.pack("<IB", 0x11223344, error_register), got
        assert frames(master, TPDO1, 0.25) == [], f"more than one TPDO1 for SYNC {k + 1}"
    # A new value goes out with the next SYNC, and not before it.
    master.write_u32(NODE, 0x2F00, 1, 0xA5A5F00D)
    master.flush()
    assert frames(master, TPDO1, 0.5) == []
    master.sync()
    got = master.wait_for(lambda m: m.arbitration_id == TPDO1, timeout=1.0)
    assert got is not None and bytes(got.data) == struct.pack("<IB", 0xA5A5F00D, error_register), got
    # Pre-operational: no PDOs even on SYNC.
    master.nmt_preop(NODE)
    assert master.wait_heartbeat(NODE, timeout=2.0, state=STATE_PREOPERATIONAL) == STATE_PREOPERATIONAL
    master.flush()
    master.sync()
    assert frames(master, TPDO1, 0.8) == []


def test_tpdo_every_third_sync(master, start_node):
    start_node(NODE)
    remap(master, 0x1800, [USER_REGISTER_1], 3)
    master.write_u32(NODE, 0x2F00, 1, 3)
    go_operational(master)
    master.flush()
    seen = []
    for k in range(1, 10):
        master.sync()
        seen.append(len(frames(master, TPDO1, 0.3)))
    assert sum(seen) == 3 and seen.count(1) == 3, f"TPDOs per SYNC: {seen}"
    assert [i for i, n in enumerate(seen) if n] in ([0, 3, 6], [1, 4, 7], [2, 5, 8]), seen


def test_tpdo_on_change_type_254(master, start_node):
    start_node(NODE)
    remap(master, 0x1800, [USER_REGISTER_1, ERROR_REGISTER], 254)
    master.write_u32(NODE, 0x2F00, 1, 1)
    master.flush()
    go_operational(master)
    # Entering operational sends the current values once.
    first = master.wait_for(lambda m: m.arbitration_id == TPDO1, timeout=1.0)
    assert first is not None and bytes(first.data) == struct.pack("<IB", 1, 0), first
    assert frames(master, TPDO1, 1.0) == [], "TPDO1 repeats without a change (no event timer set)"
    for value in (0xCAFEF00D, 0x00000000, 0x7FFFFFFF):
        master.flush()
        t0 = time.time()
        master.write_u32(NODE, 0x2F00, 1, value)
        got = master.wait_for(lambda m: m.arbitration_id == TPDO1, timeout=1.0)
        assert got is not None, f"no TPDO1 after 0x2F00:1 = 0x{value:08X}"
        assert bytes(got.data) == struct.pack("<IB", value, 0)
        assert got.timestamp - t0 < 0.8, f"TPDO1 {got.timestamp - t0:.3f} s after the write"
    # Writing the same value again is no change: no TPDO.
    master.flush()
    master.write_u32(NODE, 0x2F00, 1, 0x7FFFFFFF)
    assert frames(master, TPDO1, 0.8) == []
    # Event timer (0x1800:5, ms): the TPDO repeats without a change.
    master.write_u16(NODE, 0x1800, 5, 200)
    master.flush()
    repeats = frames(master, TPDO1, 1.6)
    assert 5 <= len(repeats) <= 10, f"{len(repeats)} TPDOs in 1.6 s with a 200 ms event timer"


def test_rpdo_applied_in_operational_and_fires_tpdo(master, start_node):
    start_node(NODE)
    remap(master, 0x1400, [USER_REGISTER_2], 254)
    remap(master, 0x1800, [USER_REGISTER_1], 254)
    remap(master, 0x1801, [USER_REGISTER_2], 254)
    # Pre-operational: an RPDO is not processed.
    master.send(RPDO1, struct.pack("<I", 0x0BADBAD0))
    time.sleep(0.3)
    assert master.read_u32(NODE, 0x2F00, 2) == 0
    go_operational(master)
    master.flush()
    time.sleep(0.3)  # the start-up transmissions of both TPDOs
    master.flush()
    master.send(RPDO1, struct.pack("<I", 0x12345678))
    got = master.wait_for(lambda m: m.arbitration_id == TPDO2, timeout=1.0)
    assert got is not None and bytes(got.data) == struct.pack("<I", 0x12345678), got
    assert master.read_u32(NODE, 0x2F00, 2) == 0x12345678
    assert frames(master, TPDO1, 0.3) == [], "TPDO1 (0x2F00:1, unchanged) was sent"
    # Shorter than the mapping: not applied, EMCY 0x8210 (PDO not processed due to length).
    master.flush()
    master.send(RPDO1, b"\x01\x02")
    emcy = master.wait_emcy(NODE, timeout=1.5)
    assert emcy is not None, "no EMCY for a 2-byte RPDO mapped to 4 bytes"
    assert emcy.error_code == 0x8210, hex(emcy.error_code)
    assert emcy.error_register & 0x11 == 0x11, hex(emcy.error_register)  # generic + communication
    assert master.read_u32(NODE, 0x2F00, 2) == 0x12345678
    assert frames(master, TPDO2, 0.3) == []
    assert master.read_u32(NODE, 0x1003, 1) & 0xFFFF == 0x8210
    # A correct RPDO is applied again afterwards.
    master.send(RPDO1, struct.pack("<I", 0xFEEDC0DE))
    got = master.wait_for(lambda m: m.arbitration_id == TPDO2, timeout=1.0)
    assert got is not None and bytes(got.data) == struct.pack("<I", 0xFEEDC0DE), got
    assert master.read_u32(NODE, 0x2F00, 2) == 0xFEEDC0DE
