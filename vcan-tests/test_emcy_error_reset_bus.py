"""The EMCY error reset (CiA 301 7.2.7.3.1) on vcan for the conditions that need an axis, a
guarding master or the controller's bus state: the node sends EMCY 0x0000 with the error
register as it then is (0) once the last active error has ended, never while another one is
still active, and 0x1003 keeps the errors, not the resets.

The bus states come from error frames (CAN_ERR_FLAG) as a SocketCAN controller driver sends
them (linux/can/error.h): vcan delivers an error frame a process sends to every socket whose
error mask asks for that class, which is how the node's socket receives a real controller's.
The node is told "no change of NMT state" for communication errors (0x1029:1 = 1) so that it
stays operational and its axis reports over the PDOs; the lost-master policy still latches
%I8 on the axis (EMCY 0xFF01), which the master clears with Clear Errors (%Q14)."""

import time

import can

from axis_helpers import EMCY_AXIS1, EMCY_HEARTBEAT, ERRORS, NODE, boot, clear_and_profile
from canopen_master import STATE_OPERATIONAL

# linux/can/error.h
CAN_ERR_CRTL, CAN_ERR_BUSOFF, CAN_ERR_RESTARTED = 0x004, 0x040, 0x100
CAN_ERR_CRTL_RX_PASSIVE, CAN_ERR_CRTL_ACTIVE = 0x10, 0x40

EMCY_ERROR_PASSIVE, EMCY_RECOVERED_FROM_BUS_OFF = 0x8120, 0x8140
# Error register 0x1001 bits (CiA 301 7.5.2.2).
GENERIC, COMMUNICATION, MANUFACTURER = 0x01, 0x10, 0x80


def error_frame(master, error_class: int, controller: int = 0) -> None:
    """An error frame as a controller driver sends it: the class in the id, data[1] the
    controller's state."""
    data = bytes([0, controller, 0, 0, 0, 0, 0, 0])
    master.bus.send(can.Message(arbitration_id=error_class, data=data, is_error_frame=True, is_extended_id=False))


def started(master, start_node, tmp_path):
    """Node 7 with one axis (a lost master latches %I8 on every axis), operational, the
    axis cleared; returns the link and the axes."""
    config = tmp_path / "one-axis.toml"
    config.write_text("axes = 1\n")
    link = boot(master, start_node, extra_args=["--config", str(config)])
    for ax in link.axes.values():
        clear_and_profile(ax)
    master.write_u8(NODE, 0x1029, 1, 1)  # a communication error changes no NMT state
    master.write_u8(NODE, 0x1003, 0, 0)  # an empty history: the test's errors only
    return link, list(link.axes.values())


def clear_errors(axes):
    """Clear Errors on every axis."""
    for ax in axes:
        mark = ax.mark()
        ax.command("clear")
        ax.wait_status(lambda s: not s & ERRORS, 3.0, mark, "after Clear Errors")


def assert_no_reset(link, mark, duration=0.4):
    link.pump(duration)
    assert 0x0000 not in link.emcy_codes(mark), [hex(c) for c in link.emcy_codes(mark)]


def history(master):
    return [master.read_u32(NODE, 0x1003, i) & 0xFFFF for i in range(1, master.read_u8(NODE, 0x1003, 0) + 1)]


def test_life_guarding_loss_then_requests_back_then_clear_errors(master, start_node, tmp_path):
    link, axes = started(master, start_node, tmp_path)
    master.write_u16(NODE, 0x1017, 0, 0)    # guarding instead of the heartbeat
    master.write_u16(NODE, 0x100C, 0, 200)  # guard time 200 ms
    master.write_u8(NODE, 0x100D, 0, 3)     # node life time 600 ms
    for _ in range(4):
        master.send(0x700 + NODE, remote=True)
        time.sleep(0.2)
    mark = link.emcy_mark()
    # The guarding master stops: 0x8130 (register: generic + communication), and the axis
    # latches %I8 (0xFF01, register now with the manufacturer bit).
    lost = link.wait_emcy(EMCY_HEARTBEAT, mark, timeout=3.0)
    assert lost.error_register & (GENERIC | COMMUNICATION) == GENERIC | COMMUNICATION
    axis = link.wait_emcy(EMCY_AXIS1, mark, timeout=3.0)
    assert axis.error_register & (GENERIC | MANUFACTURER) == GENERIC | MANUFACTURER
    # Its requests come back: the guarding error ends, the axis error is still active. (Read
    # within the node life time, then guarding is switched off: no new loss after it.)
    mark = link.emcy_mark()
    master.send(0x700 + NODE, remote=True)
    assert master.read_u8(NODE, 0x1001, 0) == GENERIC | MANUFACTURER
    master.write_u16(NODE, 0x100C, 0, 0)
    assert_no_reset(link, mark)
    assert master.read_u8(NODE, 0x1001, 0) == GENERIC | MANUFACTURER
    # Clear Errors ends the last one: EMCY 0x0000, register 0.
    clear_errors(axes)
    reset = link.wait_emcy(0x0000, mark, timeout=3.0)
    assert reset.error_register == 0 and bytes(reset.manufacturer) == bytes(5)
    assert master.read_u8(NODE, 0x1001, 0) == 0
    assert history(master) == [EMCY_AXIS1, EMCY_HEARTBEAT]  # newest first, no reset in it


def test_error_passive_until_error_active(master, start_node, tmp_path):
    link, axes = started(master, start_node, tmp_path)
    mark = link.emcy_mark()
    error_frame(master, CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE)
    passive = link.wait_emcy(EMCY_ERROR_PASSIVE, mark, timeout=2.0)
    assert passive.error_register == GENERIC | COMMUNICATION and bytes(passive.manufacturer) == bytes(5)
    assert master.read_u8(NODE, 0x1001, 0) == GENERIC | COMMUNICATION
    assert master.wait_heartbeat(NODE, timeout=2.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    error_frame(master, CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE)
    reset = link.wait_emcy(0x0000, mark, timeout=2.0)
    assert reset.error_register == 0
    assert master.read_u8(NODE, 0x1001, 0) == 0
    assert history(master) == [EMCY_ERROR_PASSIVE]


def test_bus_off_restarted_then_clear_errors(master, start_node, tmp_path):
    link, axes = started(master, start_node, tmp_path)
    mark = link.emcy_mark()
    error_frame(master, CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE)
    link.wait_emcy(EMCY_ERROR_PASSIVE, mark, timeout=2.0)
    # Bus-off is a lost master for the axes: %I8 latches (0xFF01). The controller restarts:
    # EMCY 0x8140 "recovered from bus-off"; the bus errors end, the axis error stays.
    error_frame(master, CAN_ERR_BUSOFF)
    link.wait_emcy(EMCY_AXIS1, mark, timeout=2.0)
    error_frame(master, CAN_ERR_RESTARTED)
    recovered = link.wait_emcy(EMCY_RECOVERED_FROM_BUS_OFF, mark, timeout=2.0)
    assert recovered.error_register & MANUFACTURER
    assert_no_reset(link, mark)
    assert master.read_u8(NODE, 0x1001, 0) == GENERIC | MANUFACTURER
    clear_errors(axes)
    reset = link.wait_emcy(0x0000, mark, timeout=3.0)
    assert reset.error_register == 0
    assert master.read_u8(NODE, 0x1001, 0) == 0
    assert history(master) == [EMCY_RECOVERED_FROM_BUS_OFF, EMCY_AXIS1, EMCY_ERROR_PASSIVE]
