"""A small CANopen master for integration tests, over python-can.

Written from the CiA 301 text (NMT, SDO expedited/segmented/block, SYNC, heartbeat,
EMCY) and deliberately independent of the project's C++ code, so that the tests check
the node against the specification and not against itself.

All SDO functions return the data as ``bytes`` or raise :class:`SdoAbort` (with the
32-bit abort code). An abort sent by the server has ``remote=True``; one raised by this
client (timeout, protocol error, CRC error) has ``remote=False`` and the client has then
sent that abort to the server itself, as CiA 301 requires.

Frames the master reads while waiting for something else are kept in a backlog, so
``wait_for`` sees heartbeats/EMCYs that arrived during an SDO transfer.
"""

from __future__ import annotations

import collections
import errno
import struct
import time
from dataclasses import dataclass
from typing import Callable, Deque, List, Optional

import can

# ---------------------------------------------------------------- constants

NMT_START = 0x01
NMT_STOP = 0x02
NMT_PREOP = 0x80
NMT_RESET_NODE = 0x81
NMT_RESET_COMM = 0x82

# NMT states as sent in heartbeat / boot-up frames (CiA 301 7.2.8.3.2.1)
STATE_BOOTUP = 0x00
STATE_STOPPED = 0x04
STATE_OPERATIONAL = 0x05
STATE_PREOPERATIONAL = 0x7F
STATE_NAMES = {
    STATE_BOOTUP: "boot-up",
    STATE_STOPPED: "stopped",
    STATE_OPERATIONAL: "operational",
    STATE_PREOPERATIONAL: "pre-operational",
}

COB_NMT = 0x000
COB_SYNC = 0x080
COB_EMCY = 0x080  # + node id
COB_TSDO = 0x580  # server -> client, + node id
COB_RSDO = 0x600  # client -> server, + node id
COB_HEARTBEAT = 0x700  # + node id

# SDO abort codes (CiA 301 table 22)
ABORT_TOGGLE = 0x05030000
ABORT_TIMEOUT = 0x05040000
ABORT_BAD_CS = 0x05040001
ABORT_BAD_BLKSIZE = 0x05040002
ABORT_BAD_SEQNO = 0x05040003
ABORT_CRC = 0x05040004
ABORT_OUT_OF_MEMORY = 0x05040005
ABORT_UNSUPPORTED_ACCESS = 0x06010000
ABORT_WRITE_ONLY = 0x06010001
ABORT_READ_ONLY = 0x06010002
ABORT_NO_OBJECT = 0x06020000
ABORT_NOT_MAPPABLE = 0x06040041
ABORT_PDO_LENGTH = 0x06040042
ABORT_PARAM_INCOMPATIBLE = 0x06040043
ABORT_DEVICE_INCOMPATIBLE = 0x06040047
ABORT_HARDWARE = 0x06060000
ABORT_TYPE_LENGTH = 0x06070010
ABORT_TYPE_LENGTH_HIGH = 0x06070012
ABORT_TYPE_LENGTH_LOW = 0x06070013
ABORT_NO_SUBINDEX = 0x06090011
ABORT_VALUE_RANGE = 0x06090030
ABORT_VALUE_HIGH = 0x06090031
ABORT_VALUE_LOW = 0x06090032
ABORT_MAX_LESS_MIN = 0x06090036
ABORT_NO_RESOURCE = 0x060A0023
ABORT_GENERAL = 0x08000000
ABORT_DATA_STORE = 0x08000020
ABORT_DATA_STORE_LOCAL = 0x08000021
ABORT_DATA_STORE_STATE = 0x08000022
ABORT_NO_OD = 0x08000023
ABORT_NO_DATA = 0x08000024

