"""stepnode's SDO server on vcan: expedited, segmented and block transfers in both
directions, the node's own EDS served from 0x1021, the 4096-byte user DOMAIN 0x2F01, and
every abort code a master meets when it asks for something wrong (CiA 301 table 22)."""

import os
import struct
import subprocess
import time


from canopen_master import (ABORT_DATA_STORE, ABORT_DATA_STORE_STATE, ABORT_NO_OBJECT, ABORT_NO_SUBINDEX,
                            ABORT_NOT_MAPPABLE, ABORT_PDO_LENGTH, ABORT_READ_ONLY, ABORT_TYPE_LENGTH_HIGH,
                            ABORT_TYPE_LENGTH_LOW, ABORT_VALUE_HIGH, ABORT_VALUE_RANGE, SdoAbort, abort_of, crc16_ccitt)

NODE = 22
PRODUCT_CODE = 0x53544550  # "STEP"


# ---------------------------------------------------------------- expedited


def test_expedited_upload_of_heartbeat_time_and_identity(master, start_node):
    start_node(NODE)
    # The raw answer: scs=2, e=1, s=1, n=2 (two bytes), multiplexer echoed, value 1000.
    resp = master.sdo_request(NODE, struct.pack("<BHB", 0x40, 0x1017, 0))
    assert resp == bytes([0x4B, 0x17, 0x10, 0x00]) + struct.pack("<H", 1000) + b"\0\0", resp
    assert master.read_u16(NODE, 0x1017) == 1000
    assert master.read_u8(NODE, 0x1018, 0) == 4
    assert master.read_u32(NODE, 0x1018, 1) == 0               # no CiA vendor id
    assert master.read_u32(NODE, 0x1018, 2) == PRODUCT_CODE
    assert master.read_u32(NODE, 0x1018, 3) == 0x00010000      # revision 1.0
    assert master.read_u32(NODE, 0x1018, 4) == 0               # serial number (default)
    # Expedited download and read back.
    master.write_u16(NODE, 0x1017, 0, 1234)
    assert master.read_u16(NODE, 0x1017) == 1234


def test_identity_and_defaults_from_the_config_file(master, start_node, tmp_path):
    config = tmp_path / "node.toml"
    config.write_text('serial_number = 4711\n[defaults]\n"1017" = 700\n"2F00:3" = 0x0BADF00D\n')
    start_node(NODE, ["--config", config])
    assert master.read_u32(NODE, 0x1018, 4) == 4711
    assert master.read_u16(NODE, 0x1017) == 700
    assert master.read_u32(NODE, 0x2F00, 3) == 0x0BADF00D


# ---------------------------------------------------------------- segmented / block


def test_segmented_upload_of_the_strings(master, start_node):
    start_node(NODE)
    # 0x1008 is 8 bytes: segmented, size indicated in the initiate response.
    resp = master.sdo_request(NODE, struct.pack("<BHB", 0x40, 0x1008, 0))
    assert resp[0] == 0x41 and resp[1:4] == b"\x08\x10\x00" and struct.unpack_from("<I", resp, 4)[0] == 8, resp
    master.sdo_request(NODE, struct.pack("<BHBI", 0x80, 0x1008, 0, 0x08000000), timeout=0.3)  # abort it
    assert master.sdo_upload(NODE, 0x1008, 0) == b"stepnode"
    assert master.sdo_upload(NODE, 0x1009, 0) == b"simulated machine"
    version = master.sdo_upload(NODE, 0x100A, 0).decode("ascii")
    assert version.count(".") == 2 and all(p.isdigit() for p in version.split(".")), version


def test_block_upload_of_the_eds_equals_print_eds(master, start_node, stepnode_bin):
    start_node(NODE)
    eds = master.sdo_block_upload(NODE, 0x1021, 0)
    printed = subprocess.run([str(stepnode_bin), "--print-eds"], capture_output=True, check=True, timeout=60).stdout
    assert len(eds) > 50_000, len(eds)
    assert eds.startswith(b"[FileInfo]"), eds[:40]
    assert eds == printed, "0x1021 differs from stepnode --print-eds"
    assert master.read_u8(NODE, 0x1022) == 0  # storage format: ASCII
    # Small blocks and a block size changed on every acknowledgement give the same bytes.
    assert master.sdo_block_upload(NODE, 0x1021, 0, blksize=5, next_blksize=lambda n: 1 + n % 127) == printed


def test_user_domain_round_trips_segmented_and_block(master, start_node):
    start_node(NODE)
    data = os.urandom(4096)
    master.sdo_download(NODE, 0x2F01, 0, data)                    # segmented download
    assert master.sdo_upload(NODE, 0x2F01, 0) == data             # segmented upload
    assert master.sdo_block_upload(NODE, 0x2F01, 0) == data       # block upload of the same
    data = os.urandom(4096)
    master.sdo_block_download(NODE, 0x2F01, 0, data)              # block download
    assert master.sdo_block_upload(NODE, 0x2F01, 0, blksize=7) == data
    assert master.sdo_upload(NODE, 0x2F01, 0) == data
    # A shorter value replaces the whole DOMAIN; sizes that end mid-segment are exact.
    for size in (1, 4, 5, 7, 8, 13, 889):
        data = os.urandom(size)
        master.sdo_block_download(NODE, 0x2F01, 0, data)
        assert master.sdo_upload(NODE, 0x2F01, 0) == data, size


