"""stepnode as a CiA 402 drive (config `profiles = ["cia402"]`), checked on vcan against the
text of CiA 402-2 with the master in cia402_master.py (not against the node's code).

Every test starts a fresh node. The drive is commanded over its pre-defined RPDOs and
observed through its pre-defined event-driven TPDOs (CiA 402-2 default PDO mapping):

  axis 1: RPDO1 0x200+id {6040h, 6060h}   RPDO2 0x300+id {607Ah, 60FFh}
          TPDO1 0x180+id {6041h, 6061h}   TPDO2 0x280+id {6064h, 606Ch}
  axis 2: the same objects at + 800h on RPDO3/4 (0x400/0x500+id), TPDO3/4 (0x380/0x480+id)

Units are steps (factor group 608Fh/6091h/6092h 1:1). Durations are measured between
kernel receive timestamps of the node's frames and compared with the closed form of the
profile's trapezoid; the tolerance (TIME_TOL) is for User-Mode Linux's scheduling.
Set-up that a master does once (profile parameters, 1016h) goes by SDO.
"""

import time

import pytest

from axis_helpers import HeartbeatSender
from canopen_master import ABORT_VALUE_RANGE, STATE_OPERATIONAL, abort_of
from cia402_master import (
    CW_DISABLE_OPERATION, CW_DISABLE_VOLTAGE, CW_ENABLE_OPERATION, CW_FAULT_RESET, CW_HALT, CW_QUICK_STOP,
    CW_SHUTDOWN, ERROR_CODE, FAULT, FAULT_REACTION_ACTIVE, MODE_PT, MODE_PP, MODE_PV, MODES_DISPLAY,
    MODES_OF_OPERATION, OPERATION_ENABLED, POSITION_ACTUAL, QUICK_STOP_ACTIVE, READY_TO_SWITCH_ON,
    SINGLE_DEVICE_TYPE, STATE_TIMEOUT, STATUSWORD, SUPPORTED_DRIVE_MODES, SW_REMOTE, SW_SET_POINT_ACK,
    SW_SPEED_ZERO, SW_TARGET_REACHED, SWITCH_ON_DISABLED, SWITCHED_ON, VELOCITY_ACTUAL, Node402, state_of,
    state_sequence, sw_text,
)

NODE = 42
MASTER_ID = 0x7F  # the test's own heartbeat (node-ID of the master)
TIME_TOL = 0.060  # s

# CiA 301 1000h: bits 0..15 device profile number 402 (0x0192); bits 16..23 the CiA 402
# type (0x04: stepper drive, as in ETG.6010 / IEC 61800-7-201's device type table).
DEVICE_TYPE_402_STEPPER = 0x00040192
EMCY_HEARTBEAT = 0x8130  # CiA 301 / CiA 402 error code: life guard error or heartbeat error


def trapezoid_time(distance: float, v: float, acc: float, dec: float) -> float:
    """Duration of a rest-to-rest move on a trapezoidal profile (6086h = 0, linear ramp)."""
    d_acc, d_dec = v * v / (2 * acc), v * v / (2 * dec)
    assert d_acc + d_dec <= distance, "triangular profile"
    return v / acc + (distance - d_acc - d_dec) / v + v / dec


def boot(master, start_node, tmp_path, axes=1, operational=True) -> Node402:
    path = tmp_path / "cia402.toml"
    path.write_text(f'axes = {axes}\nprofiles = ["cia402"]\n')
    start_node(NODE, ["--config", path])
    node = Node402(master, NODE, range(1, axes + 1))
    if operational:
        master.nmt_start(NODE)
        if master.wait_heartbeat(NODE, timeout=3.0, state=STATE_OPERATIONAL) != STATE_OPERATIONAL:
            pytest.fail(f"node {NODE} did not confirm NMT operational")
        node.pump(0.3)  # TPDOs sent on entering operational
    return node


@pytest.fixture
def node(master, start_node, tmp_path) -> Node402:
    return boot(master, start_node, tmp_path)


