"""stepnode and stepbridge under a service manager (README "Running as a service"): a
listener socket plays systemd's $NOTIFY_SOCKET. READY=1 comes once the process serves
(the node: after its boot-up frame is on the bus), WATCHDOG=1 every WATCHDOG_USEC/2 while
the event loop runs and only for the process WATCHDOG_PID names, STOPPING=1 on SIGTERM."""

from __future__ import annotations

import os
import signal

import pytest

from bridge_helpers import DDS_TIMEOUT, Process, fresh_domain, stepbridge_bin
from conftest import CHANNEL
from notify_listener import NotifyListener

_ = stepbridge_bin  # fixture

NODE = 41
WATCHDOG_USEC = 400_000  # the pet is due every 0.2 s


@pytest.fixture
def listener(tmp_path):
    lst = NotifyListener(tmp_path / "notify")
    yield lst
    lst.close()


def watchdog_gaps(notes):
    times = [n.timestamp for n in notes if n.text == "WATCHDOG=1"]
    return [b - a for a, b in zip(times, times[1:])]


def test_node_is_ready_after_its_bootup_pets_the_watchdog_and_says_stopping(listener, start_node):
    node = start_node(NODE, env=listener.env(WATCHDOG_USEC=str(WATCHDOG_USEC)))
    ready = listener.wait_for("READY=1", 5.0)
    assert ready is not None, f"no READY=1\n{node.log()}"
    # Both stamps are the kernel's receive times on CLOCK_REALTIME.
    assert node.bootup.timestamp <= ready.timestamp, \
        f"READY=1 {ready.timestamp - node.bootup.timestamp:+.6f} s before the boot-up frame"

    notes = listener.collect(2.0)
    assert all(n.text == "WATCHDOG=1" for n in notes), [n.text for n in notes]
    gaps = watchdog_gaps(notes)
    assert len(gaps) >= 7, f"{len(notes)} WATCHDOG=1 in 2 s"
    mean = sum(gaps) / len(gaps)
    assert 0.15 <= mean <= 0.27, f"mean period {mean:.3f} s, expected 0.2 s: {gaps}"
    # Never as late as the manager's timeout: that would be a restart.
    assert max(gaps) < WATCHDOG_USEC / 1e6, gaps

    # A process that cannot run does not pet: the pet is not sent on anyone else's behalf.
    os.kill(node.pid, signal.SIGSTOP)
    try:
        listener.collect(0.1)  # one may have been on its way
        assert listener.collect(1.0) == []
    finally:
        os.kill(node.pid, signal.SIGCONT)
    assert listener.wait_for("WATCHDOG=1", 1.0) is not None, "no WATCHDOG=1 after SIGCONT"

    node.send_signal(signal.SIGTERM)
    assert listener.wait_for("STOPPING=1", 5.0) is not None, f"no STOPPING=1\n{node.log()}"
    assert node.wait(10) == 0


def test_node_does_not_pet_for_another_process_named_by_watchdog_pid(listener, start_node):
    other = os.getpid()  # not the node
    node = start_node(NODE, env=listener.env(WATCHDOG_USEC=str(WATCHDOG_USEC), WATCHDOG_PID=str(other)))
    assert listener.wait_for("READY=1", 5.0) is not None
    texts = [n.text for n in listener.collect(1.0)]
    assert "WATCHDOG=1" not in texts, texts
    node.send_signal(signal.SIGTERM)
    assert listener.wait_for("STOPPING=1", 5.0) is not None
    assert node.wait(10) == 0


def test_node_without_watchdog_usec_says_ready_and_stopping_only(listener, start_node):
    node = start_node(NODE, env=listener.env())
    assert listener.wait_for("READY=1", 5.0) is not None
    assert [n.text for n in listener.collect(0.8)] == []
    node.send_signal(signal.SIGTERM)
    assert listener.wait_for("STOPPING=1", 5.0) is not None


def test_bridge_is_ready_pets_the_watchdog_and_says_stopping(listener, stepbridge_bin, tmp_path):
    argv = [str(stepbridge_bin), "--iface", CHANNEL, "--domain", str(fresh_domain())]
    bridge = Process(argv, tmp_path / "stepbridge.log", env=listener.env(WATCHDOG_USEC=str(WATCHDOG_USEC)))
    try:
        assert listener.wait_for("READY=1", DDS_TIMEOUT) is not None, f"no READY=1\n{bridge.log()}"
        gaps = watchdog_gaps(listener.collect(2.0))
        assert len(gaps) >= 7 and max(gaps) < WATCHDOG_USEC / 1e6, gaps
        bridge.proc.send_signal(signal.SIGTERM)
        assert listener.wait_for("STOPPING=1", 10.0) is not None, f"no STOPPING=1\n{bridge.log()}"
        assert bridge.proc.wait(15) == 0
    finally:
        bridge.kill()
        print(f"--- stepbridge ---\n{bridge.log()[-3000:]}")
