"""Helpers for the test_bridge_*.py vcan tests: the stepbridge process, and two DDS
subscriber processes that are not the bridge's code:

  cyclone_sub   Eclipse Cyclone DDS, built from bridge/idl/stepnode.idl alone: streams every
                AxisStatus / AxisPosition sample as a line of key=value pairs
  stepwatch     the supervisor tool (Fast DDS): `--once --json` prints what a late joiner
                gets at once (TRANSIENT_LOCAL) as one JSON object per line

Every test runs on its own DDS domain, so a process left over from another test can never
feed it samples.

Binaries: $STEPBRIDGE_BIN (build/bridge/stepbridge), $STEPWATCH_BIN (build/tools/stepwatch),
$CYCLONE_SUB_BIN (build/bridge/interop/cyclone_sub).
"""

from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List, Optional, Tuple

import pytest

from conftest import CHANNEL, REPO_ROOT

# DDS start-up inside User-Mode Linux is slow (every system call is); allow for it.
DDS_TIMEOUT = float(os.environ.get("BRIDGE_DDS_TIMEOUT", "20"))


def _binary(env: str, default: str) -> Path:
    p = Path(os.environ.get(env, default))
    p = p if p.is_absolute() else REPO_ROOT / p
    if not (p.is_file() and os.access(p, os.X_OK)):
        pytest.fail(f"{p} is missing: build it (cmake --build build) or set ${env}", pytrace=False)
    return p


def cyclone_sub_bin() -> Path:
    return _binary("CYCLONE_SUB_BIN", "build/bridge/interop/cyclone_sub")


@pytest.fixture
def stepbridge_bin() -> Path:
    return _binary("STEPBRIDGE_BIN", "build/bridge/stepbridge")


@pytest.fixture
def stepwatch_bin() -> Path:
    return _binary("STEPWATCH_BIN", "build/tools/stepwatch")


# Domains 1..200; a counter seeded by the process id keeps consecutive tests (and two test
# runs on one host) apart.
_domains = itertools.count(os.getpid() % 150 + 1)


def fresh_domain() -> int:
    return next(_domains) % 200 + 1


class Process:
    """A child process whose output goes to a log file (printed at teardown)."""

    def __init__(self, argv: List[str], log_path: Path, env: Optional[dict] = None):
        self.argv = argv
        self.log_path = log_path
        with open(log_path, "wb") as log:
            self.proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                         env=None if env is None else {**os.environ, **env}, start_new_session=True)

    @property
    def alive(self) -> bool:
        return self.proc.poll() is None

    def log(self) -> str:
        try:
            return self.log_path.read_text(errors="replace")
        except OSError:
            return ""

    def kill(self) -> int:
        if self.alive:
            self.proc.kill()
        return self.proc.wait()

    def terminate(self, timeout: float = 15.0) -> int:
        if self.alive:
            self.proc.terminate()
            try:
                return self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
        return self.proc.wait()


@dataclass
class Sample:
    t: float                     # time.monotonic() when the line was read
    topic: str                   # AxisStatus | AxisPosition
    fields: Dict[str, str] = field(default_factory=dict)
    disposed: bool = False

    def int(self, name: str) -> int:
        return int(self.fields[name], 0)

    @property
    def key(self) -> tuple:
        return (self.int("node"), self.int("axis"))


def parse_sample_line(line: str, t: float) -> Optional[Sample]:
    words = line.split()
    if not words or words[0] not in ("AxisStatus", "AxisPosition"):
        return None
    s = Sample(t, words[0])
    for w in words[1:]:
        if w in ("disposed", "unregistered"):
            s.disposed = True
        elif "=" in w:
            k, v = w.split("=", 1)
            s.fields[k] = v
    return s


