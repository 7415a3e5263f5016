"""`stepctl drive ...` (CiA 402 over SDO) against a running stepnode with `profiles =
["cia402"]` on vcan: status in the standard's words, enable/disable/quick-stop/fault-reset
through the controlword steps, profile position, profile velocity and homing, exit
statuses and one-line errors.

Every state and value stepctl reports is checked against the node through the independent
python master (canopen_master.py): 6041h decoded with CiA 402-2's state coding masks."""

import subprocess
import time

import pytest

from conftest import CHANNEL

NODE = 42
STATUSWORD, CONTROLWORD, MODES_DISPLAY, ERROR_CODE = 0x6041, 0x6040, 0x6061, 0x603F
POSITION_ACTUAL, VELOCITY_ACTUAL, HOMING_METHOD, ESTOP = 0x6064, 0x606C, 0x6098, 0x5F00

# CiA 402-2 statusword state coding: (mask, value).
STATES = {
    "Not ready to switch on": (0x4F, 0x00), "Switch on disabled": (0x4F, 0x40),
    "Ready to switch on": (0x6F, 0x21), "Switched on": (0x6F, 0x23), "Operation enabled": (0x6F, 0x27),
    "Quick stop active": (0x6F, 0x07), "Fault reaction active": (0x4F, 0x0F), "Fault": (0x4F, 0x08),
}


def state_of(sw):
    return next((name for name, (mask, value) in STATES.items() if sw & mask == value), f"unknown 0x{sw:04X}")


@pytest.fixture
def stepctl(stepctl_bin, tmp_path):
    p = stepctl_bin

    def run(*args, timeout=60):
        return subprocess.run([str(p), "--iface", CHANNEL, *map(str, args)], capture_output=True, text=True,
                              timeout=timeout, cwd=str(tmp_path), stdin=subprocess.DEVNULL)
    return run


def one_error_line(r):
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("stepctl: "), f"stderr: {r.stderr!r}"
    return lines[0]


def boot(start_node, tmp_path, axes=1, profiles='["cia402"]'):
    path = tmp_path / "node.toml"
    path.write_text(f"axes = {axes}\nprofiles = {profiles}\n")
    return start_node(NODE, ["--config", path])


class Drive:
    """The python master's view of axis `axis` (SDO)."""

    def __init__(self, master, axis=1):
        self.master, self.offset = master, 0x800 * (axis - 1)

    def read_u16(self, index):
        self.master.flush()  # stepctl's SDO frames are in this master's socket too
        return self.master.read_u16(NODE, index + self.offset)

    def read_i32(self, index):
        self.master.flush()
        return self.master.read_i32(NODE, index + self.offset)

    def read_i8(self, index):
        self.master.flush()
        v = self.master.read_u8(NODE, index + self.offset)
        return v - 256 if v > 127 else v

    def write_u8(self, index, value):
        self.master.flush()
        self.master.write_u8(NODE, index, 0, value)

    def state(self):
        return state_of(self.read_u16(STATUSWORD))

    def wait_state(self, name, timeout=5.0):
        deadline = time.monotonic() + timeout
        while self.state() != name:
            assert time.monotonic() < deadline, f"still {self.state()}, expected {name}"
            time.sleep(0.05)


def drive(stepctl, *args, axis=1, timeout=60):
    return stepctl("drive", *args, "--node", NODE, "--axis", axis, timeout=timeout)


# ---------------------------------------------------------------- device control


