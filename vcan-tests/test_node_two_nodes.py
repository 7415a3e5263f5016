"""Two stepnode processes with different node ids on one vcan bus: each answers only its
own SDO, NMT and PDO traffic on its own COB-IDs, and each keeps its own stored parameters
even when both share one state directory."""

import struct

from canopen_master import STATE_OPERATIONAL, STATE_PREOPERATIONAL

A, B = 5, 6
SAVE = 0x65766173


def test_each_node_has_its_own_cob_ids(master, start_node):
    start_node(A)
    start_node(B)
    for n in (A, B):
        assert master.read_u32(n, 0x1200, 1) == 0x600 + n
        assert master.read_u32(n, 0x1200, 2) == 0x580 + n
        assert master.read_u32(n, 0x1014) & 0x7FF == 0x80 + n
        for k, base in enumerate((0x180, 0x280, 0x380, 0x480)):
            assert master.read_u32(n, 0x1800 + k, 1) & 0x800007FF == base + n
        for k, base in enumerate((0x200, 0x300, 0x400, 0x500)):
            assert master.read_u32(n, 0x1400 + k, 1) & 0x800007FF == base + n


def test_sdo_to_one_node_is_answered_only_by_it(master, start_node):
    start_node(A)
    start_node(B)
    master.write_u32(A, 0x2F00, 1, 0xAAAA0005)
    master.write_u32(B, 0x2F00, 1, 0xBBBB0006)
    for node, other in ((A, B), (B, A)):
        master.flush()
        assert master.read_u32(node, 0x2F00, 1) == (0xAAAA0005 if node == A else 0xBBBB0006)
        assert master.sdo_upload(node, 0x1008, 0) == b"stepnode"          # segmented: 3 exchanges
        answers = master.collect(0.5, lambda m: 0x580 <= m.arbitration_id <= 0x5FF)
        assert answers == [], f"unexpected SDO responses after node {node}'s transfers: {answers}"
    # A request for a node that does not exist is answered by nobody.
    assert master.sdo_request(7, struct.pack("<BHB", 0x40, 0x1000, 0), timeout=0.8) is None
    assert master.collect(0.3, lambda m: 0x580 <= m.arbitration_id <= 0x5FF) == []


def test_addressed_nmt_and_pdos_stay_with_their_node(master, start_node):
    start_node(A)
    start_node(B)
    for n in (A, B):
        # TPDO1 of each node: user register 1, event-driven; RPDO1: user register 2.
        master.write_u32(n, 0x1800, 1, 0x80000180 + n)
        master.write_u8(n, 0x1A00, 0, 0)
        master.write_u32(n, 0x1A00, 1, 0x2F000220)
        master.write_u8(n, 0x1A00, 0, 1)
        master.write_u32(n, 0x1800, 1, 0x180 + n)
        master.write_u32(n, 0x1400, 1, 0x80000200 + n)
        master.write_u8(n, 0x1600, 0, 0)
        master.write_u32(n, 0x1600, 1, 0x2F000220)
        master.write_u8(n, 0x1600, 0, 1)
        master.write_u32(n, 0x1400, 1, 0x200 + n)
        master.write_u16(n, 0x1017, 0, 300)
    master.flush()
    master.nmt_start(A)
    assert master.wait_heartbeat(A, timeout=2.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    beats_b = master.collect(1.0, lambda m: m.arbitration_id == 0x700 + B)
    assert beats_b and all(bytes(m.data) == bytes([STATE_PREOPERATIONAL]) for m in beats_b), beats_b
    master.nmt_start(B)
    assert master.wait_heartbeat(B, timeout=2.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    master.flush()
    # RPDO for A: only A applies it and only A's TPDO answers.
    master.send(0x200 + A, struct.pack("<I", 0x0A0A0A0A))
    got = master.collect(0.8, lambda m: m.arbitration_id in (0x180 + A, 0x180 + B))
    assert [(m.arbitration_id, bytes(m.data)) for m in got] == [(0x180 + A, struct.pack("<I", 0x0A0A0A0A))], got
    assert master.read_u32(A, 0x2F00, 2) == 0x0A0A0A0A
    assert master.read_u32(B, 0x2F00, 2) == 0
    master.send(0x200 + B, struct.pack("<I", 0x0B0B0B0B))
    got = master.collect(0.8, lambda m: m.arbitration_id in (0x180 + A, 0x180 + B))
    assert [(m.arbitration_id, bytes(m.data)) for m in got] == [(0x180 + B, struct.pack("<I", 0x0B0B0B0B))], got
    assert master.read_u32(A, 0x2F00, 2) == 0x0A0A0A0A
    # Reset of B alone: A stays operational and keeps its values.
    master.flush()
    master.nmt_reset_node(B)
    assert master.wait_bootup(B, timeout=2.0) is not None
    beats_a = master.collect(1.0, lambda m: m.arbitration_id == 0x700 + A)
    assert beats_a and all(bytes(m.data) == bytes([STATE_OPERATIONAL]) for m in beats_a), beats_a
    assert master.read_u32(A, 0x2F00, 2) == 0x0A0A0A0A
    assert master.read_u32(B, 0x2F00, 2) == 0


def test_stored_values_are_per_node_in_a_shared_state_dir(master, start_node, tmp_path):
    state = tmp_path / "shared"
    a = start_node(A, state_dir=state)
    b = start_node(B, state_dir=state)
    master.write_u16(A, 0x1017, 0, 555)
    master.write_u32(A, 0x2F00, 1, 0x5555)
    master.write_u16(B, 0x1017, 0, 666)
    master.write_u32(B, 0x2F00, 1, 0x6666)
    master.write_u32(A, 0x1010, 1, SAVE)
    master.write_u32(B, 0x1010, 1, SAVE)
    assert sorted(p.name for p in state.iterdir()) == [f"node-{A}.params", f"node-{B}.params"]
    a.kill()
    b.kill()
    start_node(A, state_dir=state)
    start_node(B, state_dir=state)
    assert (master.read_u16(A, 0x1017), master.read_u32(A, 0x2F00, 1)) == (555, 0x5555)
    assert (master.read_u16(B, 0x1017), master.read_u32(B, 0x2F00, 1)) == (666, 0x6666)
