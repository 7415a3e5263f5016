"""A garbage flood during a long move (issue 14): while axis 1 makes a 45,000-step move,
another process fills the bus for 10 s with random frames, at the rate a saturated
500 kbit/s bus carries (about 4,000 frames/s of 8 bytes). The garbage is what a faulty
device could put on a real network:

- random standard frames on every COB-ID that does not legitimately command this node
  (not NMT 0x000, SYNC 0x080, TIME 0x100, its RPDOs, its SDO channels, LSS 0x7E5) nor is
  this node's own (its EMCY, TPDOs, SDO answers and heartbeat: another device on them is a
  duplicate node-ID, README "Duplicate node-ID"); random extended frames; remote frames;
- malformed frames on the commanding COB-IDs, each one that would act if the node took
  it: NMT stop/reset of DLC != 2 (CiA 301: an NMT command is 2 bytes), RPDOs shorter
  than their mapping carrying %Q15/%Q16 (CiA 301: not processed, EMCY 0x8210), an SDO
  expedited download of %Q16 into 0x2000 cut below 8 bytes (an SDO frame is 8 bytes: the
  server must refuse it, never write), LSS switch/configure/inquire requests that are not
  8 bytes (CiA 305 frames are 8 bytes; README "LSS": no answer), SYNCs with data.

After the flood the move is exact (motor and simulated machine at the destination, no
error, position valid), the node stayed operational, its heartbeat never went missing
for longer than a master's consumer would allow (1.5 times the producer time), it answered
SDO on a second channel during the flood and answers on the default one after it, and an
RPDO command is obeyed again. The flood's seed: $STEPNODE_FLOOD_SEED (default 14).
"""

from __future__ import annotations

import multiprocessing
import os
import random
import struct
import threading
import time
from typing import Dict, List, Tuple

import can
import pytest

from axis_helpers import FAST, MOVING, NODE, VALID, ax, link, set_position
from canopen_master import STATE_OPERATIONAL
from conftest import CHANNEL, open_bus

_ = (link, ax)  # fixtures

DISTANCE = 45_000
FLOOD_SECONDS = 10.0
FLOOD_RATE = 4000  # frames/s
HB_MS = 250
HB_CONSUMER_FACTOR = 1.5  # a master's consumer time for this producer: 375 ms
SEED = int(os.environ.get("STEPNODE_FLOOD_SEED", "14"))
# The second SDO server channel (0x1201), kept out of the flood, for reads during it.
SDO2_RX, SDO2_TX = 0x690, 0x6D0  # free CAN-IDs (README "SDO channels")
CMD, STATUS, MOTOR = 0x2000, 0x2001, 0x2005
SIM_MECH = 0x5003
EMCY_RPDO_LENGTH = 0x8210
ABORT_COMMAND_SPECIFIER = 0x05040001
Q15_Q16 = 0xC000


# ---------------------------------------------------------------- the node's PDOs


def pdo_cob_ids(master, base: int) -> List[int]:
    """The COB-IDs of the valid PDOs with communication parameters at base, base+1, ..."""
    out = []
    for n in range(512):
        try:
            cob = master.read_u32(NODE, base + n, 1)
        except Exception:  # no such PDO: the last one was before it
            break
        if not cob & 0x80000000:
            out.append(cob & 0x7FF)
    return out


def rpdo_lengths(master) -> Dict[int, int]:
    """COB-ID -> mapped length in bytes of every valid RPDO (CiA 301 mapping entries:
    index << 16 | sub << 8 | length in bits)."""
    out = {}
    for n in range(512):
        try:
            cob = master.read_u32(NODE, 0x1400 + n, 1)
        except Exception:
            break
        if cob & 0x80000000:
            continue
        count = master.read_u8(NODE, 0x1600 + n, 0)
        bits = sum(master.read_u32(NODE, 0x1600 + n, k) & 0xFF for k in range(1, count + 1))
        out[cob & 0x7FF] = bits // 8
    return out


# ---------------------------------------------------------------- the flood (another process)