def test_status_enable_disable(stepctl, master, start_node, tmp_path):
    boot(start_node, tmp_path)
    d = Drive(master)
    r = drive(stepctl, "status")
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(f"node {NODE} axis 1: Switch on disabled, mode no mode assigned (6061h = 0)\n"), r.stdout
    assert "statusword 6041h 0x0240: remote" in r.stdout
    assert "error code 603Fh 0x0000: no error" in r.stdout
    assert "position actual 6064h 0, velocity actual 606Ch 0" in r.stdout

    r = drive(stepctl, "enable")
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines() == [
        "  Switch on disabled: Shutdown (6040h = 0x0006) -> Ready to switch on",
        "  Ready to switch on: Switch on (6040h = 0x0007) -> Switched on",
        "  Switched on: Enable operation (6040h = 0x000F) -> Operation enabled",
        f"node {NODE} axis 1: Operation enabled",
    ], r.stdout
    assert d.state() == "Operation enabled"
    r = drive(stepctl, "enable", "--quiet")  # there already: nothing written
    assert r.returncode == 0 and r.stdout == f"node {NODE} axis 1: Operation enabled\n", r
    r = drive(stepctl, "status")
    assert r.returncode == 0 and "Operation enabled" in r.stdout.splitlines()[0], r.stdout
    assert "voltage enabled" in r.stdout

    r = drive(stepctl, "disable")
    assert r.returncode == 0, r.stderr
    assert "Operation enabled: Disable operation (6040h = 0x0007) -> Switched on" in r.stdout
    assert "Switched on: Shutdown (6040h = 0x0006) -> Ready to switch on" in r.stdout
    assert r.stdout.endswith(f"node {NODE} axis 1: Ready to switch on\n"), r.stdout
    assert d.state() == "Ready to switch on"


def test_fault_reset_and_enable_from_fault(stepctl, master, start_node, tmp_path):
    boot(start_node, tmp_path)
    d = Drive(master)

    def fault_while_moving():
        assert drive(stepctl, "pv", 1000, "--no-wait").returncode == 0
        d.write_u8(ESTOP, 1)  # the simulated machine's e-stop input stops the motion: a fault (9000h)
        d.wait_state("Fault")

    assert drive(stepctl, "enable").returncode == 0
    fault_while_moving()
    r = drive(stepctl, "status")
    assert r.returncode == 1, r  # a fault, as `stepctl status` with an error bit
    assert r.stdout.startswith(f"node {NODE} axis 1: Fault,"), r.stdout
    assert "error code 603Fh 0x9000: external error" in r.stdout
    # The cause persists: the reset is refused (transition 15 needs the fault gone).
    r = drive(stepctl, "fault-reset")
    assert r.returncode == 1
    line = one_error_line(r)
    assert "stuck in Fault, 603Fh 0x9000" in line and "Fault reset" in line, line
    # 6040h bit 7 is still 1 from that reset: enable takes it to 0 first, for the edge.
    assert d.read_u16(CONTROLWORD) & 0x80
    d.write_u8(ESTOP, 0)
    r = drive(stepctl, "enable")
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[0] == "  Fault: Fault reset (6040h = 0x0000, 0x0080) -> Switch on disabled", r.stdout
    assert d.state() == "Operation enabled"

    fault_while_moving()
    d.write_u8(ESTOP, 0)
    r = drive(stepctl, "fault-reset")
    assert r.returncode == 0, r.stderr
    assert r.stdout == ("  Fault: Fault reset (6040h = 0x0080) -> Switch on disabled\n"
                        f"node {NODE} axis 1: Switch on disabled\n"), r.stdout
    assert d.state() == "Switch on disabled"
    assert d.read_u16(ERROR_CODE) == 0
    r = drive(stepctl, "fault-reset")
    assert r.returncode == 0 and r.stdout == f"node {NODE} axis 1: Switch on disabled (no fault to reset)\n", r