ABORT_TEXT = {
    ABORT_TOGGLE: "toggle bit not alternated",
    ABORT_TIMEOUT: "SDO protocol timed out",
    ABORT_BAD_CS: "client/server command specifier not valid or unknown",
    ABORT_BAD_BLKSIZE: "invalid block size",
    ABORT_BAD_SEQNO: "invalid sequence number",
    ABORT_CRC: "CRC error",
    ABORT_OUT_OF_MEMORY: "out of memory",
    ABORT_UNSUPPORTED_ACCESS: "unsupported access to an object",
    ABORT_WRITE_ONLY: "attempt to read a write only object",
    ABORT_READ_ONLY: "attempt to write a read only object",
    ABORT_NO_OBJECT: "object does not exist in the object dictionary",
    ABORT_NOT_MAPPABLE: "object cannot be mapped to the PDO",
    ABORT_PDO_LENGTH: "number and length of objects to be mapped would exceed PDO length",
    ABORT_PARAM_INCOMPATIBLE: "general parameter incompatibility",
    ABORT_DEVICE_INCOMPATIBLE: "general internal incompatibility in the device",
    ABORT_HARDWARE: "access failed due to a hardware error",
    ABORT_TYPE_LENGTH: "data type does not match, length of service parameter does not match",
    ABORT_TYPE_LENGTH_HIGH: "data type does not match, length of service parameter too high",
    ABORT_TYPE_LENGTH_LOW: "data type does not match, length of service parameter too low",
    ABORT_NO_SUBINDEX: "sub-index does not exist",
    ABORT_VALUE_RANGE: "invalid value for parameter (download only)",
    ABORT_VALUE_HIGH: "value of parameter written too high (download only)",
    ABORT_VALUE_LOW: "value of parameter written too low (download only)",
    ABORT_MAX_LESS_MIN: "maximum value is less than minimum value",
    ABORT_NO_RESOURCE: "resource not available: SDO connection",
    ABORT_GENERAL: "general error",
    ABORT_DATA_STORE: "data cannot be transferred or stored to the application",
    ABORT_DATA_STORE_LOCAL: "data cannot be transferred or stored (local control)",
    ABORT_DATA_STORE_STATE: "data cannot be transferred or stored (present device state)",
    ABORT_NO_OD: "object dictionary dynamic generation fails or no object dictionary present",
    ABORT_NO_DATA: "no data available",
}


# ---------------------------------------------------------------- errors


class SdoAbort(Exception):
    """An SDO transfer ended with an abort; ``code`` is the 32-bit abort code."""

    def __init__(self, code: int, index: int = 0, subindex: int = 0, remote: bool = True, detail: str = ""):
        self.code = code
        self.index = index
        self.subindex = subindex
        self.remote = remote
        self.detail = detail
        who = "server" if remote else "client"
        text = ABORT_TEXT.get(code, "unknown abort code")
        msg = f"SDO abort 0x{code:08X} ({text}) by {who} for 0x{index:04X}:{subindex:02X}"
        if detail:
            msg += f": {detail}"
        super().__init__(msg)


class SdoTimeout(SdoAbort):
    """No (matching) SDO response within the timeout (client sent abort 0x05040000)."""


class SdoProtocolError(SdoAbort):
    """The server's response broke the protocol (client sent the given abort)."""


def abort_of(call) -> int:
    """The abort code a server sent for call(); fails if call() succeeded or the client
    gave up (a timeout or a protocol error is not the server's answer)."""
    try:
        call()
    except SdoAbort as e:
        assert e.remote, f"the client gave up, the server sent no abort: {e}"
        return e.code
    raise AssertionError("the server answered without an abort")


# ---------------------------------------------------------------- helpers


def crc16_ccitt(data: bytes, crc: int = 0) -> int:
    """CRC-16-CCITT as used by SDO block transfer: poly 0x1021, init 0, no reflection,
    no final xor (= CRC-16/XMODEM). ``crc`` allows incremental computation."""
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


@dataclass
class Emcy:
    node_id: int
    error_code: int  # u16
    error_register: int  # u8 (object 0x1001)
    manufacturer: bytes  # 5 bytes
    timestamp: float = 0.0


def decode_emcy(msg: can.Message) -> Optional[Emcy]:
    """Decode an EMCY frame (COB 0x81..0xFF); None if msg is not one.
    A short frame is zero-padded (CiA 301 EMCY is always 8 bytes)."""
    if msg.is_extended_id or msg.is_remote_frame or not (0x81 <= msg.arbitration_id <= 0xFF):
        return None
    data = bytes(msg.data).ljust(8, b"\0")
    code, reg = struct.unpack_from("<HB", data)
    return Emcy(msg.arbitration_id - COB_EMCY, code, reg, data[3:8], msg.timestamp)


