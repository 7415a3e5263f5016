"""Self-tests of canopen_master that need no vcan: the CRC, and the SDO client against a
minimal SDO server written here from CiA 301, over python-can's in-process virtual bus."""

import struct
import threading
import uuid

import can
import pytest

from canopen_master import (
    ABORT_BAD_CS,
    ABORT_NO_OBJECT,
    ABORT_TIMEOUT,
    CanopenMaster,
    SdoAbort,
    SdoTimeout,
    crc16_ccitt,
    decode_emcy,
    decode_heartbeat,
)


def test_crc16_ccitt_known_vector():
    assert crc16_ccitt(b"123456789") == 0x31C3  # CRC-16/XMODEM check value


def test_crc16_ccitt_edge_cases():
    assert crc16_ccitt(b"") == 0
    assert crc16_ccitt(b"\x00") == 0
    assert crc16_ccitt(b"A") == 0x58E5
    data = bytes(range(256)) * 3
    assert crc16_ccitt(data[100:], crc16_ccitt(data[:100])) == crc16_ccitt(data)  # incremental


def test_decode_emcy_and_heartbeat():
    e = decode_emcy(can.Message(arbitration_id=0x85, data=bytes([0x10, 0x81, 0x11, 1, 2, 3, 4, 5]), is_extended_id=False))
    assert (e.node_id, e.error_code, e.error_register, e.manufacturer) == (5, 0x8110, 0x11, b"\x01\x02\x03\x04\x05")
    assert decode_emcy(can.Message(arbitration_id=0x80, data=b"", is_extended_id=False)) is None  # SYNC
    assert decode_heartbeat(can.Message(arbitration_id=0x705, data=b"\x7f", is_extended_id=False)) == (5, 0x7F)
    assert decode_heartbeat(can.Message(arbitration_id=0x705, data=b"\x85", is_extended_id=False)) == (5, 0x05)
    assert decode_heartbeat(can.Message(arbitration_id=0x605, data=b"\x00", is_extended_id=False)) is None


# ---------------------------------------------------------------- a tiny SDO server


