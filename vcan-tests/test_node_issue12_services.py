"""Self-start (0x1F80), TIME (0x1012, 0x2F12) and a duplicate node-ID on vcan, with real
processes and frames written from the standards (CiA 301 TIME_OF_DAY, CiA 302-2 NMT
startup, the EMCY layout of CiA 301 7.2.7.3.1)."""

import datetime
import struct
import time

from lss_master import MODE_WAITING, LssMaster
from conftest import open_bus

EPOCH_1984 = datetime.datetime(1984, 1, 1, tzinfo=datetime.timezone.utc)


def config(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def give_another_node_id(master, node, serial, new_id):
    """The one node without a node-ID (it gave its own up) is found by a CiA 305 fast scan
    and given `new_id`; it boots with it."""
    bus = open_bus()
    try:
        lss = LssMaster(bus)
        assert lss.identify_non_configured() == 1
        addr = lss.fast_scan()
        assert addr is not None and addr.serial_number == serial
        assert lss.configure_node_id(new_id) == 0
        master.flush()
        lss.switch_state_global(MODE_WAITING)
    finally:
        bus.shutdown()
    assert master.wait_bootup(new_id, timeout=5.0) is not None, node.log()


def test_self_start_enters_operational_after_boot_up(master, start_node, tmp_path):
    node_id = 0x21
    start_node(node_id, ["--config", config(tmp_path, "self.toml", "self_start = true\n")])
    # Boot-up {00}, then the state changes confirmed at once: {7F} pre-operational, {05}.
    hb = master.wait_for(lambda m: m.arbitration_id == 0x700 + node_id and bytes(m.data) == b"\x05", 2.0)
    assert hb is not None, "no operational heartbeat after the boot-up"
    assert master.read_u32(node_id, 0x1F80, 0) == 0


def test_time_consumed_and_kept(master, start_node):
    node_id = 0x22
    start_node(node_id)
    assert master.read_u8(node_id, 0x2F12, 4) == 0
    # 2024-06-15 12:34:56.789 UTC: 45,296,789 ms after midnight, day 14776 since 1984.
    master.send(0x100, struct.pack("<IH", 45_296_789, 14776))
    sent = time.monotonic()
    time.sleep(0.3)
    assert master.read_u8(node_id, 0x2F12, 4) == 1
    assert master.read_u16(node_id, 0x2F12, 2) == 14776
    ms = master.read_u32(node_id, 0x2F12, 1)
    elapsed_ms = (time.monotonic() - sent) * 1000
    assert 45_296_789 + 250 <= ms <= 45_296_789 + elapsed_ms + 50, (ms, elapsed_ms)


def test_time_produced_from_the_wall_clock(master, start_node, tmp_path):
    node_id = 0x23
    cfg = config(tmp_path, "time.toml", '[defaults]\n"1012" = 0x40000100\n"2F12:5" = 200\n')
    start_node(node_id, ["--config", cfg])
    stamps = master.collect(1.1, lambda m: m.arbitration_id == 0x100)
    assert 4 <= len(stamps) <= 7, len(stamps)  # every 200 ms
    now = datetime.datetime.now(datetime.timezone.utc)
    for m in stamps:
        assert m.dlc == 6
        raw, days = struct.unpack("<IH", bytes(m.data))
        assert raw >> 28 == 0  # the 4 reserved bits
        stamp = EPOCH_1984 + datetime.timedelta(days=days, milliseconds=raw)
        assert abs((now - stamp).total_seconds()) < 3.0, stamp


def test_a_second_node_with_the_same_id_yields_it(master, start_node):
    node_id = 0x24
    hb_cob = 0x700 + node_id
    start_node(node_id, ["--serial-number", "0x11"])
    time.sleep(2.5)  # past its claim period: it keeps the id
    master.flush()
    second = start_node(node_id, ["--serial-number", "0x12"])
    emcys = master.collect(2.0, lambda m: m.arbitration_id == 0x80 + node_id)
    data = sorted(bytes(m.data) for m in emcys)
    # 0x8100, register 0x11, the heartbeat COB-ID heard (LE), 0 kept / 1 yielded.
    kept = bytes([0x00, 0x81, 0x11, hb_cob & 0xFF, hb_cob >> 8, 0, 0, 0])
    yielded = bytes([0x00, 0x81, 0x11, hb_cob & 0xFF, hb_cob >> 8, 1, 0, 0])
    assert kept in data and yielded in data, [d.hex() for d in data]
    assert "already used by another device" in second.log()

    # The one that yielded waits for LSS; a master gives it 0x25.
    give_another_node_id(master, second, 0x12, 0x25)
    assert master.read_u32(0x25, 0x1018, 4) == 0x12
    assert master.read_u32(node_id, 0x1018, 4) == 0x11


def test_a_node_that_listens_before_boot_up_refuses_a_node_id_in_use(master, start_node, tmp_path):
    node_id = 0x26
    hb_cob = 0x700 + node_id
    # The device that has the node-ID: heartbeat every 100 ms (0x1017).
    start_node(node_id, ["--serial-number", "0x21",
                         "--config", config(tmp_path, "hb.toml", '[defaults]\n"1017" = 100\n')])
    master.flush()
    second = start_node(node_id, ["--serial-number", "0x22", "--boot-listen-ms", "400"], wait_bootup=False)
    frames = master.collect(1.5, lambda m: m.arbitration_id in (hb_cob, 0x80 + node_id, 0x580 + node_id))
    # Only the first device's heartbeats (state 0x7F, pre-operational): no boot-up {00} and
    # no EMCY from the second, which never sent a frame with the node-ID.
    assert frames and all(m.arbitration_id == hb_cob and bytes(m.data) == b"\x7f" for m in frames), \
        [(hex(m.arbitration_id), bytes(m.data).hex()) for m in frames]
    assert second.alive
    assert "heard before boot-up" in second.log(), second.log()

    give_another_node_id(master, second, 0x22, 0x27)
    assert master.read_u32(0x27, 0x1018, 4) == 0x22


def test_a_node_that_listens_and_hears_nobody_boots_after_the_listening(master, start_node):
    started = time.monotonic()
    node = start_node(0x28, ["--boot-listen-ms", "300"])
    # The boot-up cannot come before the listening ended (a lower bound only: UML's clock).
    assert time.monotonic() - started >= 0.3
    assert bytes(node.bootup.data) == b"\x00"
    assert master.read_u32(0x28, 0x1000, 0) is not None
