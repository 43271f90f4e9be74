"""Real third-party parsers of camera definition files, as test peers other tests can reuse.

    import peers
    r = peers.mavsdk_load_definition(xml_bytes, tmp_path)      # MAVSDK 4.1.0 camera plugin, over HTTP
    r.accepted, r.crashed, r.settings, r.dropped
    rs = peers.mavsdk_load_definitions([b1, b2, ...], tmp_path)  # many files, one worker process
    m = peers.mavproxy_load_definition(xml_bytes)               # MAVProxy's CameraDefinition parser
    m.accepted, m.error, m.settings

MAVSDK runs in a worker subprocess (tests/peers_mavsdk_worker.py) because it crashes the whole process
on some definitions (reference §D); a crash is recorded as "rejects" and the worker is restarted for the
next file. HOME and TMPDIR of the worker point into the caller's scratch directory: MAVSDK caches
definitions by vendor+model+version under $HOME and leaves temp directories in $TMPDIR.
"""

from __future__ import annotations

import json
import lzma
import os
import queue
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

WORKER = Path(__file__).resolve().with_name("peers_mavsdk_worker.py")
XZ_MAGIC = b"\xfd7zXZ\x00"


@dataclass(frozen=True)
class MavsdkResult:
    """What MAVSDK's camera plugin made of one definition file."""

    accepted: bool  # the definition loaded (settings API answers)
    crashed: bool  # the process died while loading it (counts as a rejection)
    outcome: str  # accepted | rejected | crashed | timeout | no-system | harness-error
    # visible settings (control != 0, not excluded at the defaults) -> option values as MAVSDK lists them
    # (a min/max/step range appears as MAVSDK's pseudo-options)
    settings: dict[str, tuple[str, ...]] = field(default_factory=dict)
    known: frozenset[str] = frozenset()  # file parameters MAVSDK answers get_setting for
    file_parameters: tuple[str, ...] = ()  # parameter names in the file (document order)
    requested: tuple[str, ...] = ()  # names MAVSDK asked the camera for (PARAM_EXT_REQUEST_READ)
    log: str = ""

    @property
    def dropped(self) -> tuple[str, ...]:
        """Parameters of the file that MAVSDK silently skipped (only meaningful when accepted)."""
        if not self.accepted:
            return ()
        return tuple(n for n in self.file_parameters if n not in self.known)


@dataclass(frozen=True)
class MavproxyResult:
    """What MAVProxy's CameraDefinition parser made of one definition file."""

    accepted: bool
    error: str | None
    settings: dict[str, tuple[object, ...]] = field(default_factory=dict)  # controls at default values
    parameters: tuple[str, ...] = ()


def plain_xml(data: bytes) -> bytes:
    """The XML inside an .xz container (MAVSDK 4.1.0 does not inflate .xml.xz fetched over HTTP, so the
    harness serves the content plain: it measures the parser, not that transport gap)."""
    if data.startswith(XZ_MAGIC):
        return lzma.decompress(data)
    return data


def _file_parameter_names(data: bytes) -> tuple[str, ...]:
    from lxml import etree

    from cdf.xmlsafe import parse_xml

    # the validator's loader: it also reads UTF-8 declared as another encoding, as MAVSDK does
    root, _problems = parse_xml(data, "peer.xml")
    if root is None:
        return ()
    return tuple(p.get("name") for p in root.iter("parameter") if p.get("name"))


