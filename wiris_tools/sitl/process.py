"""What both SITL backends share around the firmware's process: an instance number held through a lock file
with every port it uses free, a working folder with the ground-station tlog, the firmware in a process group
of its own, and closing all of it so nothing is left running.

    class MySitl(SitlProcess):
        def __init__(self, ...):
            self._open_workdir(options.workdir, prefix="wiris-my-")
            self._lock = InstanceLock(INSTANCES, ...)
            ...
"""

from __future__ import annotations

import errno
import fcntl
import os
import signal
import socket
import subprocess
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

from wiris_tools.errors import LinkError
from wiris_tools.link import Link
from wiris_tools.sitl.monitor import MonitorRecord

STOP_GRACE_S = 5.0


def tcp_port_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def udp_port_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


@dataclass(frozen=True)
class Instances:
    """The instance numbers a backend may use and how to tell one is free."""

    lock_name: str                                 # lock files are <tmp>/<lock_name>-<n>.lock
    first: int
    last: int
    ports: Callable[[int], Iterable[int]]          # every port instance n uses
    port_free: Callable[[int], bool]
    what: str                                      # "SITL", "PX4 SITL": for the error
    hint: str


class InstanceLock:
    """An instance number held through a lock file, so two harnesses (or test processes) never pick the same,
    with every port it uses free (a SITL started by hand, or by another harness, holds them)."""

    def __init__(self, instances: Instances) -> None:
        order = list(range(instances.first, instances.last + 1))
        start = os.getpid() % len(order)          # spread concurrent starters over the range
        for n in order[start:] + order[:start]:
            path = Path(tempfile.gettempdir()) / f"{instances.lock_name}-{n}.lock"
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as err:
                os.close(fd)
                if err.errno in (errno.EAGAIN, errno.EACCES):
                    continue
                raise
            if all(instances.port_free(p) for p in instances.ports(n)):
                self.instance, self._fd = n, fd
                return
            os.close(fd)
        raise LinkError(f"no free {instances.what} instance in {instances.first}..{instances.last}",
                        hint=instances.hint)

    def release(self) -> None:
        os.close(self._fd)


def stop_process_group(proc: subprocess.Popen | None, grace_s: float = STOP_GRACE_S) -> None:
    """SIGTERM the process's group (the firmware and any script around it), SIGKILL after `grace_s`."""
    if proc is None or proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(grace_s)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    except ProcessLookupError:
        pass


class SitlProcess(MonitorRecord):
    """The shape both backends share: `_open_workdir` (the folder and its gcs.tlog), `_lock`, `_proc`,
    `_link` (the monitor link), and `close` ending them in order."""

    _link: Link | None = None
    _proc: subprocess.Popen | None = None
    _lock: InstanceLock | None = None

    def _open_workdir(self, workdir: str | os.PathLike | None, prefix: str) -> None:
        self.workdir = Path(workdir or tempfile.mkdtemp(prefix=prefix)).resolve()
        self.workdir.mkdir(parents=True, exist_ok=True)
        self.tlog = self.workdir / "gcs.tlog"
        self._tlog_file = open(self.tlog, "ab")
        self._tlog_lock = threading.Lock()
        self._statustext: list[str] = []

    def _alive(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    def _stop_process(self) -> None:
        if self._link is not None:
            self._link.close()
            self._link = None
        stop_process_group(self._proc)

    def close(self) -> None:
        self._stop_process()
        if getattr(self, "_tlog_file", None) is not None:
            with self._tlog_lock:
                self._tlog_file.close()
        if self._lock is not None:
            self._lock.release()
            self._lock = None

    def __enter__(self):
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