def assert_still(drive, duration=0.3):
    """The motor stands: 606Ch reads 0 and 6064h does not change (SDO)."""
    p0 = drive.read_i32(POSITION_ACTUAL)
    time.sleep(duration)
    p1 = drive.read_i32(POSITION_ACTUAL)
    assert p1 == p0, f"position actual value still changing: {p0} -> {p1}"
    assert drive.read_i32(VELOCITY_ACTUAL) == 0
    return p1


def assert_time(label, got, expect):
    print(f"{label}: {got * 1000:.1f} ms (expected {expect * 1000:.1f} ms)")
    assert abs(got - expect) <= TIME_TOL, f"{label}: {got * 1000:.1f} ms on the bus, expected " \
                                          f"{expect * 1000:.1f} ms (±{TIME_TOL * 1000:.0f})"


# ---------------------------------------------------------------- 1. identity


def test_identity_and_supported_modes(master, start_node, tmp_path):
    node = boot(master, start_node, tmp_path, operational=False)  # SDO only: pre-operational
    drive = node[1]
    assert master.read_u32(NODE, 0x1000) == DEVICE_TYPE_402_STEPPER
    # 67FFh single device type: the axis' own device type, same coding as 1000h.
    assert drive.read_u32(SINGLE_DEVICE_TYPE) == DEVICE_TYPE_402_STEPPER
    # 6502h supported drive modes: bit 0 pp, 2 pv, 5 hm, 6 ip, 7 csp, 8 csv (1 vl, 3 tq and
    # 9 cst are not a stepper's).
    assert drive.read_u32(SUPPORTED_DRIVE_MODES) == 0x1E5
    # 6061h modes of operation display follows an accepted 6060h.
    for mode in (MODE_PV, MODE_PP):
        drive.write_i8(MODES_OF_OPERATION, mode)
        assert drive.read_i8(MODES_OF_OPERATION) == mode
        assert drive.read_i8(MODES_DISPLAY) == mode
    # A mode the drive does not support (4, profile torque) is refused with CiA 301's
    # "invalid value for parameter" and changes nothing.
    assert abort_of(lambda: drive.write_i8(MODES_OF_OPERATION, MODE_PT)) == ABORT_VALUE_RANGE
    assert drive.read_i8(MODES_OF_OPERATION) == MODE_PP
    assert drive.read_i8(MODES_DISPLAY) == MODE_PP


# ---------------------------------------------------------------- 2. the PDS state machine


def test_state_machine_over_pdos(node):
    drive = node[1]
    # Transitions 0 and 1 are automatic: after initialisation the drive is in Switch on disabled.
    sw = drive.read_u16(STATUSWORD)
    assert SWITCH_ON_DISABLED(sw), sw_text(sw)
    # "Enable operation" is no command of Switch on disabled: the state stays.
    mark = drive.mark()
    drive.controlword(CW_ENABLE_OPERATION, MODE_PP)
    node.pump(0.3)
    assert all(SWITCH_ON_DISABLED(f.sw) for f in drive.status_log[mark:]), drive.status_log[mark:]
    assert SWITCH_ON_DISABLED(drive.read_u16(STATUSWORD))
    drive.controlword(CW_DISABLE_VOLTAGE)

    mark = drive.mark()
    seen = drive.enable(MODE_PP)  # transitions 2, 3, 4
    seen.append(drive.command(CW_DISABLE_OPERATION, SWITCHED_ON))  # transition 5
    seen.append(drive.command(CW_SHUTDOWN, READY_TO_SWITCH_ON))  # transition 6
    seen.append(drive.command(CW_DISABLE_VOLTAGE, SWITCH_ON_DISABLED))  # transition 7
    node.pump(0.1)
    assert [f.state for f in seen] == [READY_TO_SWITCH_ON, SWITCHED_ON, OPERATION_ENABLED, SWITCHED_ON,
                                       READY_TO_SWITCH_ON, SWITCH_ON_DISABLED]
    # Each state once, in this order, and no other state in between.
    assert state_sequence(drive.status_log[mark:]) == [
        READY_TO_SWITCH_ON.name, SWITCHED_ON.name, OPERATION_ENABLED.name, SWITCHED_ON.name,
        READY_TO_SWITCH_ON.name, SWITCH_ON_DISABLED.name], drive.status_log[mark:]
    # Bit 9 remote: the controlword is processed (it was, over RPDO1).
    assert all(f.sw & SW_REMOTE for f in seen), seen
    assert seen[2].mode == MODE_PP or drive.read_i8(MODES_DISPLAY) == MODE_PP
    # Transition 8 (Operation enabled -> Ready to switch on on Shutdown) and 9 (-> Switch on
    # disabled on Disable voltage), shortcuts of the same figure.
    drive.enable(MODE_PP)
    drive.command(CW_SHUTDOWN, READY_TO_SWITCH_ON)
    drive.command(CW_ENABLE_OPERATION, OPERATION_ENABLED)  # 0xxx 1111 from Ready: transitions 3 + 4
    drive.command(CW_DISABLE_VOLTAGE, SWITCH_ON_DISABLED)