class _Worker:
    def __init__(self, env: dict[str, str]) -> None:
        self.proc = subprocess.Popen([sys.executable, str(WORKER)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                                     text=True, bufsize=1)
        self.lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line)
        self.lines.put(None)

    def run(self, job: dict, timeout_s: float) -> tuple[dict | None, str]:
        """(result or None when the worker died / hung, stray output)."""
        assert self.proc.stdin is not None
        try:
            self.proc.stdin.write(json.dumps(job) + "\n")
            self.proc.stdin.flush()
        except BrokenPipeError:
            return None, "worker gone"
        stray = []
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                line = self.lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                self.kill()
                return None, "".join(stray) + "\n[harness] timeout: worker killed"
            if line is None:
                self.proc.wait(5)
                return None, "".join(stray) + f"\n[harness] worker exited rc={self.proc.returncode}"
            if line.startswith("@@RESULT "):
                return json.loads(line[len("@@RESULT "):]), "".join(stray)
            if not line.startswith("@@START"):
                stray.append(line)

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()  # our own child, by its handle
            self.proc.wait(5)

    def close(self) -> None:
        if self.proc.poll() is None and self.proc.stdin is not None:
            try:
                self.proc.stdin.close()
                self.proc.wait(10)
            except (BrokenPipeError, subprocess.TimeoutExpired):
                pass
        self.kill()


def mavsdk_load_definitions(definitions: Sequence[bytes], workdir: Path, *, wait_s: float = 12.0,
                            job_timeout_s: float = 40.0, workers: int = 2) -> list[MavsdkResult]:
    """Load each definition into MAVSDK's camera plugin from a fake camera over HTTP. Files are split over
    `workers` worker processes, each loading its share one after another (restarted after a crash);
    `workdir/wN` becomes worker N's HOME and TMPDIR. Results come back in input order."""
    defs = list(definitions)
    workers = max(1, min(workers, len(defs)))
    if workers == 1:
        return _load_serial(defs, Path(workdir) / "w0", 0, wait_s, job_timeout_s)
    shares = [list(range(i, len(defs), workers)) for i in range(workers)]
    out: list[MavsdkResult | None] = [None] * len(defs)

    def run(n: int) -> None:
        res = _load_serial([defs[i] for i in shares[n]], Path(workdir) / f"w{n}", n, wait_s, job_timeout_s)
        for i, r in zip(shares[n], res):
            out[i] = r

    threads = [threading.Thread(target=run, args=(n,)) for n in range(workers)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    missing = [i for i, r in enumerate(out) if r is None]
    if missing:
        raise RuntimeError(f"MAVSDK harness produced no result for definitions {missing}")
    return out  # type: ignore[return-value]


def _load_serial(definitions: Sequence[bytes], workdir: Path, tag: int, wait_s: float,
                 job_timeout_s: float) -> list[MavsdkResult]:
    workdir = Path(workdir)
    home, tmp, files = workdir / "home", workdir / "tmp", workdir / "defs"
    for d in (home, tmp, files):
        d.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, HOME=str(home), TMPDIR=str(tmp), MAVLINK20="1")
    stamp = f"{os.getpid() % 10000}{time.monotonic_ns() % 100000}w{tag}"
    results: list[MavsdkResult] = []
    worker: _Worker | None = None
    try:
        for index, raw in enumerate(definitions):
            data = plain_xml(raw)
            path = files / f"def{index}.xml"
            path.write_bytes(data)
            names = _file_parameter_names(data)
            if worker is None or worker.proc.poll() is not None:
                worker = _Worker(env)
            # unique per file: MAVSDK's cache is keyed by vendor+model+version
            job = {"job": index, "path": str(path), "model": f"peer{stamp}n{index}", "wait_s": wait_s}
            res, stray = worker.run(job, job_timeout_s)
            if res is None:
                worker.close()
                worker = None
                crashed = "timeout" not in stray
                results.append(MavsdkResult(False, crashed, "crashed" if crashed else "timeout",
                                            file_parameters=names, log=stray))
                continue
            log = "\n".join(res.get("log", [])) + ("\n" + stray if stray else "")
            # parsed = answers get_setting, or was requested from the camera by name
            known = {n for n, v in res.get("known", {}).items() if v is not None} | set(res.get("requested", ()))
            results.append(MavsdkResult(
                accepted=res["outcome"] == "accepted", crashed=False, outcome=res["outcome"],
                settings={k: tuple(v) for k, v in res.get("settings", {}).items()},
                known=frozenset(known), file_parameters=names,
                requested=tuple(res.get("requested", ())), log=log))
    finally:
        if worker is not None:
            worker.close()
    return results


