"""The CiA 402 jerk-limited ramp (6086h motion profile type = 3, jerks 60A4h) on vcan,
checked against the closed form of a constant-jerk profile, not against the node's code.

CiA 402-2 names 6086h "motion profile type": 0 linear ramp (trapezoidal profile), 1 sin²
ramp, 2 jerk-free ramp, 3 jerk-limited ramp, and leaves the jerk objects to the drive;
stepnode takes 60A4h (ARRAY of UNSIGNED32, steps/s³) as Nanotec's drives number it: sub 1
begin acceleration, 2 begin deceleration, 3 end acceleration, 4 end deceleration jerk
(README "CiA 402 drive"). A jerk-limited rest-to-rest move with all four jerks J, profile
acceleration and deceleration A and profile velocity V (V·J >= A², so the acceleration
reaches A) is, on each ramp: jerk +J for A/J, constant A for V/A - A/J, jerk -J for A/J;
each ramp takes V/A + A/J and covers V·(V/A + A/J)/2 (the velocity is point-symmetric
about its middle). The trapezoid of 6086h = 0 with the same A and V takes V/A per ramp.

The drive is commanded over its pre-defined RPDOs and observed through its event-driven
TPDO2 {6064h, 606Ch} (10 ms inhibit time), as test_cia402.py does. The shape check does
not need to know when the motion started: each position frame says the axis was at p at
its kernel receive time t, so t - t0 lies between the closed form's instants of p and
p + 1 (± TIME_TOL for User-Mode Linux); the move matches the profile if one start t0 fits
every frame. The same frames are checked not to fit the trapezoid, so the test tells the
two ramps apart.
"""

import math
import struct
from dataclasses import dataclass
from typing import List, Sequence, Tuple

import pytest

from canopen_master import ABORT_NO_SUBINDEX, ABORT_VALUE_RANGE, abort_of
from cia402_master import (
    MODE_PP, MODE_PV, OPERATION_ENABLED, POSITION_ACTUAL, SW_SPEED_ZERO, SW_TARGET_REACHED, Node402, boot_drive,
)

NODE = 44
TIME_TOL = 0.060  # s, as test_cia402.py: User-Mode Linux's scheduling
MOTION_PROFILE_TYPE = 0x6086  # INTEGER16
PROFILE_JERK = 0x60A4  # ARRAY of UNSIGNED32, subs 1..4
LINEAR_RAMP, JERK_LIMITED_RAMP = 0, 3

# V·J = 40 000 000 >= A² = 25 000 000: each ramp has a constant-acceleration phase. A/J is
# half a second so that the two ramps differ by more than the timing tolerance: the jerk
# phases make the S-curve lag the trapezoid by 0.06 s at the first step and by A/(2J) =
# 0.25 s once the velocity is reached, more than the 2 x TIME_TOL a start time can absorb.
V, A, J = 4000, 5000, 10000


# ---------------------------------------------------------------- the closed form

@dataclass
class Segment:
    duration: float  # s
    accel: float  # acceleration at the segment's start (steps/s²)
    jerk: float  # steps/s³


def ramp_up(v: float, a: float, j: float) -> List[Segment]:
    """From rest to v: a trapezoid's ramp when j is 0, else the jerk-limited one."""
    if j == 0:
        return [Segment(v / a, a, 0)]
    assert v * j >= a * a, "the acceleration would not reach a (no constant phase)"
    t_jerk = a / j
    return [Segment(t_jerk, 0, j), Segment(v / a - t_jerk, a, 0), Segment(t_jerk, a, -j)]


def ramp_down(v: float, a: float, j: float) -> List[Segment]:
    return [Segment(s.duration, -s.accel, -s.jerk) for s in ramp_up(v, a, j)]


def ramp_distance(segments: Sequence[Segment]) -> float:
    return Profile(segments).position(sum(s.duration for s in segments))