class FakeSdoServer(threading.Thread):
    """SDO server for node `node_id` serving `objects` {(index, sub): bytes}.
    drop_download_seq / drop_upload_seq: one block segment seqno to lose once, to exercise
    the retransmission path."""

    def __init__(self, channel, node_id, objects, blksize=5, crc=True, drop_download_seq=None, drop_upload_seq=None,
                 interface="virtual"):
        super().__init__(daemon=True)
        self.bus = can.interface.Bus(channel=channel, interface=interface)
        self.node_id = node_id
        self.objects = objects
        self.blksize = blksize
        self.crc = crc
        self.drop_download_seq = drop_download_seq
        self.drop_upload_seq = drop_upload_seq
        self.stop = threading.Event()
        self.state = None
        self.log = []

    def send(self, data):
        self.bus.send(can.Message(arbitration_id=0x580 + self.node_id, data=bytes(data).ljust(8, b"\0"),
                                  is_extended_id=False))

    def abort(self, idx, sub, code):
        self.state = None
        self.send(struct.pack("<BHBI", 0x80, idx, sub, code))

    def run(self):
        while not self.stop.is_set():
            msg = self.bus.recv(timeout=0.05)
            if msg is None or msg.arbitration_id != 0x600 + self.node_id:
                continue
            d = bytes(msg.data)
            self.log.append(d)
            try:
                self.handle(d)
            except Exception as e:  # pragma: no cover - shows up as client timeout
                self.log.append(repr(e))

    def handle(self, d):
        st = self.state
        if st and st["kind"] == "bdl_seg":  # block download: segments carry no ccs
            return self.bdl_segment(d)
        ccs = d[0] >> 5
        idx, sub = d[1] | d[2] << 8, d[3]
        if d[0] == 0x80:
            self.state = None
            return
        if ccs == 2:  # upload initiate
            if (idx, sub) not in self.objects:
                return self.abort(idx, sub, ABORT_NO_OBJECT)
            val = self.objects[(idx, sub)]
            if 1 <= len(val) <= 4:  # expedited (cannot carry 0 bytes)
                self.send(struct.pack("<BHB", 0x43 | (4 - len(val)) << 2, idx, sub) + val.ljust(4, b"\0"))
            else:
                self.send(struct.pack("<BHBI", 0x41, idx, sub, len(val)))
                self.state = {"kind": "up", "idx": idx, "sub": sub, "data": val, "pos": 0, "t": 0}
        elif ccs == 3 and st and st["kind"] == "up":  # upload segment
            t = d[0] >> 4 & 1
            if t != st["t"]:
                return self.abort(st["idx"], st["sub"], 0x05030000)
            chunk = st["data"][st["pos"]:st["pos"] + 7]
            st["pos"] += len(chunk)
            last = st["pos"] >= len(st["data"])
            self.send(bytes([t << 4 | (7 - len(chunk)) << 1 | int(last)]) + chunk.ljust(7, b"\0"))
            st["t"] ^= 1
            if last:
                self.state = None
        elif ccs == 1:  # download initiate
            e, s = d[0] >> 1 & 1, d[0] & 1
            if e:
                n = (d[0] >> 2 & 3) if s else 0
                self.objects[(idx, sub)] = d[4:8 - n]
            else:
                self.state = {"kind": "dl", "idx": idx, "sub": sub, "buf": bytearray(), "t": 0}
            self.send(struct.pack("<BHB", 0x60, idx, sub))
        elif ccs == 0 and st and st["kind"] == "dl":  # download segment
            t = d[0] >> 4 & 1
            if t != st["t"]:
                return self.abort(st["idx"], st["sub"], 0x05030000)
            st["buf"] += d[1:8 - (d[0] >> 1 & 7)]
            self.send(bytes([0x20 | t << 4]))
            st["t"] ^= 1
            if d[0] & 1:
                self.objects[(st["idx"], st["sub"])] = bytes(st["buf"])
                self.state = None
        elif ccs == 6 and d[0] & 1 == 0:  # block download initiate
            self.state = {"kind": "bdl_seg", "idx": idx, "sub": sub, "buf": bytearray(), "seq": 0,
                          "cc": bool(d[0] >> 2 & 1), "size": struct.unpack_from("<I", d, 4)[0] if d[0] & 2 else None}
            self.send(struct.pack("<BHBB", 0xA0 | int(self.crc) << 2, idx, sub, self.blksize))
        elif ccs == 6 and st and st["kind"] == "bdl_end":  # block download end
            n = d[0] >> 2 & 7
            data = bytes(st["buf"][:len(st["buf"]) - n])
            if self.crc and st["cc"] and struct.unpack_from("<H", d, 1)[0] != crc16_ccitt(data):
                return self.abort(st["idx"], st["sub"], 0x05040004)
            self.objects[(st["idx"], st["sub"])] = data
            self.state = None
            self.send(bytes([0xA1]))
        elif ccs == 5 and d[0] & 3 == 0:  # block upload initiate
            if (idx, sub) not in self.objects:
                return self.abort(idx, sub, ABORT_NO_OBJECT)
            val = self.objects[(idx, sub)]
            pst = d[5]
            if pst and len(val) <= pst:  # protocol switch to normal upload
                return self.handle(struct.pack("<BHB", 0x40, idx, sub).ljust(8, b"\0"))
            self.state = {"kind": "bup", "idx": idx, "sub": sub, "data": val, "pos": 0, "blk": d[4],
                          "cc": bool(d[0] >> 2 & 1), "sent": []}
            self.send(struct.pack("<BHBI", 0xC2 | int(self.crc) << 2, idx, sub, len(val)))
        elif ccs == 5 and st and st["kind"] == "bup" and d[0] & 3 == 3:  # start upload
            self.bup_block()
        elif ccs == 5 and st and st["kind"] == "bup" and d[0] & 3 == 2:  # block ack
            ackseq, st["blk"] = d[1], d[2]
            st["pos"] += 7 * ackseq
            if st["pos"] >= len(st["data"]):  # all acknowledged
                n = 7 * max(1, -(-len(st["data"]) // 7)) - len(st["data"])
                crc = crc16_ccitt(st["data"]) if (self.crc and st["cc"]) else 0
                st["kind"] = "bup_end"
                self.send(struct.pack("<BH", 0xC1 | n << 2, crc))
            else:
                self.bup_block()
        elif ccs == 5 and st and st["kind"] == "bup_end" and d[0] & 3 == 1:
            self.state = None
        else:
            self.abort(idx, sub, ABORT_BAD_CS)

    def bup_block(self):
        st = self.state
        st["sent"] = []
        st["last_sent"] = False
        pos = st["pos"]
        for seq in range(1, st["blk"] + 1):
            chunk = st["data"][pos:pos + 7]
            pos += 7
            last = pos >= len(st["data"])
            st["sent"].append(seq)
            if seq == self.drop_upload_seq:
                self.drop_upload_seq = None  # lose it once
            else:
                self.send(bytes([int(last) << 7 | seq]) + chunk.ljust(7, b"\0"))
            if last:
                st["last_sent"] = True
                break

    def bdl_segment(self, d):
        st = self.state
        seq, c = d[0] & 0x7F, d[0] >> 7
        if seq == self.drop_download_seq:
            self.drop_download_seq = None
            seq = -1  # lost
        if seq == st["seq"] + 1:
            st["seq"] = seq
            st["buf"] += d[1:8]
        if seq == self.blksize or c:
            # end of the block: acknowledge the in-order part; the client resends the rest
            ackseq = st["seq"]
            self.send(bytes([0xA2, ackseq, self.blksize]))
            st["seq"] = 0
            if c and seq == ackseq:
                st["kind"] = "bdl_end"


@pytest.fixture
def sim():
    """(master, start_server) on a private virtual bus."""
    channel = "selftest-" + uuid.uuid4().hex
    client_bus = can.interface.Bus(channel=channel, interface="virtual")
    servers = []

    def start(**kw):
        s = FakeSdoServer(channel, 5, kw.pop("objects", {}), **kw)
        s.start()
        servers.append(s)
        return s

    yield CanopenMaster(client_bus, timeout=1.0), start
    for s in servers:
        s.stop.set()
        s.join(2)
        s.bus.shutdown()
    client_bus.shutdown()


PAYLOADS = [b"", b"\x01", b"abcd", b"abcde", b"1234567", b"12345678", bytes(range(256)) * 4 + b"xyz"]


@pytest.mark.parametrize("value", PAYLOADS, ids=lambda v: f"{len(v)}B")
def test_expedited_and_segmented_roundtrip(sim, value):
    master, start = sim
    server = start(objects={})
    if len(value) == 0:
        master.sdo_download(5, 0x2000, 1, value, expedited=False)  # empty only segmented
    else:
        master.sdo_download(5, 0x2000, 1, value)
    assert server.objects[(0x2000, 1)] == value
    got = master.sdo_upload(5, 0x2000, 1)
    assert got == value


@pytest.mark.parametrize("value", PAYLOADS[1:], ids=lambda v: f"{len(v)}B")
@pytest.mark.parametrize("blksize", [1, 4, 127])
def test_block_roundtrip(sim, value, blksize):
    master, start = sim
    server = start(objects={}, blksize=blksize)
    master.sdo_block_download(5, 0x2001, 0, value)
    assert server.objects[(0x2001, 0)] == value
    assert master.sdo_block_upload(5, 0x2001, 0, blksize=blksize) == value


def test_block_transfers_retransmit_lost_segment(sim):
    master, start = sim
    value = bytes(range(200))
    server = start(objects={}, blksize=10, drop_download_seq=4, drop_upload_seq=3)
    master.sdo_block_download(5, 0x2002, 0, value)
    assert server.objects[(0x2002, 0)] == value
    assert master.sdo_block_upload(5, 0x2002, 0, blksize=10) == value


def test_block_upload_protocol_switch(sim):
    master, start = sim
    start(objects={(0x1008, 0): b"node"})
    assert master.sdo_block_upload(5, 0x1008, 0, pst=16) == b"node"


def test_abort_and_timeout(sim):
    master, start = sim
    start(objects={})
    with pytest.raises(SdoAbort) as e:
        master.sdo_upload(5, 0x1234, 0)
    assert e.value.code == ABORT_NO_OBJECT and e.value.remote
    with pytest.raises(SdoTimeout) as e:
        master.sdo_upload(6, 0x1000, 0)  # nobody is node 6
    assert e.value.code == ABORT_TIMEOUT and not e.value.remote
