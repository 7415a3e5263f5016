"""A stepnode configured with a subset of its profiles (config file `profiles = [...]`):
an HP 44714A-only node and a Horner-only node each serve an EDS with only their objects
(0x1021 equals `--print-eds` with the same config), answer CiA 301 abort 0x06020000 for the
other profile's objects, and are driven over the bus by SDO alone."""

import struct
import subprocess
import time

from canopen_master import ABORT_NO_OBJECT, abort_of

NODE = 24


def config(tmp_path, profiles):
    path = tmp_path / "node.toml"
    path.write_text("axes = 1\nprofiles = [" + ", ".join(f'"{p}"' for p in profiles) + "]\n")
    return path


def manufacturer_objects(eds: bytes):
    """The [XXXX] sections of the EDS's manufacturer area (0x2000-0x5FFF)."""
    out = set()
    for line in eds.decode().splitlines():
        if line.startswith("[") and line.endswith("]") and len(line) == 6:
            try:
                index = int(line[1:5], 16)
            except ValueError:
                continue
            if 0x2000 <= index <= 0x5FFF:
                out.add(index)
    return out


def served_eds_matches_print_eds(master, stepnode_bin, path):
    eds = master.sdo_block_upload(NODE, 0x1021, 0)
    printed = subprocess.run([str(stepnode_bin), "--print-eds", "--config", str(path)], capture_output=True,
                             check=True, timeout=60).stdout
    assert eds == printed, "0x1021 differs from stepnode --print-eds with the same config"
    return eds


def write_real(master, index, sub, value):
    master.sdo_download(NODE, index, sub, struct.pack("<d", value))


def test_an_hp_only_node_has_the_channels_and_moves_over_sdo(master, start_node, stepnode_bin, tmp_path):
    path = config(tmp_path, ["hp"])
    start_node(NODE, ["--config", path])
    objects = manufacturer_objects(served_eds_matches_print_eds(master, stepnode_bin, path))
    assert 0x2010 in objects and 0x2018 in objects  # PROFILE, DONE?
    assert not [i for i in objects if i < 0x2800 and (i & 0xFF) <= 0x0A], sorted(hex(i) for i in objects)
    assert 0x2F00 not in objects
    assert abort_of(lambda: master.read_u16(NODE, 0x2001)) == ABORT_NO_OBJECT
    assert abort_of(lambda: master.write_u16(NODE, 0x2000, 0, 1)) == ABORT_NO_OBJECT
    # HP manual Figure 3-3: PROFILE FREQ 100 800 200 25E-6, PSCALE 0.1, MOVE 20 -> 200 pulses.
    for sub, value in ((2, 100.0), (3, 800.0), (4, 200.0), (5, 25e-6)):
        write_real(master, 0x2010, sub, value)
    master.write_u8(NODE, 0x2010, 6, 1)
    write_real(master, 0x2011, 0, 0.1)
    write_real(master, 0x2012, 1, 20.0)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and master.read_u8(NODE, 0x2018) != 0:
        time.sleep(0.1)
    assert master.read_u8(NODE, 0x2018) == 0, "DONE? never 0"
    assert master.read_i32(NODE, 0x5003) == 200


def test_a_horner_only_node_has_the_registers_and_moves_over_sdo(master, start_node, stepnode_bin, tmp_path):
    path = config(tmp_path, ["horner"])
    start_node(NODE, ["--config", path])
    objects = manufacturer_objects(served_eds_matches_print_eds(master, stepnode_bin, path))
    assert 0x2000 in objects and 0x2001 in objects
    assert not [i for i in objects if i < 0x2800 and (i & 0xFF) >= 0x10], sorted(hex(i) for i in objects)
    assert abort_of(lambda: master.read_u8(NODE, 0x2018)) == ABORT_NO_OBJECT
    # Clear Errors, Set Position, Move Relative 500 (SPM30 chapter 3), by SDO.
    for bit, destination in ((1 << 13, None), (1 << 12, 0), (1 << 7, 500)):
        if destination is not None:
            master.write_i32(NODE, 0x2002, 0, destination)
        master.write_u16(NODE, 0x2000, 0, bit)
        master.write_u16(NODE, 0x2000, 0, 0)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and master.read_i32(NODE, 0x2005) != 500:
        time.sleep(0.1)
    assert master.read_i32(NODE, 0x2005) == 500
    assert master.read_i32(NODE, 0x5003) == 500