def test_quick_stop_of_a_velocity(stepctl, master, start_node, tmp_path):
    boot(start_node, tmp_path)
    d = Drive(master)
    r = drive(stepctl, "quick-stop")
    assert r.returncode == 0 and "nothing to stop" in r.stdout, r
    assert drive(stepctl, "enable", "--quiet").returncode == 0
    assert drive(stepctl, "pv", 1000, "--acceleration", 10000, "--quiet").returncode == 0
    r = drive(stepctl, "quick-stop")
    assert r.returncode == 0, r.stderr
    assert "Operation enabled: Quick stop (6040h = 0x000B) -> Quick stop active or Switch on disabled" in r.stdout
    assert r.stdout.splitlines()[-1] in (f"node {NODE} axis 1: Quick stop active",
                                         f"node {NODE} axis 1: Switch on disabled"), r.stdout
    # 605Ah = 2 (default): the quick stop ramp, then transition 12.
    d.wait_state("Switch on disabled")
    assert d.read_i32(VELOCITY_ACTUAL) == 0
    r = drive(stepctl, "pp", 100)
    assert r.returncode == 1
    line = one_error_line(r)
    assert "Switch on disabled, not Operation enabled" in line and "stepctl drive enable" in line, line


# ---------------------------------------------------------------- the modes


def test_profile_position(stepctl, master, start_node, tmp_path):
    boot(start_node, tmp_path)
    d = Drive(master)
    assert drive(stepctl, "enable", "--quiet").returncode == 0
    r = drive(stepctl, "pp", 2000, "--velocity", 4000, "--acceleration", 20000, "--deceleration", 20000)
    assert r.returncode == 0, r.stderr
    assert r.stdout.endswith(f"node {NODE} axis 1: target reached, position 2000\n"), r.stdout
    assert d.read_i32(POSITION_ACTUAL) == 2000
    assert d.read_i8(MODES_DISPLAY) == 1
    sw = d.read_u16(STATUSWORD)
    assert sw & (1 << 10) and not sw & (1 << 12), hex(sw)  # target reached, handshake done
    # Relative to the preceding target (bit 6), and backwards.
    r = drive(stepctl, "pp", -500, "--relative", "--quiet")
    assert r.returncode == 0 and r.stdout == f"node {NODE} axis 1: target reached, position 1500\n", r
    assert d.read_i32(POSITION_ACTUAL) == 1500
    # --no-wait: back once acknowledged, the move goes on.
    r = drive(stepctl, "pp", 0, "--no-wait")
    assert r.returncode == 0 and "set-point 0 acknowledged" in r.stdout, r
    deadline = time.monotonic() + 5
    while d.read_i32(POSITION_ACTUAL) != 0:
        assert time.monotonic() < deadline
        time.sleep(0.05)


def test_profile_velocity(stepctl, master, start_node, tmp_path):
    boot(start_node, tmp_path)
    d = Drive(master)
    assert drive(stepctl, "enable", "--quiet").returncode == 0
    r = drive(stepctl, "pv", 800, "--acceleration", 8000, "--deceleration", 8000)
    assert r.returncode == 0, r.stderr
    assert r.stdout.endswith(f"node {NODE} axis 1: velocity reached, velocity 800\n"), r.stdout
    assert d.read_i32(VELOCITY_ACTUAL) == 800
    assert d.read_i8(MODES_DISPLAY) == 3
    # A mode change while the drive moves ramps the motion down (6084h), then 6061h shows
    # the new mode: pp 0 from a running pv goes back to 0.
    r = drive(stepctl, "pp", 0)
    assert r.returncode == 0 and r.stdout.endswith(f"node {NODE} axis 1: target reached, position 0\n"), r
    assert d.read_i8(MODES_DISPLAY) == 1
    r = drive(stepctl, "pv", -400, "--quiet")
    assert r.returncode == 0 and r.stdout == f"node {NODE} axis 1: velocity reached, velocity -400\n", r
    r = drive(stepctl, "pv", 0, "--quiet")
    assert r.returncode == 0 and r.stdout == f"node {NODE} axis 1: speed zero, velocity 0\n", r
    assert d.read_i32(VELOCITY_ACTUAL) == 0
    # Beyond 607Fh (10 000 by default): bad input, nothing written.
    r = drive(stepctl, "pv", 20000)
    assert r.returncode == 2 and "607Fh" in one_error_line(r), r