class Profile:
    """Position against time of a chain of constant-jerk segments, starting at rest at 0."""

    def __init__(self, segments: Sequence[Segment]):
        self.segments = list(segments)
        self.duration = sum(s.duration for s in self.segments)

    def position(self, t: float) -> float:
        p = v = 0.0
        for s in self.segments:
            dt = min(max(t, 0.0), s.duration)
            p += v * dt + s.accel * dt * dt / 2 + s.jerk * dt ** 3 / 6
            v += s.accel * dt + s.jerk * dt * dt / 2
            t -= s.duration
            if t <= 0:
                return p
        return p + v * t  # after the last segment: its final velocity

    def time_of(self, p: float) -> float:
        """The first instant the profile reaches position p (it never moves backwards)."""
        lo, hi = 0.0, 1.0
        while self.position(hi) < p:
            hi *= 2
        for _ in range(60):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if self.position(mid) < p else (lo, mid)
        return hi


def rest_to_rest(distance: float, v: float, a: float, j: float) -> Profile:
    up, down = ramp_up(v, a, j), ramp_down(v, a, j)
    cruise = (distance - 2 * ramp_distance(up)) / v  # the ramp down covers what the ramp up did
    assert cruise >= 0, "the move is too short to reach the profile velocity"
    return Profile(up + [Segment(cruise, 0, 0)] + down)


def start_window(frames, profile: Profile) -> Tuple[float, float]:
    """The motion starts t0 that every position frame allows (lo > hi: none)."""
    lo, hi = -math.inf, math.inf
    for f in frames:
        lo = max(lo, f.t - profile.time_of(f.position + 1) - TIME_TOL)
        hi = min(hi, f.t - profile.time_of(f.position) + TIME_TOL)
    return lo, hi


def test_the_closed_form_itself():
    """The profile's own numbers, from the formulas in the module text."""
    up = ramp_up(V, A, J)
    assert sum(s.duration for s in up) == pytest.approx(V / A + A / J)  # 1.3 s
    assert ramp_distance(up) == pytest.approx(V * (V / A + A / J) / 2)  # 2600 steps
    assert Profile(up).position(A / J) == pytest.approx(J * (A / J) ** 3 / 6)  # the first jerk phase
    move = rest_to_rest(8000, V, A, J)
    assert move.duration == pytest.approx(1.3 + 0.7 + 1.3)
    assert move.position(move.duration) == pytest.approx(8000)
    assert rest_to_rest(8000, V, A, 0).duration == pytest.approx(0.8 + 1.2 + 0.8)


# ---------------------------------------------------------------- the drive

def boot(master, start_node, tmp_path) -> Node402:
    return boot_drive(master, start_node, tmp_path, NODE)


def write_i16(drive, index, value, sub=0):
    drive.master.sdo_download(drive.node.node_id, drive.index(index), sub, struct.pack("<h", value))


def jerk_limited(drive, jerk: int) -> None:
    write_i16(drive, MOTION_PROFILE_TYPE, JERK_LIMITED_RAMP)
    for sub in (1, 2, 3, 4):
        drive.write_u32(PROFILE_JERK, jerk, sub)


@pytest.fixture
def node(master, start_node, tmp_path) -> Node402:
    return boot(master, start_node, tmp_path)


def test_profile_types_and_jerk_objects(node, master):
    drive = node[1]
    # 1 (sin² ramp) and 2 (jerk-free ramp) are types stepnode does not have: a value the
    # object does not take is CiA 301's "value range of parameter exceeded".
    for refused in (1, 2, -1):
        assert abort_of(lambda: write_i16(drive, MOTION_PROFILE_TYPE, refused)) == ABORT_VALUE_RANGE
    jerk_limited(drive, J)
    data = master.sdo_upload(NODE, MOTION_PROFILE_TYPE, 0)
    assert struct.unpack("<h", data)[0] == JERK_LIMITED_RAMP
    assert master.read_u8(NODE, PROFILE_JERK, 0) == 4  # highest sub-index supported
    assert [drive.read_u32(PROFILE_JERK, s) for s in (1, 2, 3, 4)] == [J] * 4
    assert abort_of(lambda: drive.read_u32(PROFILE_JERK, 5)) == ABORT_NO_SUBINDEX


