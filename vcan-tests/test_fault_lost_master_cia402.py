"""A CiA 402 drive whose master is lost mid-move, and a master's controlword during the
reaction that follows (issue 14). 6007h (abort connection option code, CiA 402-2) picks the
reaction; what a controlword can still do then is the state machine's (CiA 402-2, "PDS
FSA"): the command "disable voltage" takes transitions 7, 9, 10 and 12, "quick stop"
7, 10 and 11, and no command leaves Fault reaction active (only transition 14, once the
reaction is completed).

- 6007h = 3 (quick stop command): Operation enabled -> Quick stop active (transition 11),
  with 605Ah = 1 a slow down on the slow down ramp (6084h). Quick stop is what the drive
  already does; the master's way to stop at once is "disable voltage": transition 12 to
  Switch on disabled, the drive function disabled, no step more (README "CiA 402 drive":
  "Disable drive function" stops the pulses at once).
- 6007h = 1 (fault signal): Fault reaction active, with 605Eh = 1 the same slow down ramp.
  A quick stop (or disable voltage) sent during it is no transition: the reaction runs
  to its end, then Fault.

Ramps are from the objects (v^2 / (2 * 6084h), linear: 6086h = 0), not from a run. The
drive runs in pv at 2000 steps/s; 1029h:1 = 1 keeps the node operational so its TPDOs
show the reaction; the controlword goes over RPDO1 as the master sends it.
"""

from __future__ import annotations

import time

import pytest

from axis_helpers import HeartbeatSender
from cia402_master import (
    CW_DISABLE_VOLTAGE, CW_QUICK_STOP, FAULT, FAULT_REACTION_ACTIVE, MODE_PV, QUICK_STOP_ACTIVE, STATUSWORD,
    SWITCH_ON_DISABLED, Node402, boot_drive, state_sequence,
)

NODE = 42
MASTER = 0x7F
VELOCITY = 2000          # steps/s
SLOW_DOWN = 1000         # 6084h, steps/s^2: 2 s and 2000 steps from 2000 steps/s
FAR_BELOW = 4            # "at once": at most a quarter of the steps the ramp had left
MEANINGFUL = 500         # the command must come while the ramp has this many steps to go
RAMP_TOL = 100           # steps: 5 % of the ramp, for the TPDO sampling of the start


def boot(master, start_node, tmp_path) -> Node402:
    return boot_drive(master, start_node, tmp_path, NODE)


def ramp_steps(velocity: float) -> float:
    return velocity * velocity / (2 * SLOW_DOWN)


def at_or_before(log, t: float):
    before = [m for m in log if m.t <= t]
    assert before, f"no position/velocity frame before {t}"
    return before[-1]


def first_after(log, t: float):
    after = [m for m in log if m.t > t]
    assert after, f"no position/velocity frame after {t}"
    return after[0]


def run_and_lose_the_master(master, node, abort_option: int):
    """pv at VELOCITY with the master's heartbeat consumed, then the heartbeat stops; the
    drive, the status mark before the loss, and the HeartbeatSender (stopped)."""
    drive = node[1]
    hb = HeartbeatSender(MASTER, 0.05).start()
    master.write_u32(NODE, 0x1016, 1, (MASTER << 16) | 200)
    master.write_u8(NODE, 0x1029, 1, 1)
    master.sdo_download(NODE, 0x6007, 0, abort_option.to_bytes(2, "little", signed=True))
    master.sdo_download(NODE, 0x605A, 0, (1).to_bytes(2, "little", signed=True))  # slow down ramp
    master.sdo_download(NODE, 0x605E, 0, (1).to_bytes(2, "little", signed=True))  # slow down ramp
    drive.profile(acceleration=20000, deceleration=SLOW_DOWN)
    drive.targets(velocity=0)
    drive.enable(MODE_PV)
    drive.targets(velocity=VELOCITY)
    drive.wait_motion(lambda m: m.velocity == VELOCITY, 2.0, what=f"at {VELOCITY}")
    node.pump(0.3)
    mark = drive.mark()
    hb.stop()
    return drive, mark, hb


def test_disable_voltage_during_the_quick_stop_of_a_lost_master_stops_at_once(master, start_node, tmp_path):
    node = boot(master, start_node, tmp_path)
    drive, mark, hb = run_and_lose_the_master(master, node, 3)
    try:
        qsa = drive.wait_state(QUICK_STOP_ACTIVE, 2.0, mark)
        t_cmd = time.time()
        drive.controlword(CW_DISABLE_VOLTAGE)  # transition 12
        off = drive.wait_state(SWITCH_ON_DISABLED, 2.0, mark)
        drive.wait_motion(lambda m: m.t > off.t, 2.0, what="after Switch on disabled")
        node.pump(0.3)
        before = at_or_before(drive.motion_log, t_cmd)
        behind = first_after(drive.motion_log, t_cmd)
        end = before.position + ramp_steps(before.velocity)
        left, final = end - behind.position, drive.motion_log[-1].position
        print(f"\ndisable voltage in Quick stop active: sent between {before} and {behind}, the ramp ends at "
              f"{end:.0f} ({left:.0f} steps left); stood at {final}, {final - before.position} steps after")
        assert left >= MEANINGFUL, f"the command came too late in the ramp ({left:.0f} steps left)"
        assert final - before.position <= left / FAR_BELOW, f"{final - before.position} steps after disable voltage"
        assert state_sequence(drive.status_log[mark:]) == [QUICK_STOP_ACTIVE.name, SWITCH_ON_DISABLED.name], \
            drive.status_log[mark:]
        assert qsa.t < off.t
        time.sleep(ramp_steps(VELOCITY) / VELOCITY * 2)  # longer than the whole ramp
        assert drive.read_i32(0x6064) == final and master.read_i32(NODE, 0x5003) == final
        assert SWITCH_ON_DISABLED(drive.read_u16(STATUSWORD))
    finally:
        hb.close()


def test_a_quick_stop_during_the_fault_reaction_of_a_lost_master_is_no_transition(master, start_node, tmp_path):
    node = boot(master, start_node, tmp_path)
    drive, mark, hb = run_and_lose_the_master(master, node, 1)
    try:
        fra = drive.wait_state(FAULT_REACTION_ACTIVE, 2.0, mark)
        start = at_or_before(drive.motion_log, fra.t)
        end = start.position + ramp_steps(start.velocity)
        drive.controlword(CW_QUICK_STOP)
        drive.controlword(CW_DISABLE_VOLTAGE)
        fault = drive.wait_state(FAULT, 5.0, mark)
        node.pump(0.3)
        final = drive.motion_log[-1].position
        print(f"\nquick stop and disable voltage in Fault reaction active: the ramp began at {start}, ends at "
              f"{end:.0f}; stood at {final}")
        assert state_sequence(drive.status_log[mark:]) == [FAULT_REACTION_ACTIVE.name, FAULT.name], \
            drive.status_log[mark:]
        assert abs(final - end) <= RAMP_TOL, f"stood at {final}: the slow down ramp (605Eh = 1) ends at {end:.0f}"
        # Transition 14 once the reaction is completed: nothing moves in Fault.
        assert not [m for m in drive.motion_log if m.t > fault.t and m.position != final], "moved in Fault"
        assert master.read_i32(NODE, 0x5003) == final
    finally:
        hb.close()