def malformed(rng: random.Random, rpdos: Dict[int, int]) -> Tuple[int, bytes]:
    kind = rng.randrange(5)
    if kind == 0:  # NMT stop / pre-op / reset node / reset comm for this node or all, DLC != 2
        cmd = bytes([rng.choice((0x02, 0x80, 0x81, 0x82)), rng.choice((0, NODE))]) + bytes(6)
        return 0x000, cmd[:rng.choice((0, 1, 3, 4, 8))]
    if kind == 1:  # an RPDO shorter than its mapping, %Q15 and %Q16 in its first word
        cob = rng.choice([c for c, n in rpdos.items() if n > 0])
        data = struct.pack("<H", Q15_Q16) + bytes(rng.randrange(256) for _ in range(6))
        return cob, data[:rng.randrange(rpdos[cob])]
    if kind == 2:  # expedited download 0x2000:00 = 0x8000 (%Q16), cut short
        return 0x600 + NODE, bytes([0x2B, 0x00, 0x20, 0x00, 0x00, 0x80, 0, 0])[:rng.randrange(8)]
    if kind == 3:  # LSS switch global to configuration, configure node-ID 0x33, inquire node-ID
        req = rng.choice((bytes([0x04, 0x01]), bytes([0x11, 0x33]), bytes([0x5E])))
        return 0x7E5, (req + bytes(8))[:rng.randrange(8)]
    return 0x080, bytes(rng.randrange(256) for _ in range(rng.randrange(2, 9)))  # SYNC with data


def garbage(rng: random.Random, allowed: List[int], rpdos: Dict[int, int]) -> can.Message:
    r = rng.random()
    data = bytes(rng.randrange(256) for _ in range(rng.randrange(9)))
    if r < 0.06:
        cob, data = malformed(rng, rpdos)
        return can.Message(arbitration_id=cob, data=data, is_extended_id=False)
    if r < 0.10:
        return can.Message(arbitration_id=rng.randrange(1 << 29), data=data, is_extended_id=True)
    if r < 0.12:
        return can.Message(arbitration_id=rng.choice(allowed), is_remote_frame=True, dlc=rng.randrange(9),
                           is_extended_id=False)
    return can.Message(arbitration_id=rng.choice(allowed), data=data, is_extended_id=False)


def flood(allowed: List[int], rpdos: Dict[int, int], seconds: float, rate: int, seed: int, sent) -> None:
    """Runs in its own process: `rate` frames/s for `seconds`, paced in 10 ms slices."""
    rng = random.Random(seed)
    bus = can.interface.Bus(channel=CHANNEL, interface="socketcan", receive_own_messages=False)
    bus.set_filters([{"can_id": 0x7FF, "can_mask": 0x7FF, "extended": True}])  # receive nothing
    start = time.monotonic()
    n = 0
    try:
        while (now := time.monotonic() - start) < seconds:
            due = int(now * rate) + rate // 100
            while n < due:
                try:
                    bus.send(garbage(rng, allowed, rpdos), timeout=0.2)
                    n += 1
                except can.CanError:
                    time.sleep(0.001)  # the interface's queue is full: a busy bus
            time.sleep(0.01)
    finally:
        sent.value = n
        bus.shutdown()


# ---------------------------------------------------------------- what the node sends meanwhile


class Listener:
    """The node's heartbeat, EMCYs, SDO answers and any LSS answer, on a filtered socket
    (the kernel drops the garbage before it reaches the test)."""

    def __init__(self):
        ids = (0x700 + NODE, 0x080 + NODE, 0x580 + NODE, 0x7E4)
        self.bus = can.interface.Bus(channel=CHANNEL, interface="socketcan", receive_own_messages=False,
                                     can_filters=[{"can_id": i, "can_mask": 0x7FF, "extended": False} for i in ids])
        self.frames: List[can.Message] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        while not self._stop.is_set():
            msg = self.bus.recv(timeout=0.1)
            if msg is not None:
                self.frames.append(msg)

    def close(self) -> List[can.Message]:
        self._stop.set()
        self._thread.join(2)
        self.bus.shutdown()
        return self.frames


