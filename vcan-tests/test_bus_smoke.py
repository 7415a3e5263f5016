"""Smoke test of the harness itself: vcan0/vcan1 are real SocketCAN interfaces."""

import subprocess

import can

from conftest import CHANNEL, open_bus, wait_for_frame


def test_two_sockets_exchange_frames():
    tx = open_bus(CHANNEL)
    rx = open_bus(CHANNEL)
    try:
        sent = [
            can.Message(arbitration_id=0x123, data=bytes([0x11, 0x22, 0x33]), is_extended_id=False),
            can.Message(arbitration_id=0x1ABCDE0F, data=bytes(range(8)), is_extended_id=True),
            can.Message(arbitration_id=0x7FF, data=b"", is_extended_id=False),
        ]
        for msg in sent:
            tx.send(msg, timeout=1.0)
        for msg in sent:
            got = rx.recv(timeout=2.0)
            assert got is not None, f"frame {msg} not received on {CHANNEL}"
            assert got.arbitration_id == msg.arbitration_id
            assert got.is_extended_id == msg.is_extended_id
            assert bytes(got.data) == bytes(msg.data)
            assert got.channel == CHANNEL
        # the sender does not get its own frames back (receive_own_messages=False)
        assert tx.recv(timeout=0.2) is None
    finally:
        tx.shutdown()
        rx.shutdown()


def test_vcan1_is_a_separate_bus():
    a0, a1, b1 = open_bus("vcan0"), open_bus("vcan1"), open_bus("vcan1")
    try:
        a0.send(can.Message(arbitration_id=0x100, data=b"\x00", is_extended_id=False))
        assert a1.recv(timeout=0.3) is None, "a vcan0 frame showed up on vcan1"
        b1.send(can.Message(arbitration_id=0x101, data=b"\x01", is_extended_id=False))
        got = a1.recv(timeout=2.0)
        assert got is not None and got.arbitration_id == 0x101
    finally:
        for b in (a0, a1, b1):
            b.shutdown()


def test_cansend_reaches_python_can(bus):
    """can-utils' cansend (the tool other scripts use) and python-can see one bus."""
    subprocess.run(["cansend", CHANNEL, "123#11"], check=True, timeout=10)
    got = wait_for_frame(bus, lambda m: m.arbitration_id == 0x123, timeout=2.0)
    assert got is not None and bytes(got.data) == b"\x11"