def test_4097_bytes_are_refused_and_the_old_value_kept(master, start_node):
    start_node(NODE)
    kept = os.urandom(100)
    master.sdo_download(NODE, 0x2F01, 0, kept)
    assert abort_of(lambda: master.sdo_download(NODE, 0x2F01, 0, os.urandom(4097))) == ABORT_TYPE_LENGTH_HIGH
    assert abort_of(lambda: master.sdo_block_download(NODE, 0x2F01, 0, os.urandom(4097))) == ABORT_TYPE_LENGTH_HIGH
    assert master.sdo_upload(NODE, 0x2F01, 0) == kept


# ---------------------------------------------------------------- abort codes


def test_abort_codes_for_addressing_and_access(master, start_node):
    start_node(NODE)
    assert abort_of(lambda: master.sdo_upload(NODE, 0x1F00, 0)) == ABORT_NO_OBJECT
    assert abort_of(lambda: master.write_u32(NODE, 0x4321, 0, 1)) == ABORT_NO_OBJECT
    assert abort_of(lambda: master.sdo_upload(NODE, 0x1018, 5)) == ABORT_NO_SUBINDEX
    assert abort_of(lambda: master.write_u16(NODE, 0x1017, 1, 1)) == ABORT_NO_SUBINDEX
    assert abort_of(lambda: master.write_u32(NODE, 0x1000, 0, 1)) == ABORT_READ_ONLY
    assert abort_of(lambda: master.write_u32(NODE, 0x1018, 2, 1)) == ABORT_READ_ONLY
    assert master.read_u32(NODE, 0x1000) == 0 and master.read_u32(NODE, 0x1018, 2) == PRODUCT_CODE


def test_abort_codes_for_values(master, start_node):
    start_node(NODE)
    # U16 written with 4 bytes / 1 byte.
    assert abort_of(lambda: master.write_u32(NODE, 0x1017, 0, 250)) == ABORT_TYPE_LENGTH_HIGH
    assert abort_of(lambda: master.write_u8(NODE, 0x1017, 0, 250)) == ABORT_TYPE_LENGTH_LOW
    assert master.read_u16(NODE, 0x1017) == 1000
    # Heartbeat consumer entry: bits 24..31 are reserved.
    assert abort_of(lambda: master.write_u32(NODE, 0x1016, 1, 0x01000000 | (5 << 16) | 100)) == ABORT_VALUE_RANGE
    assert master.read_u32(NODE, 0x1016, 1) == 0
    # The error history count accepts only 0.
    assert abort_of(lambda: master.write_u8(NODE, 0x1003, 0, 1)) == ABORT_VALUE_RANGE
    # Store/restore signatures other than "save"/"load".
    assert abort_of(lambda: master.write_u32(NODE, 0x1010, 1, 0x12345678)) == ABORT_DATA_STORE
    assert abort_of(lambda: master.write_u32(NODE, 0x1011, 1, 0x65766173)) == ABORT_DATA_STORE
    # The node still answers normally.
    assert master.sdo_upload(NODE, 0x1008, 0) == b"stepnode"


def disable_tpdo1(master):
    cob = master.read_u32(NODE, 0x1800, 1)
    master.write_u32(NODE, 0x1800, 1, cob | 0x80000000)
    master.write_u8(NODE, 0x1A00, 0, 0)


def test_abort_codes_for_pdo_mapping(master, start_node):
    start_node(NODE)
    old = [master.read_u32(NODE, 0x1A00, i) for i in range(1, master.read_u8(NODE, 0x1A00, 0) + 1)]
    assert old, "TPDO1 has a default mapping"
    # Mapping while the PDO is valid (bit 31 of the COB-ID clear).
    assert abort_of(lambda: master.write_u32(NODE, 0x1A00, 1, 0x2F000120)) == ABORT_DATA_STORE_STATE
    assert abort_of(lambda: master.write_u8(NODE, 0x1A00, 0, 0)) == ABORT_DATA_STORE_STATE
    assert [master.read_u32(NODE, 0x1A00, i) for i in range(1, len(old) + 1)] == old
    disable_tpdo1(master)
    # An object that is not PDO-mappable: the device name (VISIBLE_STRING, 64 bits).
    assert abort_of(lambda: master.write_u32(NODE, 0x1A00, 1, 0x10080040)) == ABORT_NOT_MAPPABLE
    # More than 8 entries: count 9.
    assert abort_of(lambda: master.write_u8(NODE, 0x1A00, 0, 9)) == ABORT_VALUE_HIGH
    # More than 64 bits: three 32-bit registers. CiA 301 lets the device refuse either the
    # entry or the count; one of them must be refused with 0x06040042.
    codes = []
    for call in (lambda: master.write_u32(NODE, 0x1A00, 1, 0x2F000120),
                 lambda: master.write_u32(NODE, 0x1A00, 2, 0x2F000220),
                 lambda: master.write_u32(NODE, 0x1A00, 3, 0x2F000320),
                 lambda: master.write_u8(NODE, 0x1A00, 0, 3)):
        try:
            call()
            codes.append(None)
        except SdoAbort as e:
            codes.append(e.code)
    assert ABORT_PDO_LENGTH in codes, [None if c is None else hex(c) for c in codes]
    assert master.read_u8(NODE, 0x1A00, 0) == 0, "a 96-bit mapping was enabled"
    # Two registers (64 bits) fit.
    master.write_u8(NODE, 0x1A00, 0, 2)
    assert master.read_u8(NODE, 0x1A00, 0) == 2
    # Nothing else broke: the node answers.
    assert master.read_u32(NODE, 0x1018, 2) == PRODUCT_CODE