def mavsdk_load_definition(xml_bytes: bytes, tmpdir: Path, **kw) -> MavsdkResult:
    """One definition through MAVSDK's camera plugin (see mavsdk_load_definitions)."""
    return mavsdk_load_definitions([xml_bytes], tmpdir, **kw)[0]


def mavproxy_load_definition(xml_bytes: bytes) -> MavproxyResult:
    """Parse with MAVProxy's `CameraDefinition` (it inflates xz itself) and list its controls with every
    parameter at its default value."""
    from MAVProxy.modules.mavproxy_camera.definition import CameraDefinition

    try:
        cd = CameraDefinition(xml_bytes, locale_name="en_US")
    except Exception as err:  # its documented failures are ValueError; anything else is a rejection too
        return MavproxyResult(False, f"{type(err).__name__}: {err}")
    values = {p.name: p.default for p in cd.parameters.values() if p.default is not None}
    try:
        controls = cd.controls(values)
    except Exception as err:
        return MavproxyResult(False, f"controls(): {type(err).__name__}: {err}", parameters=tuple(cd.parameters))
    settings = {name: tuple(v for _label, v in opts) for name, opts in controls.items()}
    return MavproxyResult(True, None, settings, tuple(cd.parameters))


# ---- corpus agreement: the real parsers vs the validator's profiles ----------------------------------------

# Rules whose finding means "MAVSDK silently skips this parameter" (reference §4.3, measured §D).
MAVSDK_DROP_RULES = frozenset({"CDF112", "CDF113", "CDF116", "CDF119", "CDF123", "CDF127", "CDF203"})


@dataclass(frozen=True)
class AgreementRow:
    file: str
    mavsdk: MavsdkResult
    mavproxy: MavproxyResult
    reports: dict  # profile -> cdf.validate.Report
    predicted_drops: tuple[str, ...]

    def mavsdk_cell(self) -> str:
        if self.mavsdk.crashed:
            return "crash"
        if not self.mavsdk.accepted:
            return self.mavsdk.outcome.replace("rejected", "rejects")
        return f"drops {len(self.mavsdk.dropped)}" if self.mavsdk.dropped else "accepts"

    def profile_cell(self, profile: str) -> str:
        r = self.reports[profile]
        return "valid" if r.valid else "ERR " + ",".join(sorted(r.rules("error")))


def corpus_agreement(paths: Sequence[Path], workdir: Path, *, workers: int = 3) -> list[AgreementRow]:
    from cdf.validate import PROFILES, validate_bytes

    datas = [Path(p).read_bytes() for p in paths]
    msdk = mavsdk_load_definitions(datas, workdir, workers=workers)
    rows = []
    for path, data, m in zip(paths, datas, msdk):
        reports = {prof: validate_bytes(data, Path(path).name, prof) for prof in PROFILES}
        drops = {f.parameter for f in reports["mavsdk"].findings
                 if f.rule in MAVSDK_DROP_RULES and f.parameter is not None}
        predicted = tuple(n for n in m.file_parameters if n in drops)
        rows.append(AgreementRow(Path(path).name, m, mavproxy_load_definition(data), reports, predicted))
    return rows


def format_agreement(rows: Sequence[AgreementRow]) -> str:
    head = ("file", "MAVSDK", "MAVProxy", "qgc", "mavsdk", "strict")
    body = [(r.file, r.mavsdk_cell(), "accepts" if r.mavproxy.accepted else "rejects",
             r.profile_cell("qgc"), r.profile_cell("mavsdk"), r.profile_cell("strict")) for r in rows]
    widths = [max(len(x[i]) for x in [head, *body]) for i in range(len(head))]
    lines = ["| " + " | ".join(c.ljust(w) for c, w in zip(head, widths)) + " |",
             "|" + "|".join("-" * (w + 2) for w in widths) + "|"]
    lines += ["| " + " | ".join(c.ljust(w) for c, w in zip(row, widths)) + " |" for row in body]
    return "\n".join(lines)
