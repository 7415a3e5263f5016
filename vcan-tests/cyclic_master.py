"""The cyclic side of a CiA 402 master for the vcan tests: the SYNC producer, the command
value stream of the cyclic synchronous modes, and a record of what the drive answered.

Written from the standards, not from the node's code:

- CiA 402-2 "Cyclic synchronous position mode" / "Cyclic synchronous velocity mode": the
  trajectory generator is in the master; it sends one command value (607Ah target position,
  60FFh target velocity) per communication cycle, and the drive follows it. 60C2h
  interpolation time period tells the drive the cycle (value * 10^index s).
- CiA 301 SYNC: the master is the SYNC producer (COB-ID 080h, no data: 1019h = 0), one SYNC
  per communication cycle period. The data of a synchronous RPDO (transmission type
  0..240) take effect at the first SYNC after the RPDO was received; a synchronous TPDO of
  type 1 is sampled and sent at every SYNC. PDO parameters are changed while the PDO is invalid (COB-ID bit 31 set).

Each cycle k the producer sends the set-point for SYNC k (RPDO2 {607Ah, 60FFh},
transmission type 1) and then SYNC k, on one raw CAN socket, so a set-point always reaches
the drive before its SYNC. The cycle is timed against CLOCK_MONOTONIC with absolute
deadlines; a cycle that is late by more than half a period is sent at once and the schedule
moves with it (a "slip"), so late cycles are not sent as a burst. Under User-Mode Linux a
process wake-up is slow and irregular: the real SYNC times are the kernel's receive
timestamps of the SYNC frames, and every check uses those, never the intended schedule.

A recorder socket with a large receive buffer (SO_RCVBUFFORCE) and a filter for the frames of
interest keeps every frame of the run in bus order with its kernel timestamp; it is read
after the run, so the test process does not compete with the node for the CPU while SYNCs go.
"""

from __future__ import annotations

import json
import socket
import statistics
import struct
import time
from dataclasses import asdict, dataclass, field
from typing import Dict, List, Optional, Sequence, Set

import can

from canopen_master import COB_SYNC, CanopenMaster

CAN_FRAME = struct.Struct("=IB3x8s")  # struct can_frame: can_id, len, pad, data[8]
SO_RCVBUFFORCE = 33  # <asm-generic/socket.h>, needs CAP_NET_ADMIN (the tests run as root)
RECORD_BUFFER = 64 << 20

# CiA 301 PDO parameters
PDO_INVALID = 1 << 31
TT_SYNC_EVERY = 1  # synchronous, every SYNC
TT_EVENT = 254  # event-driven (manufacturer specific)


@dataclass
class PdoConfig:
    comm_index: int  # 1400h + n (RPDO) or 1800h + n (TPDO)
    cob_id: int
    transmission_type: int
    inhibit_100us: Optional[int] = None  # TPDO only
    mapping: Optional[Sequence[int]] = None  # mapping words (index << 16 | sub << 8 | bits)


def configure_pdo(master: CanopenMaster, node_id: int, cfg: PdoConfig) -> None:
    """CiA 301 procedure: invalidate (bit 31), change, map, validate."""
    idx = cfg.comm_index
    master.write_u32(node_id, idx, 1, cfg.cob_id | PDO_INVALID)
    master.write_u8(node_id, idx, 2, cfg.transmission_type)
    if cfg.inhibit_100us is not None:
        master.write_u16(node_id, idx, 3, cfg.inhibit_100us)
    if cfg.mapping is not None:
        mapping = idx + 0x200  # 1600h / 1A00h
        master.write_u8(node_id, mapping, 0, 0)
        for i, word in enumerate(cfg.mapping, 1):
            master.write_u32(node_id, mapping, i, word)
        master.write_u8(node_id, mapping, 0, len(cfg.mapping))
    master.write_u32(node_id, idx, 1, cfg.cob_id)


def map_word(index: int, sub: int, bits: int) -> int:
    return (index << 16) | (sub << 8) | bits


def interpolation_period(period: float) -> tuple:
    """60C2h sub 1 / sub 2 for a cycle of `period` s, in ms (index -3) or 100 us (index -4)."""
    ms = period * 1000
    if abs(ms - round(ms)) < 1e-9 and 1 <= round(ms) <= 255:
        return round(ms), -3
    return round(period * 10000), -4


