"""A small LSS master (CiA 305 V3.0) for integration tests, over python-can.

Written from the CiA 305 protocol descriptions and independent of the node's C++ code:
requests go on COB-ID 0x7E5, answers come on 0x7E4; every frame has 8 data bytes, the
command specifier (cs) first, 32-bit values little-endian in bytes 1..4, unused bytes 0.

The master owns its socket (give it one of its own, not the CanopenMaster's): it reads
only 0x7E4 frames and drops everything else it sees.
"""

from __future__ import annotations

import struct
import time
from dataclasses import dataclass
from typing import List, Optional

import can

COB_MASTER_TO_SLAVE = 0x7E5
COB_SLAVE_TO_MASTER = 0x7E4

# Command specifiers
CS_SWITCH_STATE_GLOBAL = 0x04
CS_CONFIGURE_NODE_ID = 0x11
CS_CONFIGURE_BIT_TIMING = 0x13
CS_ACTIVATE_BIT_TIMING = 0x15
CS_STORE_CONFIGURATION = 0x17
CS_SWITCH_SELECTIVE = (0x40, 0x41, 0x42, 0x43)  # vendor, product, revision, serial
CS_SWITCH_SELECTIVE_RESPONSE = 0x44
CS_IDENTIFY_REMOTE_SLAVE = (0x46, 0x47, 0x48, 0x49, 0x4A, 0x4B)
CS_IDENTIFY_NON_CONFIGURED = 0x4C
CS_IDENTIFY_SLAVE = 0x4F
CS_IDENTIFY_NON_CONFIGURED_SLAVE = 0x50
CS_FAST_SCAN = 0x51
CS_INQUIRE_VENDOR = 0x5A
CS_INQUIRE_PRODUCT = 0x5B
CS_INQUIRE_REVISION = 0x5C
CS_INQUIRE_SERIAL = 0x5D
CS_INQUIRE_NODE_ID = 0x5E

MODE_WAITING = 0
MODE_CONFIGURATION = 1
FAST_SCAN_CONFIRM = 0x80  # BitChecked value that resets the scan on every slave


@dataclass(frozen=True)
class LssAddress:
    vendor_id: int
    product_code: int
    revision_number: int
    serial_number: int

    def parts(self):
        return (self.vendor_id, self.product_code, self.revision_number, self.serial_number)


class LssTimeout(Exception):
    pass


