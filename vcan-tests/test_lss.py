"""stepnode's LSS slave (CiA 305) on vcan, driven by the independent master in
lss_master.py: a node started without a node-ID is silent until configured; configure
node-ID, store configuration, reboot and the stored id is the one it boots with; inquire
identity and node-ID; requests back to back each answered; and fast scan of three
otherwise identical nodes (they differ only in their serial numbers) gives each its id,
after which each boots and answers SDO on it."""

import pytest

from canopen_master import STATE_PREOPERATIONAL
from conftest import BOOT_TIMEOUT, open_bus
from lss_master import (CS_INQUIRE_NODE_ID, CS_INQUIRE_PRODUCT, CS_INQUIRE_REVISION, CS_INQUIRE_SERIAL,
                        CS_INQUIRE_VENDOR, COB_SLAVE_TO_MASTER, MODE_WAITING, LssAddress, LssMaster)

# The identity every stepnode has in 0x1018 (README "LSS"); only the serial number is set.
VENDOR, PRODUCT, REVISION = 0x00000000, 0x53544550, 0x00010000
NODE = 0x2C


def address(serial):
    return LssAddress(VENDOR, PRODUCT, REVISION, serial)


@pytest.fixture
def lss():
    bus = open_bus()
    yield LssMaster(bus)
    bus.shutdown()


def start_unconfigured(start_node, serial, state_dir):
    return start_node("none", ["--serial-number", hex(serial)], state_dir=state_dir, wait_bootup=False)


def wait_unconfigured(lss, count, timeout=BOOT_TIMEOUT):
    """Asks 'identify non-configured remote slave' until `count` slaves answer (the
    processes have opened their sockets); returns how many did."""
    import time
    deadline = time.monotonic() + timeout
    n = 0
    while time.monotonic() < deadline:
        n = lss.identify_non_configured()
        if n >= count:
            return n
    return n


def test_configure_store_reboot_inquire(master, lss, start_node, tmp_path):
    serial = 0x5EED0001
    state = tmp_path / "lss-state"
    node = start_unconfigured(start_node, serial, state)
    assert wait_unconfigured(lss, 1) == 1, node.log()
    # Without a node-ID: no boot-up, no heartbeat (CiA 305: it stays in NMT initialisation).
    assert master.collect(1.2, lambda m: 0x700 <= m.arbitration_id <= 0x77F) == []

    assert lss.switch_state_selective(address(serial))
    assert lss.inquire_node_id() == 0xFF
    assert lss.configure_node_id(0) == 1        # out of range
    assert lss.configure_node_id(128) == 1
    assert lss.configure_node_id(NODE) == 0
    assert lss.configure_bit_timing(3) == 0     # 250 kbit/s
    assert lss.configure_bit_timing(5) == 1     # reserved index
    assert lss.store_configuration() == 0
    assert (state / f"lss-{VENDOR:08x}-{PRODUCT:08x}-{serial:08x}.conf").is_file()
    master.flush()
    lss.switch_state_global(MODE_WAITING)       # now it boots with the new id
    boot = master.wait_bootup(NODE, timeout=5.0)
    assert boot is not None and bytes(boot.data) == b"\x00", node.log()
    assert master.read_u32(NODE, 0x1018, 4) == serial
    assert master.read_u32(NODE, 0x1200, 2) == 0x580 + NODE
    node.terminate()

    # Reboot, no id on the command line: the LSS-stored one.
    master.flush()
    node = start_unconfigured(start_node, serial, state)
    assert master.wait_bootup(NODE, timeout=BOOT_TIMEOUT) is not None, node.log()
    assert "stored bit timing 250 kbit/s" in node.log()
    # Compared with the interface's (rtnetlink): vcan has no bit rate, so it is not applied.
    assert "cannot be applied: vcan0 is a virtual CAN interface" in node.log(), node.log()
    assert lss.identify_non_configured() == 0
    assert lss.switch_state_selective(address(serial))
    assert lss.inquire_address() == address(serial)
    assert lss.inquire_node_id() == NODE

    # Requests back to back, no waiting between them: each is answered, in order.
    lss.drain()
    master.flush()
    for cs in (CS_INQUIRE_VENDOR, CS_INQUIRE_PRODUCT, CS_INQUIRE_REVISION, CS_INQUIRE_SERIAL, CS_INQUIRE_NODE_ID):
        lss.send(cs)
    answers = master.collect(1.0, lambda m: m.arbitration_id == COB_SLAVE_TO_MASTER)
    assert [bytes(m.data) for m in answers] == [
        bytes([CS_INQUIRE_VENDOR]) + VENDOR.to_bytes(4, "little") + bytes(3),
        bytes([CS_INQUIRE_PRODUCT]) + PRODUCT.to_bytes(4, "little") + bytes(3),
        bytes([CS_INQUIRE_REVISION]) + REVISION.to_bytes(4, "little") + bytes(3),
        bytes([CS_INQUIRE_SERIAL]) + serial.to_bytes(4, "little") + bytes(3),
        bytes([CS_INQUIRE_NODE_ID, NODE]) + bytes(6),
    ]
    lss.switch_state_global(MODE_WAITING)

    # Identify remote slave: the ranges include their bounds.
    assert lss.identify_remote_slave(VENDOR, PRODUCT, 0, 0xFFFFFFFF, serial, serial)
    assert not lss.identify_remote_slave(VENDOR, PRODUCT, 0, 0xFFFFFFFF, serial + 1, 0xFFFFFFFF)
    node.terminate()

    # The command line's id wins over the stored one.
    start_node(0x2D, ["--serial-number", hex(serial)], state_dir=state)


def test_fast_scan_gives_three_identical_nodes_their_ids(master, lss, start_node, tmp_path):
    serials = [0x5CA10001, 0x5CA00002, 0x5CA00001]
    state = tmp_path / "shared-state"  # one directory: the LSS files are per identity
    nodes = [start_unconfigured(start_node, s, state) for s in serials]
    assert wait_unconfigured(lss, 3) == 3, [n.log() for n in nodes]

    found = {}
    for node_id in (0x31, 0x32, 0x33):
        addr = lss.fast_scan()
        assert addr is not None, f"fast scan found nobody with {len(found)} configured"
        assert addr.parts()[:3] == (VENDOR, PRODUCT, REVISION)
        assert addr.serial_number in serials and addr.serial_number not in found.values()
        assert lss.configure_node_id(node_id) == 0
        master.flush()
        lss.switch_state_global(MODE_WAITING)
        assert master.wait_bootup(node_id, timeout=5.0) is not None, f"node with serial {addr.serial_number:#x}"
        found[node_id] = addr.serial_number
    # The scan takes the lowest address first: a 0 bit is tried before a 1.
    assert list(found.values()) == sorted(serials)
    assert lss.fast_scan() is None
    assert lss.identify_non_configured() == 0
    for node_id, serial in found.items():
        assert master.read_u32(node_id, 0x1018, 4) == serial
        assert master.wait_heartbeat(node_id, timeout=2.5) == STATE_PREOPERATIONAL