# ---------------------------------------------------------------- the run's record


@dataclass
class Cycle:
    """One SYNC as it went on the bus, and what the drive sent for it."""

    k: int
    t: float  # kernel receive timestamp of the SYNC (s, CLOCK_REALTIME)
    set_point: int  # 607Ah in effect at this SYNC (the last RPDO2 before it)
    velocity_cmd: int  # 60FFh in effect at this SYNC
    answered: Optional[float] = None  # kernel timestamp of that TPDO2: when the drive took the SYNC
    position: Optional[int] = None  # 6064h in the synchronous TPDO2 of this SYNC
    velocity: Optional[int] = None  # 606Ch in the synchronous TPDO2 of this SYNC
    tpdo3: Optional[tuple] = None  # the values of the synchronous TPDO3 of this SYNC, if it is one


@dataclass
class Sample:
    """A TPDO as it came: kernel timestamp and the mapped values."""

    t: float
    values: tuple

    def __getitem__(self, i):
        return self.values[i]


@dataclass
class Record:
    period: float
    cycles: List[Cycle]
    status: List[Sample]  # TPDO1 {6041h, 6061h}
    motion: List[Sample]  # TPDO2 {6064h, 606Ch}
    extra: List[Sample]  # TPDO3, as mapped by the test
    emcy: List[can.Message]
    slips: int  # cycles sent late (more than half a period) and re-anchored
    skipped: Set[int] = field(default_factory=set)  # cycles whose SYNC was not sent

    def dump(self, path) -> None:
        """The run as JSON (for a look after a failure)."""
        with open(path, "w") as f:
            json.dump({"period": self.period, "slips": self.slips, "skipped": sorted(self.skipped),
                       "cycles": [asdict(c) for c in self.cycles],
                       **{name: [[x.t, *x.values] for x in getattr(self, name)]
                          for name in ("status", "motion", "extra")}}, f)

    def intervals(self) -> List[float]:
        """SYNC to SYNC, from the kernel timestamps (a skipped SYNC makes one long interval)."""
        return [b.t - a.t for a, b in zip(self.cycles, self.cycles[1:])]

    def regularity(self) -> Dict[str, float]:
        iv = self.intervals()
        T = self.period
        s = sorted(iv)
        return {
            "n": len(self.cycles), "mean_ms": statistics.mean(iv) * 1e3, "sd_ms": statistics.pstdev(iv) * 1e3,
            "min_ms": s[0] * 1e3, "p1_ms": s[len(s) // 100] * 1e3, "p99_ms": s[(99 * len(s)) // 100] * 1e3,
            "max_ms": s[-1] * 1e3, "within_10pct": sum(1 for x in iv if abs(x - T) <= 0.1 * T) / len(iv),
            "within_50pct": sum(1 for x in iv if abs(x - T) <= 0.5 * T) / len(iv), "slips": self.slips,
        }

    def regularity_text(self) -> str:
        r = self.regularity()
        return (f"{r['n']} SYNCs at {self.period * 1e3:g} ms: interval mean {r['mean_ms']:.3f} ms, sd "
                f"{r['sd_ms']:.3f}, min {r['min_ms']:.3f}, p1 {r['p1_ms']:.3f}, p99 {r['p99_ms']:.3f}, max "
                f"{r['max_ms']:.3f}; {100 * r['within_10pct']:.1f} % within +-10 %, {100 * r['within_50pct']:.1f} % "
                f"within +-50 %; {r['slips']} slips")


# ---------------------------------------------------------------- the producer


class CyclicMaster:
    """SYNC producer and command value stream for one axis-1 drive of node `node_id`."""

    def __init__(self, channel: str, node_id: int, tpdo3_format: str = "<ii"):
        self.node_id = node_id
        self.tpdo3_format = tpdo3_format  # struct format of TPDO3's mapping (the test maps it)
        self.rpdo2 = 0x300 + node_id
        self.tpdo1, self.tpdo2, self.tpdo3 = 0x180 + node_id, 0x280 + node_id, 0x380 + node_id
        self.emcy = 0x80 + node_id
        self._tx = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
        self._tx.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_FILTER, b"")  # send only
        self._tx.bind((channel,))
        ids = (COB_SYNC, self.rpdo2, self.tpdo1, self.tpdo2, self.tpdo3, self.emcy)
        self._rx = can.interface.Bus(channel=channel, interface="socketcan", receive_own_messages=False,
                                     can_filters=[{"can_id": i, "can_mask": 0x7FF, "extended": False} for i in ids])
        try:
            self._rx.socket.setsockopt(socket.SOL_SOCKET, SO_RCVBUFFORCE, RECORD_BUFFER)
        except OSError:  # not root: the plain limit (rmem_max); the frame counts show a loss
            self._rx.socket.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECORD_BUFFER)

    def close(self) -> None:
        self._tx.close()
        self._rx.shutdown()

    def _send(self, cob_id: int, data: bytes) -> None:
        frame = CAN_FRAME.pack(cob_id, len(data), data.ljust(8, b"\0"))
        while True:
            try:
                self._tx.send(frame)
                return
            except OSError:  # ENOBUFS: the queue of the interface is full for a moment
                time.sleep(0.0002)

    def run(self, period: float, positions: Sequence[int], velocities: Optional[Sequence[int]] = None,
            skip_sync: Set[int] = frozenset(), settle: float = 0.3) -> Record:
        """Cycle k: RPDO2 {607Ah = positions[k], 60FFh = velocities[k]}, then SYNC (unless k is
        in skip_sync: a SYNC lost on the bus, its RPDO sent all the same). Then `settle` s
        for the last answers, and the record of the run in bus order."""
        velocities = velocities if velocities is not None else [0] * len(positions)
        assert len(velocities) == len(positions)
        while self._rx.recv(timeout=0) is not None:  # only this run's frames
            pass
        sync = b""
        slips = 0
        t0 = time.monotonic() + 0.02
        for k, (p, v) in enumerate(zip(positions, velocities)):
            deadline = t0 + k * period
            now = time.monotonic()
            if deadline > now:
                time.sleep(deadline - now)
            elif now - deadline > period / 2:
                slips += 1
                t0 += now - deadline  # re-anchor: no burst of late cycles
            self._send(self.rpdo2, struct.pack("<ii", p, v))
            if k not in skip_sync:
                self._send(COB_SYNC, sync)
        time.sleep(settle)
        return self._record(period, slips, set(skip_sync))

    def _record(self, period: float, slips: int, skipped: Set[int]) -> Record:
        cycles: List[Cycle] = []
        status: List[Sample] = []
        motion: List[Sample] = []
        extra: List[Sample] = []
        emcy: List[can.Message] = []
        sp, vc = None, None
        while (m := self._rx.recv(timeout=0)) is not None:
            cob, data = m.arbitration_id, bytes(m.data)
            if cob == COB_SYNC:
                assert sp is not None, "a SYNC before any set-point"
                cycles.append(Cycle(len(cycles), m.timestamp, sp, vc))
            elif cob == self.rpdo2:
                sp, vc = struct.unpack("<ii", data)
            elif cob == self.tpdo1:
                status.append(Sample(m.timestamp, struct.unpack("<Hb", data)))
            elif cob == self.tpdo2:
                motion.append(Sample(m.timestamp, struct.unpack("<ii", data)))
            elif cob == self.tpdo3:
                extra.append(Sample(m.timestamp, struct.unpack(self.tpdo3_format, data)))
            elif cob == self.emcy:
                emcy.append(m)
        return Record(period, cycles, status, motion, extra, emcy, slips, skipped)


def attach_sync_samples(rec: Record, motion: bool = True, extra: bool = False) -> None:
    """Synchronous TPDOs (type 1): the drive sends exactly one per SYNC, in SYNC order, so the
    i-th TPDO belongs to the i-th SYNC (whatever the node's latency, even when a TPDO comes
    after the next SYNC)."""
    if motion:
        assert len(rec.motion) == len(rec.cycles), \
            f"{len(rec.motion)} synchronous TPDO2 for {len(rec.cycles)} SYNCs (a TPDO missing or lost)"
        for c, s in zip(rec.cycles, rec.motion):
            c.answered = s.t
            c.position, c.velocity = s.values
    if extra:
        assert len(rec.extra) == len(rec.cycles), \
            f"{len(rec.extra)} synchronous TPDO3 for {len(rec.cycles)} SYNCs (a TPDO missing or lost)"
        for c, s in zip(rec.cycles, rec.extra):
            c.tpdo3 = s.values