class LssMaster:
    def __init__(self, bus: can.BusABC, timeout: float = 1.0, scan_timeout: float = 0.15, settle: float = 0.03):
        self.bus = bus
        self.timeout = timeout            # a confirmed service's answer
        self.scan_timeout = scan_timeout  # silence that means "nobody matches" in a scan
        self.settle = settle              # after a scan answer: later ones of the same request

    # ------------------------------------------------------------ frames

    def send(self, cs: int, payload: bytes = b"") -> None:
        data = bytes([cs]) + payload
        data += bytes(8 - len(data))
        self.bus.send(can.Message(arbitration_id=COB_MASTER_TO_SLAVE, data=data, is_extended_id=False))

    def send_u32(self, cs: int, value: int) -> None:
        self.send(cs, struct.pack("<I", value))

    def drain(self) -> None:
        """Drops whatever arrived so far (late answers to an earlier request)."""
        while self.bus.recv(timeout=0) is not None:
            pass

    def answers(self, cs: int, timeout: float, first_only: bool = False) -> List[bytes]:
        """The 0x7E4 frames with this cs seen within timeout (or until the first, plus the
        settle time to swallow the others' answers to the same request)."""
        out: List[bytes] = []
        deadline = time.monotonic() + timeout
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return out
            msg = self.bus.recv(timeout=remaining)
            if msg is None:
                return out
            if msg.arbitration_id != COB_SLAVE_TO_MASTER or msg.is_remote_frame or msg.is_extended_id:
                continue
            assert len(msg.data) == 8, f"LSS answer with DLC {len(msg.data)}: {bytes(msg.data).hex()}"
            if msg.data[0] == cs:
                out.append(bytes(msg.data))
                if first_only:
                    deadline = min(deadline, time.monotonic() + self.settle)

    def request(self, cs: int, payload: bytes = b"", answer_cs: Optional[int] = None) -> bytes:
        """A confirmed service: the one answer, or LssTimeout."""
        self.drain()
        self.send(cs, payload)
        got = self.answers(cs if answer_cs is None else answer_cs, self.timeout, first_only=True)
        if not got:
            raise LssTimeout(f"no LSS answer to cs 0x{cs:02X}")
        return got[0]

    # ------------------------------------------------------------ services

    def switch_state_global(self, mode: int) -> None:
        self.send(CS_SWITCH_STATE_GLOBAL, bytes([mode]))

    def switch_state_selective(self, address: LssAddress) -> bool:
        """The slave with this address enters configuration and answers 0x44."""
        self.drain()
        for cs, value in zip(CS_SWITCH_SELECTIVE, address.parts()):
            self.send_u32(cs, value)
        return bool(self.answers(CS_SWITCH_SELECTIVE_RESPONSE, self.timeout, first_only=True))

    def configure_node_id(self, node_id: int) -> int:
        """Error code: 0 ok, 1 node-ID out of range."""
        return self.request(CS_CONFIGURE_NODE_ID, bytes([node_id]))[1]

    def configure_bit_timing(self, table_index: int, table_selector: int = 0) -> int:
        """Error code: 0 ok, 1 bit timing not supported."""
        return self.request(CS_CONFIGURE_BIT_TIMING, bytes([table_selector, table_index]))[1]

    def activate_bit_timing(self, switch_delay_ms: int) -> None:
        self.send(CS_ACTIVATE_BIT_TIMING, struct.pack("<H", switch_delay_ms))

    def store_configuration(self) -> int:
        """Error code: 0 ok, 1 not supported, 2 storage media access error."""
        return self.request(CS_STORE_CONFIGURATION)[1]

    def inquire(self, cs: int) -> int:
        return struct.unpack_from("<I", self.request(cs), 1)[0]

    def inquire_address(self) -> LssAddress:
        return LssAddress(*(self.inquire(cs) for cs in (CS_INQUIRE_VENDOR, CS_INQUIRE_PRODUCT,
                                                         CS_INQUIRE_REVISION, CS_INQUIRE_SERIAL)))

    def inquire_node_id(self) -> int:
        return self.request(CS_INQUIRE_NODE_ID)[1]

    def identify_remote_slave(self, vendor_id: int, product_code: int, revision_low: int, revision_high: int,
                              serial_low: int, serial_high: int) -> bool:
        """Does any slave of this vendor and product have its revision and serial number in
        the ranges (bounds included)?"""
        self.drain()
        for cs, v in zip(CS_IDENTIFY_REMOTE_SLAVE,
                         (vendor_id, product_code, revision_low, revision_high, serial_low, serial_high)):
            self.send_u32(cs, v)
        return bool(self.answers(CS_IDENTIFY_SLAVE, self.scan_timeout * 2, first_only=True))

    def identify_non_configured(self) -> int:
        """How many slaves without a node-ID answered (0x50)."""
        self.drain()
        self.send(CS_IDENTIFY_NON_CONFIGURED)
        return len(self.answers(CS_IDENTIFY_NON_CONFIGURED_SLAVE, self.scan_timeout * 3))

    # ------------------------------------------------------------ fast scan

    def _scan_step(self, id_number: int, bit_checked: int, lss_sub: int, lss_next: int) -> bool:
        self.drain()
        self.send(CS_FAST_SCAN, struct.pack("<IBBB", id_number, bit_checked, lss_sub, lss_next))
        return bool(self.answers(CS_IDENTIFY_SLAVE, self.scan_timeout, first_only=True))

    def fast_scan_once(self) -> Optional[LssAddress]:
        """CiA 305 fast scan: reset (BitChecked 0x80: every unconfigured slave answers), then
        for LSSSub 0..3 find the bits from 31 down: with the bit under test 0 in IDNumber, an
        answer means some slave has 0 there, silence that none has (so it is 1). Each part is
        confirmed whole (BitChecked 0) with LSSNext the next part; after the serial number
        LSSNext is 0 and the one slave left enters the configuration state."""
        if not self._scan_step(0, FAST_SCAN_CONFIRM, 0, 0):
            return None
        found = []
        for sub in range(4):
            id_number = 0
            for bit in range(31, -1, -1):
                if not self._scan_step(id_number, bit, sub, sub):
                    id_number |= 1 << bit
            if not self._scan_step(id_number, 0, sub, (sub + 1) % 4):
                return None
            found.append(id_number)
        return LssAddress(*found)

    def fast_scan(self, attempts: int = 3) -> Optional[LssAddress]:
        """fast_scan_once, checked: the slave in configuration must report the address found
        (a scan answer late beyond the settle time would have misread one bit); retried."""
        for _ in range(attempts):
            address = self.fast_scan_once()
            if address is None:
                if self.identify_non_configured() == 0:
                    return None
                continue
            try:
                if self.inquire_address() == address:
                    return address
            except LssTimeout:
                pass
            self.switch_state_global(MODE_WAITING)
        return None