def decode_heartbeat(msg: can.Message) -> Optional[tuple]:
    """(node_id, state) for a heartbeat/boot-up frame (COB 0x701..0x77F, 1 byte),
    else None. state is one of STATE_*; bit 7 (node-guarding toggle) is masked off."""
    if (
        msg.is_extended_id
        or msg.is_remote_frame
        or not (0x701 <= msg.arbitration_id <= 0x77F)
        or len(msg.data) < 1
    ):
        return None
    return msg.arbitration_id - COB_HEARTBEAT, msg.data[0] & 0x7F


def is_bootup(msg: can.Message, node_id: int) -> bool:
    return (
        not msg.is_extended_id
        and not msg.is_remote_frame
        and msg.arbitration_id == COB_HEARTBEAT + node_id
        and len(msg.data) == 1
        and msg.data[0] == 0x00
    )


def fmt_frame(msg: can.Message) -> str:
    """cansend-like text: 123#1122"""
    ident = f"{msg.arbitration_id:08X}" if msg.is_extended_id else f"{msg.arbitration_id:03X}"
    if msg.is_remote_frame:
        return f"{ident}#R"
    return f"{ident}#{bytes(msg.data).hex().upper()}"


# ---------------------------------------------------------------- master


class CanopenMaster:
    """CANopen master (NMT master, SDO client, SYNC producer) on a python-can bus.

    ``timeout`` is the default SDO response timeout in seconds (per frame exchange).
    """

    def __init__(self, bus: can.BusABC, timeout: float = 2.0, backlog: int = 100000):
        self.bus = bus
        self.timeout = timeout
        self.backlog: Deque[can.Message] = collections.deque(maxlen=backlog)

    # ------------------------------------------------------------ raw frames

    def send(self, cob_id: int, data: bytes = b"", remote: bool = False, extended: bool = False) -> None:
        msg = can.Message(
            arbitration_id=cob_id,
            data=bytes(data),
            is_extended_id=extended,
            is_remote_frame=remote,
            dlc=len(data),
        )
        deadline = time.monotonic() + max(self.timeout, 1.0)
        while True:
            try:
                self.bus.send(msg, timeout=0.5)
                return
            except can.CanOperationError as e:  # e.g. ENOBUFS when the tx queue is full
                if getattr(e, "error_code", None) not in (errno.ENOBUFS, errno.EAGAIN) or time.monotonic() > deadline:
                    raise
                time.sleep(0.001)

    def _recv_new(self, timeout: float) -> Optional[can.Message]:
        msg = self.bus.recv(timeout=max(timeout, 0.0))
        return msg

    def wait_for(self, predicate: Callable[[can.Message], bool], timeout: float = 2.0) -> Optional[can.Message]:
        """First frame (oldest first, backlog included) matching predicate, or None after
        timeout. Non-matching frames read from the bus are kept in the backlog."""
        for i, msg in enumerate(self.backlog):
            if predicate(msg):
                del self.backlog[i]
                return msg
        deadline = time.monotonic() + timeout
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return None
            msg = self._recv_new(remaining)
            if msg is None:
                return None
            if predicate(msg):
                return msg
            self.backlog.append(msg)

    def collect(self, duration: float, predicate: Optional[Callable[[can.Message], bool]] = None) -> List[can.Message]:
        """All frames (backlog first) matching predicate (or all) during `duration` s.
        Matching frames are removed from the backlog."""
        out = []
        keep = collections.deque(maxlen=self.backlog.maxlen)
        for msg in self.backlog:
            (out if predicate is None or predicate(msg) else keep).append(msg)
        self.backlog = keep
        deadline = time.monotonic() + duration
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return out
            msg = self._recv_new(remaining)
            if msg is None:
                continue
            if predicate is None or predicate(msg):
                out.append(msg)
            else:
                self.backlog.append(msg)

    def flush(self) -> int:
        """Drop the backlog and everything already queued on the socket; returns count."""
        n = len(self.backlog)
        self.backlog.clear()
        while self.bus.recv(timeout=0) is not None:
            n += 1
        return n

    # ------------------------------------------------------------ NMT / SYNC

    def nmt(self, cs: int, node_id: int = 0) -> None:
        """NMT command (COB 0x000: cs, node id); node_id 0 = all nodes."""
        self.send(COB_NMT, bytes([cs, node_id]))

    def nmt_start(self, node_id: int = 0) -> None:
        self.nmt(NMT_START, node_id)

    def nmt_stop(self, node_id: int = 0) -> None:
        self.nmt(NMT_STOP, node_id)

    def nmt_preop(self, node_id: int = 0) -> None:
        self.nmt(NMT_PREOP, node_id)

    def nmt_reset_node(self, node_id: int = 0) -> None:
        self.nmt(NMT_RESET_NODE, node_id)

    def nmt_reset_comm(self, node_id: int = 0) -> None:
        self.nmt(NMT_RESET_COMM, node_id)

    def sync(self, counter: Optional[int] = None, cob_id: int = COB_SYNC) -> None:
        """SYNC (COB 0x080); with counter (1..240) a 1-byte SYNC, else empty."""
        self.send(cob_id, b"" if counter is None else bytes([counter]))

    # ------------------------------------------------------------ heartbeat / EMCY

    def wait_bootup(self, node_id: int, timeout: float = 5.0) -> Optional[can.Message]:
        return self.wait_for(lambda m: is_bootup(m, node_id), timeout)

    def wait_heartbeat(self, node_id: int, timeout: float = 2.0, state: Optional[int] = None) -> Optional[int]:
        """State byte of the next heartbeat of node_id (optionally: the next one with
        that state); None on timeout. Boot-up frames count (state 0)."""

        def pred(m):
            hb = decode_heartbeat(m)
            return hb is not None and hb[0] == node_id and (state is None or hb[1] == state)

        msg = self.wait_for(pred, timeout)
        return None if msg is None else decode_heartbeat(msg)[1]

    def wait_emcy(self, node_id: int, timeout: float = 2.0) -> Optional[Emcy]:
        msg = self.wait_for(lambda m: (e := decode_emcy(m)) is not None and e.node_id == node_id, timeout)
        return None if msg is None else decode_emcy(msg)

    # ------------------------------------------------------------ SDO: low level

    def _sdo_pred(self, node_id: int):
        cob = COB_TSDO + node_id
        return lambda m: (not m.is_extended_id and not m.is_remote_frame and m.arbitration_id == cob)

    def _sdo_recv(self, node_id: int, index: int, sub: int, timeout: Optional[float] = None) -> bytes:
        msg = self.wait_for(self._sdo_pred(node_id), self.timeout if timeout is None else timeout)
        if msg is None:
            self._abort(node_id, index, sub, ABORT_TIMEOUT)
            raise SdoTimeout(ABORT_TIMEOUT, index, sub, remote=False, detail=f"no response on 0x{COB_TSDO + node_id:03X}")
        data = bytes(msg.data)
        if len(data) >= 1 and data[0] == 0x80:
            data = data.ljust(8, b"\0")
            code = struct.unpack_from("<I", data, 4)[0]
            raise SdoAbort(code, data[1] | data[2] << 8, data[3], remote=True)
        if len(data) != 8:
            self._fail(node_id, index, sub, ABORT_GENERAL, f"response has {len(data)} bytes, not 8: {data.hex()}")
        return data

    def _sdo_send(self, node_id: int, data: bytes) -> None:
        self.send(COB_RSDO + node_id, bytes(data).ljust(8, b"\0"))

    def _abort(self, node_id: int, index: int, sub: int, code: int) -> None:
        self._sdo_send(node_id, struct.pack("<BHBI", 0x80, index, sub, code))

    def _fail(self, node_id: int, index: int, sub: int, code: int, detail: str):
        self._abort(node_id, index, sub, code)
        raise SdoProtocolError(code, index, sub, remote=False, detail=detail)

    def _check_mux(self, node_id, index, sub, resp):
        if resp[1] | resp[2] << 8 != index or resp[3] != sub:
            self._fail(node_id, index, sub, ABORT_GENERAL,
                       f"response is for 0x{resp[1] | resp[2] << 8:04X}:{resp[3]:02X}")

    def _purge_sdo(self, node_id: int) -> None:
        pred = self._sdo_pred(node_id)
        self.backlog = collections.deque((m for m in self.backlog if not pred(m)), maxlen=self.backlog.maxlen)

    def sdo_request(self, node_id: int, data: bytes, timeout: Optional[float] = None) -> Optional[bytes]:
        """Send one raw SDO request (padded to 8 bytes) and return the raw response
        bytes (abort frames included, not raised), or None on timeout. For tests of
        malformed requests."""
        self._purge_sdo(node_id)
        self._sdo_send(node_id, data)
        msg = self.wait_for(self._sdo_pred(node_id), self.timeout if timeout is None else timeout)
        return None if msg is None else bytes(msg.data)

    # ------------------------------------------------------------ SDO upload (read)

    def sdo_upload(self, node_id: int, index: int, subindex: int) -> bytes:
        """Read an object: expedited or segmented, whichever the server chooses."""
        self._purge_sdo(node_id)
        self._sdo_send(node_id, struct.pack("<BHB", 0x40, index, subindex))
        resp = self._sdo_recv(node_id, index, subindex)
        return self._upload_after_initiate(node_id, index, subindex, resp)

    def _upload_after_initiate(self, node_id, index, sub, resp: bytes) -> bytes:
        if resp[0] >> 5 != 2:
            self._fail(node_id, index, sub, ABORT_BAD_CS, f"expected upload initiate response, got {resp.hex()}")
        self._check_mux(node_id, index, sub, resp)
        e, s = resp[0] >> 1 & 1, resp[0] & 1
        if e:
            if s:
                n = resp[0] >> 2 & 3
                return resp[4 : 8 - n]
            return resp[4:8]  # size not indicated: all 4 bytes
        size = struct.unpack_from("<I", resp, 4)[0] if s else None
        out = bytearray()
        toggle = 0
        while True:
            self._sdo_send(node_id, bytes([0x60 | toggle << 4]))
            seg = self._sdo_recv(node_id, index, sub)
            if seg[0] >> 5 != 0:
                self._fail(node_id, index, sub, ABORT_BAD_CS, f"expected upload segment response, got {seg.hex()}")
            if (seg[0] >> 4 & 1) != toggle:
                self._fail(node_id, index, sub, ABORT_TOGGLE, f"toggle {seg[0] >> 4 & 1}, expected {toggle}")
            n = seg[0] >> 1 & 7
            out += seg[1 : 8 - n]
            if seg[0] & 1:
                break
            toggle ^= 1
            if size is not None and len(out) > size:
                self._fail(node_id, index, sub, ABORT_TYPE_LENGTH_HIGH, f"more than the indicated {size} bytes")
        if size is not None and len(out) != size:
            raise SdoProtocolError(ABORT_TYPE_LENGTH, index, sub, remote=False,
                                   detail=f"received {len(out)} bytes, size indicated {size}")
        return bytes(out)

    # ------------------------------------------------------------ SDO download (write)

    def sdo_download(self, node_id: int, index: int, subindex: int, data: bytes,
                     expedited: Optional[bool] = None, size_indicated: bool = True) -> None:
        """Write an object. expedited=None: expedited if len(data) <= 4, else segmented;
        True/False forces the protocol (True needs len(data) <= 4)."""
        data = bytes(data)
        if expedited is None:
            expedited = len(data) <= 4
        self._purge_sdo(node_id)
        if expedited:
            if len(data) > 4:
                raise ValueError("expedited download carries at most 4 bytes")
            if size_indicated:
                cmd = 0x20 | (4 - len(data)) << 2 | 0x02 | 0x01
            else:
                cmd = 0x20 | 0x02
            self._sdo_send(node_id, struct.pack("<BHB", cmd, index, subindex) + data.ljust(4, b"\0"))
            self._expect_download_initiate(node_id, index, subindex)
            return
        cmd = 0x20 | (0x01 if size_indicated else 0)
        size = len(data) if size_indicated else 0
        self._sdo_send(node_id, struct.pack("<BHBI", cmd, index, subindex, size))
        self._expect_download_initiate(node_id, index, subindex)
        toggle = 0
        pos = 0
        while True:
            chunk = data[pos : pos + 7]
            pos += len(chunk)
            last = pos >= len(data)
            n = 7 - len(chunk)
            self._sdo_send(node_id, bytes([toggle << 4 | n << 1 | int(last)]) + chunk.ljust(7, b"\0"))
            resp = self._sdo_recv(node_id, index, subindex)
            if resp[0] >> 5 != 1:
                self._fail(node_id, index, subindex, ABORT_BAD_CS, f"expected download segment response, got {resp.hex()}")
            if (resp[0] >> 4 & 1) != toggle:
                self._fail(node_id, index, subindex, ABORT_TOGGLE, f"toggle {resp[0] >> 4 & 1}, expected {toggle}")
            if last:
                return
            toggle ^= 1

    def _expect_download_initiate(self, node_id, index, sub):
        resp = self._sdo_recv(node_id, index, sub)
        if resp[0] >> 5 != 3:
            self._fail(node_id, index, sub, ABORT_BAD_CS, f"expected download initiate response, got {resp.hex()}")
        self._check_mux(node_id, index, sub, resp)

    # ------------------------------------------------------------ SDO block upload

    def sdo_block_upload(self, node_id: int, index: int, subindex: int, blksize: int = 127,
                         pst: int = 0, crc: bool = True,
                         next_blksize: Optional[Callable[[int], int]] = None) -> bytes:
        """Read an object with SDO block upload (CiA 301 7.2.4.3.11-7.2.4.3.14).

        blksize: segments per block the client offers (1..127); next_blksize(block_no)
        may choose the blksize sent in each block acknowledgement (default: blksize).
        pst: protocol switch threshold; if the server then answers with a normal upload
        initiate response, the transfer continues as an expedited/segmented upload.
        crc: whether the client announces CRC support (then checks it if the server
        supports it too)."""
        if not 1 <= blksize <= 127:
            raise ValueError("blksize must be 1..127")
        self._purge_sdo(node_id)
        self._sdo_send(node_id, struct.pack("<BHBBB", 0xA0 | int(crc) << 2, index, subindex, blksize, pst))
        resp = self._sdo_recv(node_id, index, subindex)
        if resp[0] >> 5 == 2 and pst > 0:
            return self._upload_after_initiate(node_id, index, subindex, resp)
        if resp[0] >> 5 != 6 or resp[0] & 1 != 0:  # scs=6, ss (bit 0)=0; bit 1 is s
            self._fail(node_id, index, subindex, ABORT_BAD_CS, f"expected block upload initiate response, got {resp.hex()}")
        self._check_mux(node_id, index, subindex, resp)
        server_crc = bool(resp[0] >> 2 & 1)
        size = struct.unpack_from("<I", resp, 4)[0] if resp[0] >> 1 & 1 else None

        self._sdo_send(node_id, bytes([0xA3]))  # start upload
        out = bytearray()
        cur = blksize
        block_no = 0
        last_seg = b""
        while True:
            # receive one block: segments 1..cur, or fewer when c=1
            ackseq = 0
            block = bytearray()
            done = False
            while True:
                seg = self._sdo_recv(node_id, index, subindex)
                seqno = seg[0] & 0x7F
                c = seg[0] >> 7
                if seqno == ackseq + 1:
                    ackseq = seqno
                    block += seg[1:8]
                    last_seg = seg[1:8]
                    if c:
                        done = True
                        break
                    if seqno == cur:
                        break
                elif seqno == cur or c:
                    break  # end of a block with a lost/out-of-order segment: ack what we have
                # else: out of sequence, ignore until the block ends
            block_no += 1
            out += block
            new_blk = next_blksize(block_no) if next_blksize else blksize
            self._sdo_send(node_id, bytes([0xA2, ackseq, new_blk]))
            cur = new_blk
            if done:
                break
        # end phase
        end = self._sdo_recv(node_id, index, subindex)
        if end[0] >> 5 != 6 or end[0] & 1 != 1:  # scs=6, n in bits 4-2, ss (bit 0)=1
            self._fail(node_id, index, subindex, ABORT_BAD_CS, f"expected block upload end, got {end.hex()}")
        n = end[0] >> 2 & 7
        if n:
            del out[len(out) - n :]
        if crc and server_crc:
            got = struct.unpack_from("<H", end, 1)[0]
            want = crc16_ccitt(bytes(out))
            if got != want:
                self._fail(node_id, index, subindex, ABORT_CRC, f"CRC 0x{got:04X} from server, computed 0x{want:04X}")
        if size is not None and len(out) != size:
            self._fail(node_id, index, subindex, ABORT_TYPE_LENGTH,
                       f"received {len(out)} bytes, size indicated {size}")
        self._sdo_send(node_id, bytes([0xA1]))  # end block upload response
        return bytes(out)

    # ------------------------------------------------------------ SDO block download

    def sdo_block_download(self, node_id: int, index: int, subindex: int, data: bytes,
                           crc: bool = True, size_indicated: bool = True) -> None:
        """Write an object with SDO block download (CiA 301 7.2.4.3.9-7.2.4.3.10,
        7.2.4.3.15-7.2.4.3.16). The server chooses the block size (initiate response and
        every acknowledgement); segments it does not acknowledge are sent again."""
        data = bytes(data)
        self._purge_sdo(node_id)
        cmd = 0xC0 | int(crc) << 2 | int(size_indicated) << 1
        self._sdo_send(node_id, struct.pack("<BHBI", cmd, index, subindex, len(data) if size_indicated else 0))
        resp = self._sdo_recv(node_id, index, subindex)
        if resp[0] >> 5 != 5 or resp[0] & 3 != 0:
            self._fail(node_id, index, subindex, ABORT_BAD_CS, f"expected block download initiate response, got {resp.hex()}")
        self._check_mux(node_id, index, subindex, resp)
        server_crc = bool(resp[0] >> 2 & 1)
        blksize = resp[4]
        if not 1 <= blksize <= 127:
            self._fail(node_id, index, subindex, ABORT_BAD_BLKSIZE, f"server block size {blksize}")

        segments = [data[i : i + 7] for i in range(0, len(data), 7)] or [b""]
        pos = 0  # index of the first segment not yet acknowledged
        while pos < len(segments):
            count = min(blksize, len(segments) - pos)
            for k in range(count):
                chunk = segments[pos + k]
                last = pos + k == len(segments) - 1
                self._sdo_send(node_id, bytes([int(last) << 7 | (k + 1)]) + chunk.ljust(7, b"\0"))
            ack = self._sdo_recv(node_id, index, subindex)
            if ack[0] >> 5 != 5 or ack[0] & 3 != 2:
                self._fail(node_id, index, subindex, ABORT_BAD_CS, f"expected block ack, got {ack.hex()}")
            ackseq, blksize = ack[1], ack[2]
            if ackseq > count:
                self._fail(node_id, index, subindex, ABORT_BAD_SEQNO, f"ackseq {ackseq} > {count} segments sent")
            if not 1 <= blksize <= 127:
                self._fail(node_id, index, subindex, ABORT_BAD_BLKSIZE, f"server block size {blksize}")
            pos += ackseq
        n = 7 - len(segments[-1])
        value = crc16_ccitt(data) if (crc and server_crc) else 0
        self._sdo_send(node_id, struct.pack("<BH", 0xC1 | n << 2, value))
        end = self._sdo_recv(node_id, index, subindex)
        if end[0] >> 5 != 5 or end[0] & 3 != 1:
            self._fail(node_id, index, subindex, ABORT_BAD_CS, f"expected block download end response, got {end.hex()}")

    # ------------------------------------------------------------ typed convenience

    def read_u8(self, node_id, index, sub=0) -> int:
        return self._read_int(node_id, index, sub, 1, False)

    def read_u16(self, node_id, index, sub=0) -> int:
        return self._read_int(node_id, index, sub, 2, False)

    def read_u32(self, node_id, index, sub=0) -> int:
        return self._read_int(node_id, index, sub, 4, False)

    def read_i32(self, node_id, index, sub=0) -> int:
        return self._read_int(node_id, index, sub, 4, True)

    def _read_int(self, node_id, index, sub, size, signed) -> int:
        data = self.sdo_upload(node_id, index, sub)
        if len(data) != size:
            raise AssertionError(f"0x{index:04X}:{sub:02X}: {len(data)} bytes, expected {size}: {data.hex()}")
        return int.from_bytes(data, "little", signed=signed)

    def write_u8(self, node_id, index, sub, value: int) -> None:
        self.sdo_download(node_id, index, sub, value.to_bytes(1, "little"))

    def write_u16(self, node_id, index, sub, value: int) -> None:
        self.sdo_download(node_id, index, sub, value.to_bytes(2, "little"))

    def write_u32(self, node_id, index, sub, value: int) -> None:
        self.sdo_download(node_id, index, sub, value.to_bytes(4, "little"))

    def write_i32(self, node_id, index, sub, value: int) -> None:
        self.sdo_download(node_id, index, sub, value.to_bytes(4, "little", signed=True))