# ---------------------------------------------------------------- protocol errors


def abort_frame(resp):
    """(index, sub, code) of a raw abort response, else None."""
    if resp is None or resp[0] != 0x80:
        return None
    return struct.unpack_from("<HBI", resp, 1)


def test_small_objects_by_block_and_protocol_switch(master, start_node):
    start_node(NODE)
    assert master.sdo_block_upload(NODE, 0x1017, 0) == struct.pack("<H", 1000)
    # With a protocol switch threshold the server may answer as a normal upload.
    assert master.sdo_block_upload(NODE, 0x1017, 0, pst=8) == struct.pack("<H", 1000)
    assert master.sdo_block_upload(NODE, 0x1008, 0, pst=21) == b"stepnode"
    master.sdo_block_download(NODE, 0x1017, 0, struct.pack("<H", 321))
    assert master.read_u16(NODE, 0x1017) == 321
    # Segmented download without the size indicated.
    data = os.urandom(50)
    master.sdo_download(NODE, 0x2F01, 0, data, size_indicated=False)
    assert master.sdo_upload(NODE, 0x2F01, 0) == data


def test_unknown_command_specifier_and_wrong_toggle_are_aborted(master, start_node):
    start_node(NODE)
    # ccs=7 is not a client command.
    resp = master.sdo_request(NODE, bytes([0xE0, 0x17, 0x10, 0]))
    assert abort_frame(resp) is not None and abort_frame(resp)[2] == 0x05040001, resp
    # Segmented download whose first segment has toggle 1.
    resp = master.sdo_request(NODE, struct.pack("<BHBI", 0x21, 0x2F01, 0, 14))
    assert resp[0] == 0x60, resp
    resp = master.sdo_request(NODE, bytes([0x10]) + b"abcdefg")
    assert abort_frame(resp) is not None and abort_frame(resp)[2] == 0x05030000, resp
    assert master.sdo_upload(NODE, 0x2F01, 0) == b"", "an aborted download changed the value"


def test_stalled_transfer_times_out_and_the_server_recovers(master, start_node):
    start_node(NODE)
    master.sdo_download(NODE, 0x2F01, 0, b"kept")
    resp = master.sdo_request(NODE, struct.pack("<BHBI", 0x21, 0x2F01, 0, 21))
    assert resp[0] == 0x60, resp
    resp = master.sdo_request(NODE, bytes([0x00]) + b"1234567")   # one segment of three
    assert resp[0] == 0x20, resp
    # Silence: the server gives up with 0x05040000 (its timeout is 1 s).
    t0 = time.monotonic()
    msg = master.wait_for(lambda m: m.arbitration_id == 0x580 + NODE, timeout=4.0)
    assert msg is not None, "the server never aborted the stalled download"
    assert abort_frame(bytes(msg.data)) == (0x2F01, 0, 0x05040000), bytes(msg.data).hex()
    assert 0.5 <= time.monotonic() - t0 <= 3.5
    assert master.sdo_upload(NODE, 0x2F01, 0) == b"kept"


def test_block_download_with_a_wrong_crc_is_aborted(master, start_node):
    start_node(NODE)
    master.sdo_download(NODE, 0x2F01, 0, b"kept")
    data = b"0123456789"
    resp = master.sdo_request(NODE, struct.pack("<BHBI", 0xC6, 0x2F01, 0, len(data)))  # CRC, size
    assert resp[0] & 0xE3 == 0xA0 and resp[0] & 0x04, resp.hex()                    # server does CRC
    master.send(0x600 + NODE, bytes([0x01]) + data[:7])
    resp = master.sdo_request(NODE, bytes([0x82]) + data[7:].ljust(7, b"\0"))
    assert resp[:2] == bytes([0xA2, 2]), resp.hex()                                   # both acknowledged
    good = crc16_ccitt(data)
    resp = master.sdo_request(NODE, struct.pack("<BH", 0xC1 | 4 << 2, good ^ 0x5A5A))
    assert abort_frame(resp) is not None and abort_frame(resp)[2] == 0x05040004, resp
    assert master.sdo_upload(NODE, 0x2F01, 0) == b"kept"