def pp_move(drive, distance: int, timeout: float):
    drive.profile(velocity=V, acceleration=A, deceleration=A)
    drive.enable(MODE_PP)
    mmark = drive.motion_mark()
    ack = drive.set_point(distance)
    done = drive.wait_target_reached(timeout, mark=drive.status_log.index(ack))
    assert OPERATION_ENABLED(done.sw), done
    drive.node.pump(0.1)
    moving = [m for m in drive.motion_log[mmark:] if 0 < m.position < distance]
    assert len(moving) >= 50, f"too few position frames during the move: {len(moving)}"
    assert drive.read_i32(POSITION_ACTUAL) == distance
    assert max(m.position for m in drive.motion_log[mmark:]) == distance, "overshoot"
    return ack, done, moving


def test_pp_move_follows_the_jerk_limited_profile(node):
    drive = node[1]
    distance = 8000
    jerk_limited(drive, J)
    ack, done, moving = pp_move(drive, distance, timeout=6.0)
    s_curve, trapezoid = rest_to_rest(distance, V, A, J), rest_to_rest(distance, V, A, 0)
    print(f"set-point acknowledge -> target reached: {(done.t - ack.t) * 1000:.1f} ms "
          f"(jerk-limited {s_curve.duration * 1000:.0f} ms, trapezoid {trapezoid.duration * 1000:.0f})")
    assert abs((done.t - ack.t) - s_curve.duration) <= TIME_TOL
    lo, hi = start_window(moving, s_curve)
    assert lo <= hi, f"no start fits every position frame: window {lo:.3f} .. {hi:.3f}"
    # The acknowledge is sent as the motion starts.
    assert lo - TIME_TOL <= ack.t <= hi + TIME_TOL, (ack.t, lo, hi)
    lo, hi = start_window(moving, trapezoid)
    assert lo > hi, "the frames fit the trapezoid too: the test cannot tell the ramps apart"


def test_zero_jerks_are_not_limited_a_trapezoid(node):
    """60A4h = 0: "not limited" (README): each phase of jerk takes no time."""
    drive = node[1]
    distance = 8000
    jerk_limited(drive, 0)
    ack, done, moving = pp_move(drive, distance, timeout=5.0)
    trapezoid = rest_to_rest(distance, V, A, 0)
    assert abs((done.t - ack.t) - trapezoid.duration) <= TIME_TOL
    lo, hi = start_window(moving, trapezoid)
    assert lo <= hi, f"no start fits every position frame: window {lo:.3f} .. {hi:.3f}"


def test_pv_reaches_its_velocity_on_the_jerk_limited_ramp(node):
    """PV: the velocity reached bit (10) rises when the ramp of V/A + A/J is over."""
    drive = node[1]
    jerk_limited(drive, J)
    drive.profile(acceleration=A, deceleration=A)
    drive.enable(MODE_PV)
    mmark, mark = drive.motion_mark(), drive.mark()
    drive.targets(velocity=V)
    moving = drive.wait_bits(SW_SPEED_ZERO, False, 1.0, mark, "with speed 0 (bit 12) cleared")
    reached = drive.wait_bits(SW_TARGET_REACHED, True, 3.0, drive.status_log.index(moving),
                              "with velocity reached (bit 10)")
    ramp = Profile(ramp_up(V, A, J))
    print(f"speed 0 cleared -> velocity reached: {(reached.t - moving.t) * 1000:.1f} ms "
          f"(ramp {ramp.duration * 1000:.0f} ms)")
    assert ramp.duration - 2 * TIME_TOL <= reached.t - moving.t <= ramp.duration + TIME_TOL
    frames = [m for m in drive.motion_log[mmark:] if m.t <= reached.t and m.position > 0]
    assert len(frames) >= 30, f"too few position frames on the ramp: {len(frames)}"
    lo, hi = start_window(frames, ramp)
    assert lo <= hi, f"no start fits every position frame: window {lo:.3f} .. {hi:.3f}"
    lo, hi = start_window(frames, Profile(ramp_up(V, A, 0)))
    assert lo > hi, "the ramp fits the trapezoid too"
    drive.targets(velocity=0)
    drive.wait_bits(SW_SPEED_ZERO, True, 3.0, what="with speed 0 after the ramp down")
