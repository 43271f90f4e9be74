"""The process shape both SITL backends share (wiris_tools.sitl.process), with real lock files, real sockets
and a real process group: no SITL needed."""

from __future__ import annotations

import socket
import subprocess
import sys
import time

import pytest

from wiris_tools.errors import LinkError
from wiris_tools.sitl.process import InstanceLock, Instances, stop_process_group, udp_port_free


def _instances(tmp_name: str, ports, first: int = 1, last: int = 3) -> Instances:
    return Instances(tmp_name, first, last, ports, udp_port_free, "TEST SITL", "stop them")


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_two_locks_never_hold_the_same_instance(tmp_path):
    base = _free_udp_port()
    inst = _instances(f"wiris-test-{tmp_path.name}", lambda n: [base + 100 + n])
    a, b = InstanceLock(inst), InstanceLock(inst)
    try:
        assert a.instance != b.instance
    finally:
        a.release()
        b.release()


def test_an_instance_whose_port_is_taken_is_skipped_and_none_left_is_an_error(tmp_path):
    held = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    held.bind(("127.0.0.1", 0))
    port = held.getsockname()[1]
    try:
        only_taken = _instances(f"wiris-test-{tmp_path.name}-a", lambda n: [port], first=1, last=1)
        with pytest.raises(LinkError) as err:
            InstanceLock(only_taken)
        assert "no free TEST SITL instance in 1..1" in str(err.value) and err.value.hint == "stop them"
        free = _free_udp_port()
        one_free = _instances(f"wiris-test-{tmp_path.name}-b", lambda n: [port] if n == 1 else [free], last=2)
        lock = InstanceLock(one_free)
        assert lock.instance == 2
        lock.release()
    finally:
        held.close()


def test_stopping_a_process_group_ends_its_children():
    # a shell with a child that ignores nothing: both go with the group
    proc = subprocess.Popen([sys.executable, "-c", "import subprocess, sys, time; "
                             "c = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)']); "
                             "print(c.pid, flush=True); time.sleep(60)"],
                            stdout=subprocess.PIPE, text=True, start_new_session=True)
    child = int(proc.stdout.readline())
    stop_process_group(proc, grace_s=5.0)
    assert proc.poll() is not None
    for _ in range(100):
        try:
            with open(f"/proc/{child}/stat") as f:
                if f.read().split()[2] == "Z":
                    break
        except FileNotFoundError:
            break
        time.sleep(0.05)
    else:
        pytest.fail(f"child {child} still running after its group was stopped")
    proc.stdout.close()
