"""A stand-in for systemd's notification socket: an AF_UNIX datagram socket bound in the
test's temporary directory, as the service manager binds $NOTIFY_SOCKET. Every datagram
keeps its kernel receive time (SO_TIMESTAMPNS, CLOCK_REALTIME), the clock python-can
stamps CAN frames with, so a test can order a notification against a frame."""

from __future__ import annotations

import os
import select
import socket
import struct
import time
from dataclasses import dataclass
from pathlib import Path
from typing import List, Optional

SO_TIMESTAMPNS = 35  # asm-generic/socket.h; Python's socket module does not name it
_TIMESPEC = struct.Struct("@qq")


@dataclass
class Notification:
    text: str
    timestamp: float  # kernel receive time, seconds since the epoch


class NotifyListener:
    def __init__(self, path: Path):
        self.path = Path(path)
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.sock.bind(str(self.path))
        self.sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)

    def env(self, **extra: str) -> dict:
        """The environment a service manager gives: NOTIFY_SOCKET plus extra variables."""
        return {"NOTIFY_SOCKET": str(self.path), **extra}

    def receive(self, timeout: float) -> Optional[Notification]:
        ready, _, _ = select.select([self.sock], [], [], max(timeout, 0.0))
        if not ready:
            return None
        data, anc, _, _ = self.sock.recvmsg(4096, socket.CMSG_SPACE(_TIMESPEC.size))
        stamp = time.time()
        for level, kind, payload in anc:
            if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS:
                sec, ns = _TIMESPEC.unpack_from(payload)
                stamp = sec + ns / 1e9
        return Notification(data.decode(errors="replace"), stamp)

    def wait_for(self, text: str, timeout: float) -> Optional[Notification]:
        """The first notification equal to text within timeout (others are dropped)."""
        deadline = time.monotonic() + timeout
        while True:
            n = self.receive(deadline - time.monotonic())
            if n is None or n.text == text:
                return n

    def collect(self, duration: float) -> List[Notification]:
        out = []
        deadline = time.monotonic() + duration
        while (remaining := deadline - time.monotonic()) > 0:
            n = self.receive(remaining)
            if n is not None:
                out.append(n)
        return out

    def close(self) -> None:
        self.sock.close()
        try:
            os.unlink(self.path)
        except OSError:
            pass
