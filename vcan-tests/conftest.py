"""pytest infrastructure for the vcan integration tests (run them with vcan-tests/run).

Fixtures
  bus           python-can Bus on $VCAN_CHANNEL (default vcan0), no filters, fresh per test
  master        canopen_master.CanopenMaster on that bus
  start_node    factory: start_node(node_id, extra_args=(), state_dir=None, ...) -> NodeProcess
  stepnode_bin  pathlib.Path of the node binary ($STEPNODE_BIN, default build/node/stepnode)

Helpers (import from conftest)
  wait_for_frame(source, predicate, timeout=2.0) -> can.Message | None
  collect_frames(source, duration, predicate=None) -> list[can.Message]
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Callable, List, Optional, Sequence

import can
import pytest

from canopen_master import CanopenMaster, fmt_frame, is_bootup

REPO_ROOT = Path(__file__).resolve().parent.parent
CHANNEL = os.environ.get("VCAN_CHANNEL", "vcan0")
BOOT_TIMEOUT = float(os.environ.get("STEPNODE_BOOT_TIMEOUT", "15"))


def stepnode_path() -> Path:
    p = Path(os.environ.get("STEPNODE_BIN", "build/node/stepnode"))
    return p if p.is_absolute() else REPO_ROOT / p


def open_bus(channel: str = CHANNEL) -> can.BusABC:
    """A SocketCAN socket on channel that receives every frame (own frames excluded)."""
    return can.interface.Bus(channel=channel, interface="socketcan", receive_own_messages=False)


# ---------------------------------------------------------------- frame helpers


def wait_for_frame(source, predicate: Callable[[can.Message], bool], timeout: float = 2.0) -> Optional[can.Message]:
    """First frame matching predicate within timeout, else None.

    source: a CanopenMaster (uses and keeps its backlog) or a python-can bus (frames that
    do not match are dropped)."""
    if isinstance(source, CanopenMaster):
        return source.wait_for(predicate, timeout)
    deadline = time.monotonic() + timeout
    while True:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            return None
        msg = source.recv(timeout=remaining)
        if msg is None:
            return None
        if predicate(msg):
            return msg


def collect_frames(source, duration: float, predicate: Optional[Callable[[can.Message], bool]] = None) -> List[can.Message]:
    """Every frame (matching predicate, if given) seen during duration seconds."""
    if isinstance(source, CanopenMaster):
        return source.collect(duration, predicate)
    out = []
    deadline = time.monotonic() + duration
    while True:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            return out
        msg = source.recv(timeout=remaining)
        if msg is not None and (predicate is None or predicate(msg)):
            out.append(msg)


# ---------------------------------------------------------------- fixtures


def pytest_report_header(config):
    return [
        f"vcan: mode={os.environ.get('VCAN_MODE', 'unknown (not started via tools/vcan)')} channel={CHANNEL}",
        f"stepnode: {stepnode_path()}" + ("" if stepnode_path().exists() else " (missing: node tests skip)"),
    ]


@pytest.fixture
def bus():
    try:
        b = open_bus()
    except (OSError, can.CanError) as e:
        pytest.fail(f"cannot open SocketCAN {CHANNEL}: {e} (run the tests through vcan-tests/run or tools/vcan)")
    yield b
    b.shutdown()


@pytest.fixture
def master(bus):
    return CanopenMaster(bus, timeout=float(os.environ.get("VCAN_SDO_TIMEOUT", "2.0")))


@pytest.fixture
def stepctl_bin() -> Path:
    p = Path(os.environ.get("STEPCTL_BIN", "build/tools/stepctl"))
    p = p if p.is_absolute() else REPO_ROOT / p
    if not (p.is_file() and os.access(p, os.X_OK)):
        pytest.skip(f"stepctl not found at {p}: build with -DSTEPNODE_BUILD_TOOLS=ON or set STEPCTL_BIN")
    return p


@pytest.fixture
def stepnode_bin() -> Path:
    p = stepnode_path()
    if not (p.is_file() and os.access(p, os.X_OK)):
        pytest.skip(f"stepnode binary not found at {p}: build it (build/node/stepnode) or set STEPNODE_BIN")
    return p


class NodeProcess:
    """A running stepnode. Its stdout+stderr go to log_path."""

    def __init__(self, proc: subprocess.Popen, node_id: int, state_dir: Path, log_path: Path, argv: List[str]):
        self.proc = proc
        self.node_id = node_id
        self.state_dir = state_dir
        self.log_path = log_path
        self.argv = argv
        self.bootup: Optional[can.Message] = None  # the boot-up frame seen at start

    @property
    def pid(self) -> int:
        return self.proc.pid

    @property
    def alive(self) -> bool:
        return self.proc.poll() is None

    @property
    def returncode(self) -> Optional[int]:
        return self.proc.poll()

    def log(self) -> str:
        try:
            return self.log_path.read_text(errors="replace")
        except OSError:
            return ""

    def send_signal(self, sig: int) -> None:
        if self.alive:
            self.proc.send_signal(sig)

    def kill(self) -> Optional[int]:
        """SIGKILL (a crash/power loss) and reap; returns the exit status."""
        if self.alive:
            self.proc.kill()
        return self.proc.wait()

    def terminate(self, timeout: float = 10.0) -> Optional[int]:
        """SIGTERM and wait up to timeout, then SIGKILL; returns the exit status
        (negative = killed by that signal, as subprocess reports it)."""
        if self.alive:
            self.proc.terminate()
            try:
                return self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
        return self.proc.wait()

    def wait(self, timeout: Optional[float] = None) -> int:
        return self.proc.wait(timeout)

    def __repr__(self):
        return f"<stepnode id={self.node_id} pid={self.proc.pid} rc={self.proc.poll()} state_dir={self.state_dir}>"


@pytest.fixture
def start_node(bus, stepnode_bin, tmp_path, request):
    """Factory fixture: start_node(node_id, extra_args=(), state_dir=None,
    wait_bootup=True, timeout=BOOT_TIMEOUT, env=None) -> NodeProcess.

    Runs `stepnode --iface vcan0 --node-id N --state-dir DIR [extra_args]` and waits for
    its boot-up frame (0x700+N, one byte 0x00) on a private socket. The test's own `bus`
    is opened before the node starts, so it sees the boot-up frame too. state_dir
    defaults to a fresh dir under tmp_path; pass the same dir again to restart a node
    on its persisted state. Every node still running at test end is killed; its log
    is printed (shown by pytest for failed tests)."""
    nodes: List[NodeProcess] = []
    counter = [0]

    def _start(node_id: int, extra_args: Sequence[str] = (), state_dir=None, wait_bootup: bool = True,
               timeout: float = BOOT_TIMEOUT, env: Optional[dict] = None) -> NodeProcess:
        counter[0] += 1
        if state_dir is None:
            state_dir = tmp_path / f"node{node_id}-state-{counter[0]}"
        state_dir = Path(state_dir)
        state_dir.mkdir(parents=True, exist_ok=True)
        log_path = tmp_path / f"node{node_id}-run{counter[0]}.log"
        argv = [str(stepnode_bin), "--iface", CHANNEL, "--node-id", str(node_id), "--state-dir", str(state_dir),
                *map(str, extra_args)]
        watch = open_bus() if wait_bootup else None
        try:
            with open(log_path, "wb") as log:
                proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                        cwd=str(tmp_path), env=None if env is None else {**os.environ, **env},
                                        start_new_session=True)
            node = NodeProcess(proc, node_id, state_dir, log_path, argv)
            nodes.append(node)
            if wait_bootup:
                deadline = time.monotonic() + timeout
                while node.bootup is None:
                    remaining = deadline - time.monotonic()
                    if remaining <= 0 or not node.alive:
                        break
                    msg = watch.recv(timeout=min(remaining, 0.2))
                    if msg is not None and is_bootup(msg, node_id):
                        node.bootup = msg
                if node.bootup is None:
                    why = (f"exited with status {node.returncode}" if not node.alive
                           else f"sent no boot-up frame 0x{0x700 + node_id:03X}#00 within {timeout} s")
                    node.kill()
                    pytest.fail(f"stepnode {why}\n  argv: {' '.join(argv)}\n  log ({log_path}):\n{node.log()[-4000:]}",
                                pytrace=False)
            return node
        finally:
            if watch is not None:
                watch.shutdown()

    yield _start

    for node in nodes:
        if node.alive:
            node.kill()
        text = node.log()
        if text:
            print(f"--- {node!r} log ---\n{text[-4000:]}")


__all__ = [
    "CHANNEL", "REPO_ROOT", "NodeProcess", "collect_frames", "fmt_frame", "open_bus", "stepnode_path",
    "wait_for_frame",
]
