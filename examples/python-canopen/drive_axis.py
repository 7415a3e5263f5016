#!/usr/bin/env python3
"""Drive one stepnode CiA 402 axis with python-canopen's BaseNode402.

Written against python-canopen's documented API (canopen.Network, canopen.BaseNode402:
setup_402_state_machine, nmt.state, op_mode, state, controlword, statusword,
check_statusword, homing, sdo[...].raw). python-canopen is not installed on the machine
this repository is built on, so this script has not been run as it stands; the vcan test
vcan-tests/test_python_canopen_example.py plays the same frames it makes (NMT, SDO reads of
the PDO configuration, the RPDO with controlword and mode, the SDO writes) against a real
node and checks what the node answers.

  pip install canopen            # python-canopen (it brings python-can)
  build/node/stepnode --config examples/python-canopen/stepnode.toml --iface vcan0 &
  examples/python-canopen/drive_axis.py --channel vcan0 --node 5

What it does, in CiA 402's words: the node to pre-operational, the PDO mapping read (the
default RPDO1 {6040h controlword, 6060h modes of operation}, TPDO1 {6041h statusword,
6061h modes of operation display}), operational; homing mode with method 37 (the current
position is the home position, 607Ch home offset 0); profile position mode: a move to
--target with the set-point handshake (bit 4 new set-point, bit 12 set-point acknowledge,
bit 10 target reached), then two set-points where the second is given with bit 9 "change on
set-point", so the axis runs through the first target without stopping; then Switch on
disabled and pre-operational again.
"""

import argparse
import pathlib
import sys
import time

import canopen

CW_ENABLE_OPERATION = 0x000F
CW_NEW_SET_POINT = 0x0010  # bit 4
CW_CHANGE_ON_SET_POINT = 0x0200  # bit 9, with bit 5 "change set immediately" = 0
SW_TARGET_REACHED = 1 << 10
SW_SET_POINT_ACKNOWLEDGE = 1 << 12  # profile position mode


def wait_statusword(node: canopen.BaseNode402, mask: int, value: int, timeout: float, what: str) -> int:
    # check_statusword reads 6041h (over SDO when its TPDO is event-driven, as stepnode's is).
    end = time.monotonic() + timeout
    while True:
        sw = node.check_statusword()
        if sw & mask == value:
            return sw
        if time.monotonic() > end:
            raise RuntimeError(f"node {node.id}: no {what} within {timeout} s (statusword 0x{sw:04X})")
        time.sleep(0.01)


def set_point(node: canopen.BaseNode402, target: int, extra_bits: int = 0, wait_reached: bool = True) -> None:
    """The set-point handshake: 607Ah, then bit 4 up until bit 12 answers, bit 4 down."""
    node.sdo[0x607A].raw = target
    node.controlword = CW_ENABLE_OPERATION | CW_NEW_SET_POINT | extra_bits
    wait_statusword(node, SW_SET_POINT_ACKNOWLEDGE, SW_SET_POINT_ACKNOWLEDGE, 1.0, "set-point acknowledge")
    node.controlword = CW_ENABLE_OPERATION | extra_bits
    if wait_reached:
        wait_statusword(node, SW_TARGET_REACHED | SW_SET_POINT_ACKNOWLEDGE, SW_TARGET_REACHED, 30.0,
                        "target reached")


def run(node: canopen.BaseNode402, args: argparse.Namespace) -> None:
    node.nmt.state = "PRE-OPERATIONAL"
    node.setup_402_state_machine()  # reads every PDO's configuration over SDO
    node.nmt.state = "OPERATIONAL"  # the node sends its TPDOs: statusword, mode, position
    time.sleep(0.2)

    # Homing on the current position (method 37): the position actual value reads 607Ch.
    node.sdo[0x6098].raw = 37
    node.sdo[0x607C].raw = 0
    if not node.homing(timeout=10):
        raise RuntimeError(f"node {node.id}: homing failed")
    node.controlword = CW_ENABLE_OPERATION  # bit 4 down before the mode changes

    node.op_mode = "PROFILED POSITION"
    node.sdo[0x6081].raw = args.velocity  # profile velocity
    node.sdo[0x6083].raw = args.acceleration  # profile acceleration
    node.sdo[0x6084].raw = args.acceleration  # profile deceleration
    set_point(node, args.target)
    print(f"at {node.sdo[0x6064].raw} (target {args.target})")

    # Change on set-point: the second set-point goes into the buffer with bit 9; the axis
    # does not stop at the first target.
    first, second = args.target + args.step, args.target + 2 * args.step
    set_point(node, first, wait_reached=False)
    set_point(node, second, CW_CHANGE_ON_SET_POINT)
    print(f"at {node.sdo[0x6064].raw} (through {first} to {second})")

    node.state = "SWITCH ON DISABLED"
    node.nmt.state = "PRE-OPERATIONAL"


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--interface", default="socketcan", help="python-can interface (default socketcan)")
    p.add_argument("--channel", default="can0", help="CAN channel (default can0)")
    p.add_argument("--node", type=int, default=5, help="node-ID (default 5, as stepnode.toml)")
    p.add_argument("--eds", default=None, help="the node's EDS (default: ../ros2_canopen/stepnode_cia402.eds)")
    p.add_argument("--target", type=int, default=2000, help="the first target, steps (default 2000)")
    p.add_argument("--step", type=int, default=1000, help="the run-through set-points' spacing (default 1000)")
    p.add_argument("--velocity", type=int, default=4000, help="6081h, steps/s (default 4000)")
    p.add_argument("--acceleration", type=int, default=40000, help="6083h/6084h, steps/s^2 (default 40000)")
    args = p.parse_args()
    eds = args.eds or str(pathlib.Path(__file__).resolve().parent.parent / "ros2_canopen" / "stepnode_cia402.eds")

    network = canopen.Network()
    network.connect(interface=args.interface, channel=args.channel)
    try:
        node = canopen.BaseNode402(args.node, eds)
        network.add_node(node)
        run(node, args)
    except (RuntimeError, canopen.SdoAbortedError, canopen.SdoCommunicationError) as e:
        print(f"drive_axis: {e}", file=sys.stderr)
        return 1
    finally:
        network.disconnect()
    return 0


if __name__ == "__main__":
    sys.exit(main())