# ---------------------------------------------------------------- 3. pp: one absolute move


def test_pp_absolute_move_and_its_trapezoid(node):
    drive = node[1]
    v, acc, dec, distance = 4000, 40000, 40000, 2000
    drive.profile(velocity=v, acceleration=acc, deceleration=dec)
    drive.enable(MODE_PP)
    mark, mmark = drive.mark(), drive.motion_mark()
    ack = drive.set_point(distance)
    # The drive assumed the new target: the target (2000) is not reached at that moment.
    assert not ack.sw & SW_TARGET_REACHED, f"set-point acknowledged with target reached on: {ack}"
    done = drive.wait_target_reached(3.0, mark=drive.status_log.index(ack))
    assert OPERATION_ENABLED(done.sw), done
    node.pump(0.1)
    motion = drive.motion_log[mmark:]
    assert motion, "no position TPDO during the move"
    assert motion[-1].position == distance and motion[-1].velocity == 0, motion[-3:]
    assert drive.read_i32(POSITION_ACTUAL) == distance
    assert max(m.position for m in motion) == distance, "overshoot"
    # 0.1 s up to 4000 steps/s, 0.4 s at 4000, 0.1 s down: 0.6 s.
    expect = trapezoid_time(distance, v, acc, dec)
    assert expect == pytest.approx(0.6)
    assert_time("set-point acknowledge -> target reached", done.t - ack.t, expect)
    first = next(m for m in motion if m.position != 0)
    arrived = next(m for m in motion if m.position == distance)
    assert_time("first step -> position 2000 (TPDO2)", arrived.t - first.t, expect)
    # Velocity actual value at the plateau is the profile velocity.
    cruise = [m.velocity for m in motion if first.t + 0.15 <= m.t <= first.t + 0.45]
    assert cruise and all(abs(x - v) <= v // 100 for x in cruise), cruise
    # Target reached stays on at standstill; the set-point acknowledge handshake is over.
    assert drive.sw & SW_TARGET_REACHED and not drive.sw & SW_SET_POINT_ACK, sw_text(drive.sw)


# ---------------------------------------------------------------- 4. pp: relative, buffered, immediate


def test_pp_relative_buffered_and_immediate_set_points(node):
    drive = node[1]
    v, acc = 4000, 40000
    drive.profile(velocity=v, acceleration=acc, deceleration=acc)
    drive.enable(MODE_PP)

    # Bit 6 = 1: the target is relative; twice 1000 -> 2000.
    for expect in (1000, 2000):
        ack = drive.set_point(1000, relative=True)
        drive.wait_target_reached(2.0, mark=drive.status_log.index(ack))
        drive.wait_motion(lambda m: m.velocity == 0 and m.position == expect, 1.0, what=f"at {expect}")
        assert drive.read_i32(POSITION_ACTUAL) == expect

    # Bit 5 = 0 (change set immediately off): a set-point given while moving is processed
    # only when the running positioning is finished. 2000 -> 4000 (0.6 s), then 1000 given
    # 0.15 s in: the drive goes to 4000 first, then back to 1000.
    mmark = drive.motion_mark()
    drive.set_point(4000)
    time.sleep(0.15)
    drive.set_point(1000, release_timeout=1.5)  # bit 12 may stay set while the buffer is full
    drive.wait_motion(lambda m: m.position == 1000 and m.velocity == 0, 3.0, what="at 1000")
    node.pump(0.1)
    assert drive.sw & SW_TARGET_REACHED, sw_text(drive.sw)
    path = drive.motion_log[mmark:]
    top = max(m.position for m in path)
    assert top >= 3990, f"turned back at {top}: the buffered set-point did not wait for 4000: {path}"
    assert drive.read_i32(POSITION_ACTUAL) == 1000

    # Bit 5 = 1 (change set immediately): 1000 -> 2500, and 0.1 s in 5000 at once. The drive
    # does not stop at 2500; the whole run is one 4000-step trapezoid (1.1 s).
    mark, mmark = drive.mark(), drive.motion_mark()
    first_ack = drive.set_point(2500)
    time.sleep(0.1)
    drive.set_point(5000, immediately=True)
    done = drive.wait_status(lambda f: f.sw & SW_TARGET_REACHED and f.t > first_ack.t, 3.0,
                             drive.status_log.index(first_ack), "with target reached")
    drive.wait_motion(lambda m: m.position == 5000 and m.velocity == 0, 1.0, what="at 5000")
    path = drive.motion_log[mmark:]
    moving = [m for m in path if 1000 < m.position < 5000]
    assert moving and all(m.velocity > 0 for m in moving), f"stopped on the way: {path}"
    assert drive.read_i32(POSITION_ACTUAL) == 5000
    at_done = [m for m in path if m.t <= done.t]
    assert at_done and at_done[-1].position > 4900, f"target reached on the way, at {at_done[-1:]}"
    assert_time("1000 -> 5000 changed on the way", done.t - first_ack.t, trapezoid_time(4000, v, acc, acc))


# ---------------------------------------------------------------- 5. pv


def test_pv_velocity_reached_reversal_and_standstill(node):
    drive = node[1]
    acc = 20000
    drive.profile(acceleration=acc, deceleration=acc)
    drive.targets(position=0, velocity=0)
    drive.enable(MODE_PV)
    drive.wait_status(lambda f: f.mode == MODE_PV, STATE_TIMEOUT, what="with modes of operation display 3")
    assert drive.read_i8(MODES_DISPLAY) == MODE_PV

    previous = 0
    for target in (2000, -1000):
        mark, mmark = drive.mark(), drive.motion_mark()
        t0 = time.time()  # the clock of the kernel's receive timestamps
        drive.targets(velocity=target)
        # Bit 10 goes off for the new target (if it was on) and on when the velocity is reached.
        cleared = drive.wait_bits(SW_TARGET_REACHED, False, STATE_TIMEOUT, what="with target reached off")
        reached = drive.wait_status(lambda f: f.sw & SW_TARGET_REACHED, 1.5, max(mark, drive.status_log.index(cleared)),
                                    "with target reached (velocity reached)")
        drive.wait_motion(lambda m: m.velocity == target, 0.5, mmark, f"with 606Ch = {target}")
        # Linear ramp at 6083h/6084h: |2000 - 0| / 20000 = 0.1 s, |-1000 - 2000| / 20000 = 0.15 s.
        assert_time(f"target velocity {previous} -> {target}", reached.t - t0, abs(target - previous) / acc)
        assert not reached.sw & SW_SPEED_ZERO, f"speed = 0 while at {target}: {reached}"
        assert OPERATION_ENABLED(reached.sw), reached
        node.pump(0.2)
        assert drive.read_i32(VELOCITY_ACTUAL) == target
        previous = target
    p0 = drive.read_i32(POSITION_ACTUAL)
    time.sleep(0.2)
    assert drive.read_i32(POSITION_ACTUAL) < p0 - 100, "not moving backwards at -1000"

    mark = drive.mark()
    drive.targets(velocity=0)
    # Bit 12 in pv: speed is equal 0.
    stopped = drive.wait_bits(SW_SPEED_ZERO, True, 1.0, mark, "with speed = 0 (bit 12)")
    assert OPERATION_ENABLED(stopped.sw), stopped
    node.pump(0.1)
    assert drive.sw & SW_TARGET_REACHED and drive.sw & SW_SPEED_ZERO, sw_text(drive.sw)
    assert drive.motion_log[-1].velocity == 0, drive.motion_log[-3:]
    assert_still(drive)


# ---------------------------------------------------------------- 6. quick stop


def test_quick_stop_during_pv(node, master):
    drive = node[1]
    assert master.read_u16(NODE, 0x605A) == 2  # slow down on quick stop ramp, then Switch on disabled
    decel = master.read_u32(NODE, 0x6085)
    assert decel == 10000
    drive.profile(acceleration=20000, deceleration=20000)
    drive.targets(velocity=0)
    drive.enable(MODE_PV)
    drive.targets(velocity=2000)
    drive.wait_motion(lambda m: m.velocity == 2000, 1.0, what="at 2000")
    drive.wait_target_reached(1.0)

    mark, mmark = drive.mark(), drive.motion_mark()
    drive.controlword(CW_QUICK_STOP)  # 0xxx x01x: transition 11
    active = drive.wait_state(QUICK_STOP_ACTIVE, STATE_TIMEOUT, mark)
    # Quick stop option 2: after the stop on 6085h, transition 12 to Switch on disabled.
    disabled = drive.wait_state(SWITCH_ON_DISABLED, 1.0, mark)
    assert state_sequence(drive.status_log[mark:]) == [QUICK_STOP_ACTIVE.name, SWITCH_ON_DISABLED.name], \
        drive.status_log[mark:]
    node.pump(0.1)
    ramp = drive.motion_log[mmark:]
    assert ramp and ramp[-1].velocity == 0, ramp[-3:]
    stop_at = next(m.t for m in ramp if m.velocity == 0)
    assert stop_at <= disabled.t + 0.02, "Switch on disabled before the motor stood"
    assert_time("quick stop ramp 2000 -> 0 at 6085h", disabled.t - active.t, 2000 / decel)
    # 2000^2 / (2 * 10000) = 200 steps on the ramp.
    assert abs((ramp[-1].position - ramp[0].position) - 200) <= 50, ramp
    assert_still(drive)
    assert SWITCH_ON_DISABLED(drive.read_u16(STATUSWORD))


# ---------------------------------------------------------------- 7. a lost master


def test_lost_master_heartbeat_is_a_fault(node, master):
    drive = node[1]
    assert master.read_u16(NODE, 0x6007) == 1  # abort connection option: fault signal
    hb = HeartbeatSender(MASTER_ID, 0.05).start()
    try:
        # 1016h:1: consume the master's heartbeat, 200 ms. 1029h:1 = 1 (CiA 301: no NMT state
        # change on a communication error), so the TPDOs keep showing what the drive does.
        master.write_u32(NODE, 0x1016, 1, (MASTER_ID << 16) | 200)
        master.write_u8(NODE, 0x1029, 1, 1)
        drive.profile(acceleration=20000, deceleration=20000)
        drive.targets(velocity=0)
        drive.enable(MODE_PV)
        drive.targets(velocity=2000)
        drive.wait_motion(lambda m: m.velocity == 2000, 1.0, what="at 2000")
        node.pump(0.4)
        assert OPERATION_ENABLED(drive.sw), "left Operation enabled while the heartbeat was there"

        emark, mark, mmark = len(node.emcys), drive.mark(), drive.motion_mark()
        hb.stop()
        last_beat = hb.last_sent
        fault = drive.wait_state(FAULT, 2.0, mark)
        states = state_sequence(drive.status_log[mark:])
        assert states in ([FAULT.name], [FAULT_REACTION_ACTIVE.name, FAULT.name]), drive.status_log[mark:]
        first = drive.status_log[mark]
        assert 0.18 <= first.t - last_beat <= 0.2 + 0.25, \
            f"fault {1000 * (first.t - last_beat):.0f} ms after the last heartbeat (timeout 200 ms)"
        if first.state is FAULT_REACTION_ACTIVE:
            # 605Eh fault reaction option 2: slow down on the quick stop ramp (6085h), then
            # transition 14 to Fault once the reaction is completed.
            assert master.read_u16(NODE, 0x605E) == 2
            assert_time("fault reaction 2000 -> 0 at 6085h", fault.t - first.t, 2000 / master.read_u32(NODE, 0x6085))
        emcy = node.wait_emcy(EMCY_HEARTBEAT, emark)
        assert emcy.error_register & 0x01, f"EMCY error register 0x{emcy.error_register:02X}: generic error bit off"
        assert drive.read_u16(ERROR_CODE) == EMCY_HEARTBEAT
        assert FAULT(drive.read_u16(STATUSWORD))
        drive.wait_motion(lambda m: m.velocity == 0, 1.0, mmark, "at standstill")
        assert_still(drive)
        assert FAULT(drive.sw), f"left Fault by itself: {drive.status_log[-3:]}"

        # The master is back; a fault reset (0 -> 1 edge of bit 7) leads to Switch on disabled.
        hb = HeartbeatSender(MASTER_ID, 0.05).start()
        time.sleep(0.4)
        drive.controlword(CW_DISABLE_VOLTAGE)
        reset = drive.command(CW_FAULT_RESET, SWITCH_ON_DISABLED)  # transition 15
        assert not reset.sw & 0x08, reset
        drive.controlword(CW_DISABLE_VOLTAGE)
        # And the drive can be enabled again.
        drive.targets(velocity=0)
        drive.enable(MODE_PV)
    finally:
        hb.close()


# ---------------------------------------------------------------- 8. axis 2


def test_axis_2_on_its_own_pdos_while_axis_1_stands(master, start_node, tmp_path):
    node = boot(master, start_node, tmp_path, axes=2)
    a1, a2 = node[1], node[2]
    assert (a2.rpdo_cw, a2.rpdo_targets, a2.tpdo_status, a2.tpdo_motion) == (
        0x400 + NODE, 0x500 + NODE, 0x380 + NODE, 0x480 + NODE)
    assert a2.index(0x6040) == 0x6840
    a2.profile(velocity=4000, acceleration=40000, deceleration=40000)  # 6881h, 6883h, 6884h
    assert master.read_u32(NODE, 0x6081) == 1000, "axis 2's profile velocity written into axis 1's"
    a1.enable(MODE_PP)  # axis 1 enabled, at rest, no set-point
    mark1, mmark1 = a1.mark(), a1.motion_mark()

    a2.enable(MODE_PP)
    mark = a2.mark()
    ack = a2.set_point(1000)
    done = a2.wait_target_reached(2.0, a2.status_log.index(ack))
    assert_time("axis 2: 1000 steps", done.t - ack.t, trapezoid_time(1000, 4000, 40000, 40000))
    a2.wait_motion(lambda m: m.position == 1000 and m.velocity == 0, 1.0, what="at 1000")
    assert a2.read_i32(POSITION_ACTUAL) == 1000  # 6864h
    assert state_sequence(a2.status_log[mark:])[-1] == OPERATION_ENABLED.name

    # Axis 1 saw nothing of it: no statusword change, no position frame, at 0.
    assert all(OPERATION_ENABLED(f.sw) for f in a1.status_log[mark1:]), a1.status_log[mark1:]
    assert all(m.position == 0 and m.velocity == 0 for m in a1.motion_log[mmark1:]), a1.motion_log[mmark1:]
    assert OPERATION_ENABLED(a1.read_u16(STATUSWORD))
    assert a1.read_i32(POSITION_ACTUAL) == 0
    # The simulated machine (stepnode's 0x5n03, the load position of motor n): only motor 2 moved.
    assert master.read_i32(NODE, 0x5003) == 0
    assert master.read_i32(NODE, 0x5103) == 1000


# ---------------------------------------------------------------- 9. pp: halt


def test_pp_halt_stops_on_profile_deceleration(node, master):
    drive = node[1]
    assert master.read_u16(NODE, 0x605D) == 1  # halt option: slow down on profile deceleration
    v, dec = 4000, 40000
    drive.profile(velocity=v, acceleration=40000, deceleration=dec)
    drive.enable(MODE_PP)
    drive.set_point(20000)
    drive.wait_motion(lambda m: m.velocity == v, 1.0, what="at the profile velocity")
    mark, mmark = drive.mark(), drive.motion_mark()
    t0 = time.time()
    drive.controlword(drive.cw | CW_HALT)  # bit 8
    stop = drive.wait_motion(lambda m: m.velocity == 0, 1.0, mmark, "at standstill")
    assert_time("halt ramp 4000 -> 0 at 6084h", stop.t - t0, v / dec)
    # Bit 10 with halt = 1: the velocity of the axis is 0. The state stays Operation enabled.
    halted = drive.wait_target_reached(STATE_TIMEOUT, mark)
    assert OPERATION_ENABLED(halted.sw), halted
    assert all(OPERATION_ENABLED(f.sw) for f in drive.status_log[mark:]), drive.status_log[mark:]
    p = assert_still(drive)
    assert p < 20000
    assert state_of(drive.read_u16(STATUSWORD)) is OPERATION_ENABLED


# ---------------------------------------------------------------- 10. a fault that is still there


def test_fault_reset_while_the_master_is_still_lost_keeps_the_fault(node, master):
    """CiA 402-2, transition 15 (Fault -> Switch on disabled on Fault reset): "a reset of the
    fault condition is carried out if no fault exists currently". The master's heartbeat
    is still missing (the consumer of 1016h has seen none since the timeout), so the
    condition behind 603Fh = 8130h persists and the drive stays in Fault."""
    drive = node[1]
    hb = HeartbeatSender(MASTER_ID, 0.05).start()
    try:
        master.write_u32(NODE, 0x1016, 1, (MASTER_ID << 16) | 200)
        master.write_u8(NODE, 0x1029, 1, 1)
        drive.profile(acceleration=20000, deceleration=20000)
        drive.targets(velocity=0)
        drive.enable(MODE_PV)
        drive.targets(velocity=2000)
        drive.wait_motion(lambda m: m.velocity == 2000, 1.0, what="at 2000")
        mark = drive.mark()
        hb.stop()
        drive.wait_state(FAULT, 2.0, mark)
        emark, mark = len(node.emcys), drive.mark()
        drive.controlword(CW_DISABLE_VOLTAGE)
        drive.controlword(CW_FAULT_RESET)  # 0 -> 1 edge of bit 7, no heartbeat yet
        node.pump(0.4)
        sw = drive.read_u16(STATUSWORD)
        assert FAULT(sw), f"fault reset with the master still lost: 6041h {sw_text(sw)}, TPDO1 frames " \
                          f"{drive.status_log[mark:]}, EMCYs {[hex(e.error_code) for e in node.emcys[emark:]]}, " \
                          f"603Fh 0x{drive.read_u16(ERROR_CODE):04X}"
        assert drive.read_u16(ERROR_CODE) == EMCY_HEARTBEAT
    finally:
        hb.close()