class CycloneSubscriber:
    """cyclone_sub on a domain, its samples collected by a reader thread."""

    def __init__(self, domain: int, log_path: Path):
        self.argv = [str(cyclone_sub_bin()), "--domain", str(domain)]
        self.samples: List[Sample] = []
        self.log_path = log_path
        self._lines: List[str] = []
        self._lock = threading.Lock()
        self.proc = subprocess.Popen(self.argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, start_new_session=True)
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self):
        for raw in self.proc.stdout:
            line = raw.decode(errors="replace").rstrip("\n")
            s = parse_sample_line(line, time.monotonic())
            with self._lock:
                self._lines.append(line)
                if s is not None:
                    self.samples.append(s)

    def snapshot(self, topic: Optional[str] = None, node: Optional[int] = None, axis: Optional[int] = None) -> List[Sample]:
        with self._lock:
            out = list(self.samples)
        return [s for s in out if (topic is None or s.topic == topic) and (node is None or s.int("node") == node)
                and (axis is None or s.int("axis") == axis)]

    def mark(self) -> int:
        with self._lock:
            return len(self.samples)

    def since(self, mark: int, topic: Optional[str] = None, node: Optional[int] = None,
              axis: Optional[int] = None) -> List[Sample]:
        with self._lock:
            out = self.samples[mark:]
        return [s for s in out if (topic is None or s.topic == topic) and (node is None or s.int("node") == node)
                and (axis is None or s.int("axis") == axis)]

    def wait(self, pred: Callable[[], bool], timeout: float = DDS_TIMEOUT, what: str = "") -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if pred():
                return
            time.sleep(0.02)
        if pred():
            return
        pytest.fail(f"cyclone_sub: {what or 'condition'} not seen within {timeout} s; last lines:\n"
                    + "\n".join(self.tail(25)), pytrace=False)

    def tail(self, n: int) -> List[str]:
        with self._lock:
            return self._lines[-n:]

    def close(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._thread.join(2)
        with self._lock:
            self.log_path.write_text("\n".join(self._lines) + "\n")


def watch_once(stepwatch_bin: Path, domain: int, *extra: str, wait_ms: int = 8000) -> Tuple[int, List[dict], str]:
    """stepwatch --once --json: (exit status, one dict per line, stderr). Exit 1 = nothing
    published yet."""
    r = subprocess.run([str(stepwatch_bin), "--once", "--json", "--domain", str(domain), "--wait-ms", str(wait_ms),
                        *extra], capture_output=True, text=True, timeout=wait_ms / 1000 + 10)
    return r.returncode, [json.loads(line) for line in r.stdout.splitlines() if line.strip()], r.stderr


def wait_for_snapshot(stepwatch_bin, domain, predicate, timeout=10.0, extra=()) -> List[dict]:
    """Repeats stepwatch --once until predicate(lines) holds; returns the last lines."""
    deadline = time.monotonic() + timeout
    lines: List[dict] = []
    while time.monotonic() < deadline:
        _, lines, _ = watch_once(stepwatch_bin, domain, *extra, wait_ms=3000)
        if predicate(lines):
            return lines
        time.sleep(0.3)
    pytest.fail(f"stepwatch never showed the expected state within {timeout} s; last: {lines}", pytrace=False)


def node_line(lines: List[dict], node: int) -> Optional[dict]:
    return next((l for l in lines if l["type"] == "node" and l["node"] == node), None)


def axis_line(lines: List[dict], node: int, axis: int) -> Optional[dict]:
    return next((l for l in lines if l["type"] == "axis" and l["node"] == node and l["axis"] == axis), None)


class LiveWatch:
    """stepwatch --json streaming every sample to a file until stopped."""

    def __init__(self, stepwatch_bin: Path, domain: int, path: Path, *extra: str):
        self.path = path
        with open(path, "wb") as f:
            self.proc = subprocess.Popen([str(stepwatch_bin), "--json", "--domain", str(domain), *extra],
                                         stdin=subprocess.DEVNULL, stdout=f, stderr=subprocess.STDOUT)

    def stop(self) -> List[dict]:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            self.proc.wait(5)
        return [json.loads(l) for l in self.path.read_text().splitlines() if l.startswith("{")]


@pytest.fixture
def domain() -> int:
    return fresh_domain()


@pytest.fixture
def start_bridge(domain, stepbridge_bin, tmp_path):
    """Factory: start_bridge(*extra_args) -> Process running stepbridge on vcan0 and the
    test's domain. Killed at teardown; its log is printed."""
    bridges: List[Process] = []
    counter = itertools.count(1)

    def _start(*extra, niceness: int = 0) -> Process:
        n = next(counter)
        extra = [str(e) for e in extra]
        level = [] if "--log-level" in extra else ["--log-level", "debug"]  # a test may ask for less
        # Under nice(1) every thread of the bridge (Fast DDS starts several) has the niceness;
        # setpriority() on the pid afterwards would reach the main thread only.
        prefix = ["nice", "-n", str(niceness)] if niceness else []
        argv = [*prefix, str(stepbridge_bin), "--iface", CHANNEL, "--domain", str(domain), *level, *extra]
        b = Process(argv, tmp_path / f"stepbridge-{n}.log")
        bridges.append(b)
        time.sleep(0.2)
        if not b.alive:
            pytest.fail(f"stepbridge exited at once (status {b.proc.returncode}):\n{b.log()}", pytrace=False)
        return b

    yield _start
    for b in bridges:
        b.terminate()
        print(f"--- stepbridge {' '.join(b.argv)} ---\n{b.log()[-6000:]}")


@pytest.fixture
def cyclone(domain, tmp_path):
    """A running cyclone_sub on the test's domain."""
    sub = CycloneSubscriber(domain, tmp_path / "cyclone_sub.log")
    yield sub
    sub.close()
    print(f"--- cyclone_sub (last lines) ---\n" + "\n".join(sub.tail(40)))


def status_changes(samples: List[Sample]) -> List[int]:
    """The status words of AxisStatus samples, consecutive repeats dropped."""
    seq: List[int] = []
    for s in samples:
        if s.topic != "AxisStatus" or s.disposed:
            continue
        v = s.int("status_bits")
        if not seq or seq[-1] != v:
            seq.append(v)
    return seq


__all__ = [n for n in dir() if not n.startswith("_")]