def test_homing(stepctl, master, start_node, tmp_path):
    boot(start_node, tmp_path)
    d = Drive(master)
    assert drive(stepctl, "enable", "--quiet").returncode == 0
    # 6098h = 0 (no method assigned): bad input.
    r = drive(stepctl, "home")
    assert r.returncode == 2 and "--method" in one_error_line(r), r
    # 37: the current position is the home position, 607Ch its position.
    r = drive(stepctl, "home", "--method", 37, "--offset", 250)
    assert r.returncode == 0, r.stderr
    assert r.stdout.endswith(f"node {NODE} axis 1: homing procedure is completed successfully, position 250\n"), r.stdout
    assert d.read_i32(POSITION_ACTUAL) == 250
    assert d.read_i8(MODES_DISPLAY) == 6
    r = drive(stepctl, "status")
    assert "homing: homing procedure is completed successfully" in r.stdout, r.stdout
    # 19: the home switch (the simulated machine's at 1000), searched at the switch speed.
    r = drive(stepctl, "home", "--method", 19, "--offset", 0, "--switch-speed", 4000, "--zero-speed", 400,
              "--acceleration", 20000)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "homing procedure is completed successfully, position 0" in r.stdout, r.stdout
    assert d.read_i8(HOMING_METHOD) == 19


def test_homing_on_a_node_without_it(stepctl, master, start_node, tmp_path):
    # No CiA 402 objects at all: the node says so, stepctl names the likely cause.
    boot(start_node, tmp_path, profiles='["horner"]')
    r = drive(stepctl, "status")
    assert r.returncode == 1
    line = one_error_line(r)
    assert "0x06020000" in line and 'profiles = ["cia402"]' in line, line


def test_second_axis_uses_its_own_objects(stepctl, master, start_node, tmp_path):
    boot(start_node, tmp_path, axes=2)
    r = drive(stepctl, "enable", "--quiet", axis=2)
    assert r.returncode == 0 and r.stdout == f"node {NODE} axis 2: Operation enabled\n", r
    assert Drive(master, 2).state() == "Operation enabled"
    assert Drive(master, 1).state() == "Switch on disabled"
    r = drive(stepctl, "pp", 300, "--quiet", axis=2)
    assert r.returncode == 0 and r.stdout == f"node {NODE} axis 2: target reached, position 300\n", r
    assert Drive(master, 1).read_i32(POSITION_ACTUAL) == 0


def test_profile_position_waits_for_room_in_the_set_point_buffer(stepctl, master, start_node, tmp_path):
    """CiA 402-2 PP: the drive takes a new set-point (bit 4's edge) only while 6041h bit 12 is
    0; it stays 1 while the buffer holds a set-point behind the move. stepctl raised bit 4
    then and took the old 1 for an acknowledgement (found in review)."""
    boot(start_node, tmp_path)
    d = Drive(master)
    assert drive(stepctl, "enable", "--quiet").returncode == 0
    r = drive(stepctl, "pp", 20000, "--velocity", 2000, "--no-wait", "--quiet")  # 10 s
    assert r.returncode == 0, r
    r = drive(stepctl, "pp", 0, "--no-wait")  # buffered behind it: bit 12 stays 1
    assert r.returncode == 0 and "buffered" in r.stdout, r
    assert d.read_u16(STATUSWORD) & (1 << 12)
    r = drive(stepctl, "pp", 100, "--no-wait", "--wait", 1)
    assert r.returncode == 1, r
    line = one_error_line(r)
    assert "takes no new set-point" in line and "bit 12" in line, line
    assert "acknowledged" not in r.stdout, r.stdout


def test_bad_input_exits_2_before_the_bus(stepctl):
    for args in (("pp",), ("pp", "ten"), ("pp", 1, "--velocity", -1), ("pv", 1, "--axis", 9), ("frobnicate",)):
        r = stepctl("drive", *args, "--node", NODE)
        assert r.returncode == 2, (args, r)
        one_error_line(r)