class SecondChannel:
    """Expedited uploads on SDO server channel 2 (CiA 301 7.2.4.3.3: request 0x40, index
    LE, sub; the answer scs 2 with e = s = 1), on its own filtered socket."""

    def __init__(self):
        self.bus = can.interface.Bus(channel=CHANNEL, interface="socketcan", receive_own_messages=False,
                                     can_filters=[{"can_id": SDO2_TX, "can_mask": 0x7FF, "extended": False}])

    def read_i32(self, index: int, sub: int = 0, tries: int = 3) -> Tuple[int, object]:
        """(requests sent, value or None). A master repeats a read that timed out (stepctl
        up to 3 times): the node may have lost the request at a full receive queue (it says
        so: EMCY 0x8110, 0x2F10)."""
        for n in range(1, tries + 1):
            value = self.read_once(index, sub)
            if value is not None:
                return n, value
        return tries, None

    def read_once(self, index: int, sub: int = 0, timeout: float = 1.0):
        self.bus.send(can.Message(arbitration_id=SDO2_RX, is_extended_id=False,
                                  data=bytes([0x40, index & 0xFF, index >> 8, sub, 0, 0, 0, 0])))
        deadline = time.monotonic() + timeout
        while (remaining := deadline - time.monotonic()) > 0:
            r = self.bus.recv(timeout=remaining)
            if r is not None and len(r.data) == 8 and r.data[0] & 0xE3 == 0x43 and \
                    bytes(r.data[1:4]) == bytes([index & 0xFF, index >> 8, sub]):
                return struct.unpack_from("<i", bytes(r.data), 4)[0]
        return None

    def close(self):
        self.bus.shutdown()


def heartbeat_gaps(frames: List[can.Message]) -> List[float]:
    beats = [m.timestamp for m in frames if m.arbitration_id == 0x700 + NODE]
    return [b - a for a, b in zip(beats, beats[1:])]


def run_flood(allowed: List[int], rpdos: Dict[int, int], listener: Listener):
    """The flood in another process while a second SDO channel reads the motor position
    every 0.25 s: (frames sent, the reads, the flood's seconds, the listener's frame count
    at its end: later frames answer the test's own requests)."""
    second = SecondChannel()
    sent = multiprocessing.get_context("fork").Value("l", 0)
    flooder = multiprocessing.get_context("fork").Process(
        target=flood, args=(allowed, rpdos, FLOOD_SECONDS, FLOOD_RATE, SEED, sent), daemon=True)
    t0 = time.monotonic()
    flooder.start()
    reads: List[Tuple[int, object]] = []
    try:
        while flooder.is_alive() and time.monotonic() - t0 < FLOOD_SECONDS + 20:
            reads.append(second.read_i32(MOTOR))
            time.sleep(0.25)
        flooder.join(5)
        flood_s = time.monotonic() - t0
        time.sleep(0.3)  # the node's answers to the last garbage
        return sent.value, reads, flood_s, len(listener.frames)
    finally:
        if flooder.is_alive():
            flooder.kill()
        second.close()


# ---------------------------------------------------------------- the test


