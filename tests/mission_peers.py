"""MAVSDK 4.1.0 mission peers for tests and benchmarks, each in a child process
(tests/mission_peers_worker.py): MAVSDK aborts or wedges its process on some inputs.

    import mission_peers
    res = mission_peers.mavsdk_import_plan(plan_text, tmp_path, autopilot="px4")   # QGC importer
    server = mission_peers.MavsdkServer(tmp_path)   # mission_raw_server: the vehicle, on server.port
    result, items = server.incoming()
    client = mission_peers.MavsdkClient(port, tmp_path)   # mission_raw: the ground station
    client.upload(items); client.download()

Each child gets HOME and TMPDIR inside `scratch`.
"""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
import sys
import threading
import queue
from pathlib import Path

from missions.emit.items import MissionItem

WORKER = Path(__file__).resolve().with_name("mission_peers_worker.py")


def free_udp_port() -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def item_to_dict(it: MissionItem, seq: int) -> dict:
    return {"seq": seq, "frame": it.frame, "command": it.command, "current": int(seq == 0),
            "autocontinue": it.autocontinue, "param1": it.param1, "param2": it.param2, "param3": it.param3,
            "param4": it.param4, "x": it.x, "y": it.y, "z": it.z, "mission_type": it.mission_type}


def item_from_dict(d: dict) -> MissionItem:
    return MissionItem(command=d["command"], frame=d["frame"], param1=d["param1"], param2=d["param2"],
                       param3=d["param3"], param4=d["param4"], x=d["x"], y=d["y"], z=d["z"],
                       autocontinue=d["autocontinue"], current=d["current"], mission_type=d["mission_type"])


def _env(scratch: Path) -> dict:
    home = scratch / "home"
    tmp = scratch / "tmp"
    home.mkdir(parents=True, exist_ok=True)
    tmp.mkdir(parents=True, exist_ok=True)
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, HOME=str(home), TMPDIR=str(tmp))
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(root), env.get("PYTHONPATH", "")) if p)
    return env


def mavsdk_import_plan(text: str, scratch: Path, autopilot: str = "px4", timeout: float = 60) -> dict:
    """MAVSDK's QGC importer on `text`: {"ok", "mission", "fence", "rally"} with MissionItems."""
    proc = subprocess.run([sys.executable, str(WORKER), "import", "--autopilot", autopilot], input=text,
                          capture_output=True, text=True, timeout=timeout, env=_env(scratch))
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if not lines:
        return {"ok": False, "error": f"worker exit {proc.returncode}: {proc.stderr[-500:]}"}
    res = json.loads(lines[-1])
    for k in ("mission", "fence", "rally"):
        if k in res:
            res[k] = [item_from_dict(d) for d in res[k]]
    return res


class _Child:
    def __init__(self, args: list[str], scratch: Path) -> None:
        self.proc = subprocess.Popen([sys.executable, str(WORKER), *args], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                                     env=_env(scratch))
        self.lines: queue.Queue = queue.Queue()
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            if line.startswith("{"):
                self.lines.put(json.loads(line))
        self.lines.put(None)

    def next(self, timeout: float) -> dict | None:
        try:
            return self.lines.get(timeout=timeout)
        except queue.Empty:
            return None

    def send(self, obj: dict) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(obj) + "\n")
        self.proc.stdin.flush()

    def close(self) -> None:
        try:
            if self.proc.stdin:
                self.proc.stdin.close()
            self.proc.wait(timeout=10)
        except (subprocess.TimeoutExpired, OSError, BrokenPipeError):
            self.proc.kill()   # only the child we started, by its handle
            self.proc.wait(timeout=5)


class MavsdkServer(_Child):
    """MAVSDK mission_raw_server as the vehicle (system 1, component 1) on udpin://127.0.0.1:port."""

    def __init__(self, scratch: Path) -> None:
        self.port = free_udp_port()
        super().__init__(["server", "--port", str(self.port)], scratch)
        ready = self.next(30)
        if not ready or not ready.get("ready"):
            self.close()
            raise RuntimeError("MAVSDK mission_raw_server did not start")

    def incoming(self, timeout: float = 30) -> tuple[str, list[MissionItem]] | None:
        msg = self.next(timeout)
        if msg is None:
            return None
        return msg["incoming"], [item_from_dict(d) for d in msg["items"]]


class MavsdkClient(_Child):
    """MAVSDK mission_raw as the ground station, sending to udpout://127.0.0.1:port."""

    def __init__(self, port: int, scratch: Path) -> None:
        super().__init__(["client", "--port", str(port)], scratch)
        ready = self.next(40)
        if not ready or not ready.get("ready"):
            self.close()
            raise RuntimeError(f"MAVSDK mission_raw found no autopilot: {ready}")

    def upload(self, items: list[MissionItem], timeout: float = 300) -> dict:
        self.send({"op": "upload", "items": [item_to_dict(it, i) for i, it in enumerate(items)]})
        return self.next(timeout) or {"ok": False, "error": "no answer from the MAVSDK worker"}

    def download(self, timeout: float = 300) -> dict:
        self.send({"op": "download"})
        res = self.next(timeout) or {"ok": False, "error": "no answer from the MAVSDK worker"}
        if res.get("items") is not None:
            res["items"] = [item_from_dict(d) for d in res["items"]]
        return res


def nan_safe_equal(a: float, b: float) -> bool:
    return a == b or (math.isnan(a) and math.isnan(b))