def test_a_garbage_flood_during_a_move_leaves_the_move_exact_and_the_node_serving(link, ax, master):
    master.write_u16(NODE, 0x1017, 0, HB_MS)
    master.write_u32(NODE, 0x1201, 1, SDO2_RX)
    master.write_u32(NODE, 0x1201, 2, SDO2_TX)
    rpdos = rpdo_lengths(master)
    own = set(pdo_cob_ids(master, 0x1800)) | {0x080 + NODE, 0x580 + NODE, 0x700 + NODE}
    commanding = set(rpdos) | {0x000, 0x080, 0x100, 0x600 + NODE, SDO2_RX, SDO2_TX, 0x7E5, 0x7E4}
    allowed = [i for i in range(0x800) if i not in own | commanding]
    assert 0x200 + NODE in rpdos and rpdos[0x200 + NODE] == 6, rpdos  # RPDO1: command bits + destination

    set_position(ax, 0)
    mark = ax.mark()
    ax.command("rel", DISTANCE)  # about 11.3 s at FAST's 4000 steps/s
    ax.wait_status(lambda s: s == MOVING | VALID, 5.0, mark, "running")

    listener = Listener()
    sent, reads, flood_s, during = run_flood(allowed, rpdos, listener)
    # The move goes on after the flood: wait for its end over SDO (the test's own socket is
    # full of garbage; drop it).
    master.flush()
    deadline = time.monotonic() + 30
    while master.read_u16(NODE, STATUS) & MOVING:
        assert time.monotonic() < deadline, "still moving 30 s after the flood"
        time.sleep(0.1)
    frames = listener.close()

    gaps = heartbeat_gaps(frames)
    states = {m.data[0] for m in frames if m.arbitration_id == 0x700 + NODE}
    emcys = [struct.unpack_from("<H", bytes(m.data).ljust(8, b"\0"))[0] for m in frames
             if m.arbitration_id == 0x080 + NODE]
    sdo = [bytes(m.data) for m in frames[:during] if m.arbitration_id == 0x580 + NODE]
    lss = [m for m in frames if m.arbitration_id == 0x7E4]
    answered = [p for _, p in reads if p is not None]
    repeated = sum(n - 1 for n, _ in reads)
    dropped = master.read_u32(NODE, 0x2F10)
    print(f"\nflood: {sent} frames in {flood_s:.1f} s ({sent / FLOOD_SECONDS:.0f}/s, seed {SEED}); "
          f"heartbeat gaps max {max(gaps) * 1000:.0f} ms (period {HB_MS} ms, {len(gaps)} gaps); "
          f"second-channel reads {len(answered)}/{len(reads)} ({repeated} repeated); frames the node's socket "
          f"dropped (0x2F10) {dropped}; EMCYs {sorted({hex(c) for c in emcys})}; "
          f"SDO answers to the cut-short downloads {len(sdo)}, abort codes "
          f"{sorted({hex(struct.unpack_from('<I', d, 4)[0]) for d in sdo})}")

    assert sent >= FLOOD_RATE * FLOOD_SECONDS * 0.5, f"only {sent} frames sent: no flood"
    # The move is exact and ended as a move ends: at the destination, no error, position valid.
    assert master.read_i32(NODE, MOTOR) == DISTANCE
    assert master.read_i32(NODE, SIM_MECH) == DISTANCE, "the simulated machine made another step count"
    assert master.read_u16(NODE, STATUS) == VALID
    # Operational all along, and never silent for longer than a master's consumer allows.
    assert states == {STATE_OPERATIONAL}, f"heartbeat states {states}"
    assert gaps and max(gaps) <= HB_CONSUMER_FACTOR * HB_MS / 1000, \
        f"a heartbeat gap of {max(gaps) * 1000:.0f} ms (period {HB_MS} ms)"
    # SDO answered during the flood (a request lost at a full receive queue is repeated, as
    # a master does), each read a position on the way to the destination.
    assert len(answered) == len(reads) and answered == sorted(answered), reads
    # The cut-short frames: the RPDOs reported as CiA 301's length error, the SDO requests
    # refused with an abort (never a download confirmation), LSS silent.
    assert EMCY_RPDO_LENGTH in emcys, f"no EMCY 0x8210 for the short RPDOs: {emcys}"
    assert sdo and all(d[0] == 0x80 for d in sdo), f"SDO server answers that are not aborts: {sdo[:5]}"
    assert not lss, f"LSS answers to frames that are not 8 bytes: {lss[:3]}"
    # And the node still obeys a good RPDO command (frames the SDO reads left in the
    # master's backlog are recorded first, so only TPDOs after the command count).
    ax.link.pump(0.5)
    mark = ax.mark()
    ax.command("rel", 100)
    assert ax.wait_stopped(mark, 5.0)[-1].position == DISTANCE + 100
    assert master.read_i32(NODE, SIM_MECH) == DISTANCE + 100
