"""`wiris cdf serve`: a real threaded HTTP server on 127.0.0.1 (port 0) over a built bundle — content types,
GET/HEAD, ETag/Last-Modified/304, 405, no escape out of the directory, one log line per request."""

from __future__ import annotations

import contextlib
import hashlib
import http.client
import json
import os
import re
import signal
import socket
import threading
from pathlib import Path

import pytest

from cdf.bundle import build_bundle
from cdf.errors import WirisError
from cli_child import stop, wiris_child
from wiris_tools.serve import make_server, prefix_from_manifest, server_url

PRO = "workswell_wiris-pro_v1.xml"


@contextlib.contextmanager
def serving(directory, host: str = "127.0.0.1", **kwargs):
    """make_server(directory, host, 0, **kwargs) serving in a thread for the block, then shut down."""
    srv = make_server(directory, host, 0, **kwargs)
    thread = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    try:
        yield srv
    finally:
        srv.shutdown()
        srv.server_close()
        thread.join(5)


@pytest.fixture(scope="module")
def bundle(tmp_path_factory) -> Path:
    base = tmp_path_factory.mktemp("serve")
    out = base / "cdf"
    build_bundle(out, ["wiris-pro", "wiris-security"], base_url="http://127.0.0.1:8000/cdf", xz=True)
    (base / "secret.txt").write_text("outside the bundle")
    os.symlink(base / "secret.txt", out / "leak.xml")                    # points outside: 403
    os.symlink(out / PRO, out / "alias.xml")                              # points inside: fine
    (out / ".hidden.xml").write_text("<x/>")
    (out / "sub").mkdir()
    return out


@pytest.fixture
def server(bundle):
    lines: list[str] = []
    with serving(bundle, log=lines.append) as srv:
        yield srv, lines


def request(srv, method: str, path: str, headers: dict | None = None):
    conn = http.client.HTTPConnection("127.0.0.1", srv.server_address[1], timeout=10)
    try:
        conn.putrequest(method, path, skip_accept_encoding=True)
        for k, v in (headers or {}).items():
            conn.putheader(k, v)
        conn.endheaders()
        resp = conn.getresponse()
        return resp.status, {k.lower(): v for k, v in resp.getheaders()}, resp.read()
    finally:
        conn.close()


def test_serves_definitions_xz_and_manifest_with_their_content_types(server, bundle):
    srv, lines = server
    assert server_url(srv).endswith("/cdf/")   # the path of the manifest's URIs
    for name, ctype in ((PRO, "application/xml"), (PRO + ".xz", "application/x-xz"),
                        ("manifest.json", "application/json")):
        status, headers, body = request(srv, "GET", f"/cdf/{name}")
        assert status == 200
        assert headers["content-type"] == ctype
        assert body == (bundle / name).read_bytes()
        assert headers["content-length"] == str(len(body))
        assert headers["etag"] == f'"{hashlib.sha256(body).hexdigest()}"'
        assert "last-modified" in headers
    manifest = json.loads(request(srv, "GET", "/cdf/manifest.json")[2])
    row = next(r for r in manifest["models"] if r["file"] == PRO)
    assert request(srv, "GET", f"/cdf/{PRO}")[1]["etag"] == f'"{row["sha256"]}"'   # ETag = manifest sha256
    assert lines[0] == f"GET /cdf/{PRO} 200 {row['bytes']}"
    assert len(lines) == 5


def test_versioned_files_are_immutable_and_the_manifest_revalidated(server):
    srv, _ = server
    assert "immutable" in request(srv, "GET", f"/cdf/{PRO}")[1]["cache-control"]
    assert request(srv, "GET", "/cdf/manifest.json")[1]["cache-control"] == "no-cache"


def test_head_has_the_headers_and_no_body(server, bundle):
    srv, lines = server
    status, headers, body = request(srv, "HEAD", f"/cdf/{PRO}")
    assert status == 200 and body == b""
    assert headers["content-length"] == str((bundle / PRO).stat().st_size)
    assert lines == [f"HEAD /cdf/{PRO} 200 0"]


def test_if_none_match_answers_304(server):
    srv, lines = server
    etag = request(srv, "GET", f"/cdf/{PRO}")[1]["etag"]
    status, headers, body = request(srv, "GET", f"/cdf/{PRO}", {"If-None-Match": etag})
    assert status == 304 and body == b"" and headers["etag"] == etag
    assert request(srv, "GET", f"/cdf/{PRO}", {"If-None-Match": f'"x", W/{etag}'})[0] == 304
    assert request(srv, "GET", f"/cdf/{PRO}", {"If-None-Match": '"other"'})[0] == 200
    last = request(srv, "HEAD", f"/cdf/{PRO}")[1]["last-modified"]
    assert request(srv, "GET", f"/cdf/{PRO}", {"If-Modified-Since": last})[0] == 304
    assert request(srv, "GET", f"/cdf/{PRO}", {"If-Modified-Since": "Thu, 01 Jan 1970 00:00:00 GMT"})[0] == 200
    assert request(srv, "GET", f"/cdf/{PRO}", {"If-Modified-Since": "garbage"})[0] == 200
    assert f"GET /cdf/{PRO} 304 0" in lines


@pytest.mark.parametrize("path", [
    "/cdf/../secret.txt", "/cdf/%2e%2e/secret.txt", "/cdf/%2E%2E%2Fsecret.txt", "/cdf/..%2fsecret.txt",
    "/cdf/%252e%252e/secret.txt", "/cdf/sub/../../secret.txt", "/cdf//etc/passwd", "/cdf/..\\secret.txt",
    "/cdf/%00", "/cdf/.hidden.xml", "/cdf/sub", "/cdf/", "/cdf/nope.xml", "/secret.txt", "/" + PRO,
    "/cdf/%ff.xml", "/cdf/./" + PRO,
])
def test_nothing_outside_the_bundle_or_hidden_is_served(server, path):
    srv, _ = server
    status, _, body = request(srv, "GET", path)
    assert status == 404
    assert b"outside the bundle" not in body


def test_a_symlink_out_of_the_bundle_is_forbidden_one_inside_is_served(server, bundle):
    srv, lines = server
    status, _, body = request(srv, "GET", "/cdf/leak.xml")
    assert status == 403 and b"outside" not in body
    status, _, body = request(srv, "GET", "/cdf/alias.xml")
    assert status == 200 and body == (bundle / PRO).read_bytes()
    assert lines[0].startswith("GET /cdf/leak.xml 403 ")


@pytest.mark.parametrize("method", ["POST", "PUT", "DELETE", "PATCH", "OPTIONS", "TRACE", "FOO"])
def test_other_methods_are_405_and_change_nothing(server, bundle, method):
    srv, lines = server
    before = (bundle / PRO).read_bytes()
    status, headers, _ = request(srv, method, f"/cdf/{PRO}")
    assert status == 405 and headers["allow"] == "GET, HEAD"
    assert (bundle / PRO).read_bytes() == before
    assert lines == [f"{method} /cdf/{PRO} 405 {int(headers['content-length'])}"]


def raw_request(srv, data: bytes) -> bytes:
    """Send bytes that http.client would not, and return the start of the answer."""
    with socket.create_connection(("127.0.0.1", srv.server_address[1]), timeout=5) as s:
        s.sendall(data)
        return s.recv(1024)


def test_a_malformed_request_gets_an_error_not_a_crash(server):
    srv, lines = server
    assert raw_request(srv, b"GARBAGE\r\n\r\n").startswith(b"HTTP/1.1 400")
    # HTTP/0.9: refused, not served header-less
    assert raw_request(srv, b"GET /cdf/" + PRO.encode() + b"\r\n\r\n").startswith(b"HTTP/1.1 400")
    assert request(srv, "GET", f"/cdf/{PRO}")[0] == 200   # still serving
    assert lines[0] == "- - 400 " + lines[0].rsplit(" ", 1)[1]


def test_a_broken_absolute_target_is_400_not_a_dropped_connection(server):
    srv, lines = server
    answer = raw_request(srv, b"GET http://[::1/cdf/x.xml HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
    assert answer.startswith(b"HTTP/1.1 400")
    assert lines == ["GET http://[::1/cdf/x.xml 400 12"]


def test_stalled_and_idle_connections_are_closed_after_the_idle_timeout(bundle):
    """Every connection holds a server thread: one that sends half a request, or stays open after its
    answer (HTTP/1.1 keep-alive), is closed once idle for idle_timeout_s (it used to be held for ever)."""
    lines: list[str] = []
    with serving(bundle, log=lines.append, idle_timeout_s=0.3) as srv:
        port = srv.server_address[1]
        with socket.create_connection(("127.0.0.1", port), timeout=5) as stalled, \
                socket.create_connection(("127.0.0.1", port), timeout=5) as idle:
            stalled.sendall(b"GET /cdf/" + PRO.encode())  # no end of line, ever
            idle.sendall(f"GET /cdf/{PRO} HTTP/1.1\r\nHost: x\r\n\r\n".encode())
            answer = b""
            while b"</mavlinkcamera>" not in answer:
                chunk = idle.recv(65536)
                assert chunk, "closed before the whole answer"
                answer += chunk
            assert answer.startswith(b"HTTP/1.1 200")
            assert stalled.recv(1) == b""  # closed by the server, not the 5 s socket timeout here
            assert idle.recv(1) == b""
        assert request(srv, "GET", f"/cdf/{PRO}")[0] == 200  # still serving
        body = answer.split(b"\r\n\r\n", 1)[1]
        assert lines == [f"GET /cdf/{PRO} 200 {len(body)}"] * 2


def test_connections_over_the_cap_get_503_and_the_slot_comes_back(bundle):
    """Each served connection holds a thread: beyond max_connections the accepting thread answers 503 with
    Retry-After and closes (a flood of connections used to start threads without bound); a slot frees when
    its connection ends."""
    import time

    lines: list[str] = []
    with serving(bundle, log=lines.append, max_connections=2) as srv:
        port = srv.server_address[1]
        held = [socket.create_connection(("127.0.0.1", port), timeout=5) for _ in range(2)]
        for s in held:
            s.sendall(b"GET /cdf/" + PRO.encode())  # half a request: the connection keeps its thread
        # accepted in order, so both hold their slot by the time this one is accepted
        status, headers, body = request(srv, "GET", f"/cdf/{PRO}")
        assert status == 503 and headers["retry-after"] == "1" and headers["connection"] == "close"
        assert body == b"too many connections; retry shortly\n"
        assert len(lines) == 1 and re.fullmatch(r"- 127\.0\.0\.1:\d+ 503 over the limit of 2 connections", lines[0])
        with socket.create_connection(("127.0.0.1", port), timeout=5) as raw:  # sends nothing: still answered
            assert raw.recv(65536).startswith(b"HTTP/1.1 503 ")
        held.pop().close()
        deadline = time.monotonic() + 5
        while (status := request(srv, "GET", f"/cdf/{PRO}")[0]) == 503 and time.monotonic() < deadline:
            time.sleep(0.02)  # the closed connection's thread has not yet seen the end
        assert status == 200
        held.pop().close()


def test_a_ctrl_c_landing_in_thread_start_stops_the_server(bundle, monkeypatch):
    """Under load the connection's thread can serve its request and give its slot back before Thread.start
    returns in the accepting thread; a Ctrl-C landing then must stop the server. (It was lost: the slot was
    given back a second time, the KeyError replaced the KeyboardInterrupt, and socketserver logged it as an
    internal error and went on serving: `wiris cdf serve` ignored the Ctrl-C.)"""
    srv = make_server(bundle, "127.0.0.1", 0, log=(lines := []).append)
    ended: list[BaseException | None] = []

    def serve() -> None:
        try:
            srv.serve_forever(poll_interval=0.05)
            ended.append(None)
        except BaseException as err:  # noqa: BLE001 (the test wants whatever ended it)
            ended.append(err)

    runner = threading.Thread(target=serve, daemon=True)
    runner.start()

    class InterruptedAfterServing(threading.Thread):
        def start(self) -> None:
            super().start()
            self.join(10)              # the connection is served and its slot given back...
            raise KeyboardInterrupt    # ...and then the Ctrl-C lands in the accepting thread

    monkeypatch.setattr(threading, "Thread", InterruptedAfterServing)
    try:
        status, _, _ = request(srv, "GET", f"/cdf/{PRO}")
        runner.join(10)
    finally:
        monkeypatch.undo()
        if runner.is_alive():
            srv.shutdown()
        srv.server_close()
    assert status == 200
    assert len(ended) == 1 and isinstance(ended[0], KeyboardInterrupt), (ended, lines)
    assert srv._slots.in_use == 0 and not any("internal error" in line for line in lines), lines


def test_a_slot_is_given_back_once():
    from wiris_tools.serve import Refusal, Slots

    slots = Slots(total=2, per_client=1)
    first = slots.take("10.0.0.1")
    assert slots.take("10.0.0.1") == Refusal("over the limit of 1 connections from one address")
    first.give_back()
    first.give_back()                       # the second give-back changes nothing
    assert slots.in_use == 0
    again, other = slots.take("10.0.0.1"), slots.take("10.0.0.2")
    assert slots.in_use == 2 and slots.take("10.0.0.3") == Refusal("over the limit of 2 connections")
    again.give_back(), other.give_back()
    assert slots.in_use == 0


def _closed_by_server(sock: socket.socket, wait_s: float) -> bool:
    """Whether the server has closed `sock`, waiting at most `wait_s` for it to say so."""
    import select

    if not select.select([sock], [], [], wait_s)[0]:
        return False
    try:
        return sock.recv(65536) == b""
    except ConnectionError:
        return True


def test_a_request_trickled_in_is_closed_at_the_request_deadline(bundle):
    """A byte of a header every 0.05 s keeps a per-read timeout (here 10 s) from ever firing: 64 such clients
    held every slot for as long as they liked. The request line and headers must all arrive within
    request_timeout_s of their first byte; a keep-alive connection idle between requests is not cut by it."""
    import time

    lines: list[str] = []
    with serving(bundle, log=lines.append, idle_timeout_s=10, request_timeout_s=0.3) as srv:
        port = srv.server_address[1]
        with socket.create_connection(("127.0.0.1", port), timeout=5) as slow:
            slow.sendall(f"GET /cdf/{PRO} HTTP/1.1\r\nX-Slow: ".encode())
            closed = False
            for _ in range(400):   # 20 s of one header line, far beyond 0.3 s and within no per-read timeout
                try:
                    slow.sendall(b"a")
                except ConnectionError:
                    closed = True
                if closed or (closed := _closed_by_server(slow, 0.05)):
                    break
            assert closed, "the trickled request was never cut off"
        with socket.create_connection(("127.0.0.1", port), timeout=5) as kept:
            for _ in range(2):   # the second request comes after an idle pause longer than the deadline
                kept.sendall(f"HEAD /cdf/{PRO} HTTP/1.1\r\nHost: x\r\n\r\n".encode())
                assert kept.recv(65536).startswith(b"HTTP/1.1 200")
                time.sleep(0.6)
        assert lines == [f"HEAD /cdf/{PRO} 200 0"] * 2   # the cut-off request is no request to log


def test_one_client_address_holds_at_most_max_per_client_slots(bundle):
    """Slow connections from one address take at most max_per_client of the slots: the next from that
    address gets 503 while another address (127.0.0.2, also loopback) is still served."""
    lines: list[str] = []
    with serving(bundle, log=lines.append, max_connections=4, max_per_client=2) as srv:
        port = srv.server_address[1]
        held = [socket.create_connection(("127.0.0.1", port), timeout=5) for _ in range(2)]
        try:
            for s in held:
                s.sendall(b"GET /cdf/" + PRO.encode())  # half a request: the connection keeps its slot
            status, headers, _ = request(srv, "GET", f"/cdf/{PRO}")
            assert status == 503 and headers["retry-after"] == "1"
            assert re.fullmatch(r"- 127\.0\.0\.1:\d+ 503 over the limit of 2 connections from one address",
                                lines[0]), lines
            with socket.create_connection(("127.0.0.1", port), timeout=5, source_address=("127.0.0.2", 0)) as other:
                other.sendall(f"HEAD /cdf/{PRO} HTTP/1.1\r\nHost: x\r\n\r\n".encode())
                assert other.recv(65536).startswith(b"HTTP/1.1 200")
        finally:
            for s in held:
                s.close()


@pytest.mark.parametrize("path", ["/cdf/" + "a" * 256, "/cdf/" + "%C3%A9" * 128, "/cdf/" + "a/" * 1100])
def test_an_over_long_segment_or_path_is_414_in_a_short_log_line(server, path):
    # a segment over 255 bytes used to raise ENAMETOOLONG out of the handler: no answer at all, and a log
    # line of the whole path
    srv, lines = server
    status, _, body = request(srv, "GET", path)
    assert status == 414 and body == b"URI too long\n"
    assert len(lines) == 1 and lines[0].endswith("… 414 13") and len(lines[0]) < 220, lines
    assert request(srv, "GET", "/cdf/" + "a" * 255)[0] == 404   # the longest name a file can have


def test_control_characters_in_a_logged_request_are_escaped(server):
    # logged raw, an escape sequence in a request reached the operator's terminal
    srv, lines = server
    raw_request(srv, b"GET /cdf/\x1b[2J\x07\\x HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
    raw_request(srv, b"G\x1b]0;T\x07 /cdf/x HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
    assert lines == ["GET /cdf/\\x1b[2J\\x07\\\\x 404 10", "G\\x1b]0;T\\x07 /cdf/x 405 45"]


@pytest.mark.parametrize("headers", [
    b"Content-Length: 38\r\n", b"Transfer-Encoding: chunked\r\n", b"Content-Length: 0\r\nContent-Length: 38\r\n",
    b"Content-Length: 38\r\nExpect: 100-continue\r\n",
])
@pytest.mark.parametrize("method", ["GET", "HEAD"])
def test_a_get_or_head_with_a_body_is_400_and_the_body_never_a_request(server, method, headers):
    """The body used to be left unread and parsed as the next request on the connection: behind a proxy
    that forwards it as one request's body, a request the proxy never saw (request smuggling)."""
    srv, lines = server
    smuggled = b"GET /cdf/manifest.json HTTP/1.1\r\n\r\n"
    with socket.create_connection(("127.0.0.1", srv.server_address[1]), timeout=5) as s:
        s.sendall(f"{method} /cdf/{PRO} HTTP/1.1\r\nHost: x\r\n".encode() + headers + b"\r\n" + smuggled)
        answer = b""
        while chunk := s.recv(65536):   # until the server closes the connection
            answer += chunk
    assert answer.startswith(b"HTTP/1.1 400 ") and b"Connection: close\r\n" in answer
    assert answer.count(b"HTTP/1.1 ") == 1, answer   # nothing answered to the smuggled request
    assert lines == [f"{method} /cdf/{PRO} 400 {0 if method == 'HEAD' else 26}"]


def test_a_get_with_an_empty_body_is_served(server):
    srv, _ = server
    assert request(srv, "GET", f"/cdf/{PRO}", {"Content-Length": "0"})[0] == 200


def test_a_client_hanging_up_is_one_log_line_not_a_traceback(server, capfd):
    import struct
    import time

    srv, lines = server
    with socket.create_connection(("127.0.0.1", srv.server_address[1]), timeout=5) as s:
        s.sendall(b"GET /cdf/" + PRO.encode() + b" HTTP/1.1\r\n")  # the headers never come
        time.sleep(0.2)  # the server is now reading them
        s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # close with a reset
    deadline = time.monotonic() + 5
    while not lines and time.monotonic() < deadline:
        time.sleep(0.02)
    assert len(lines) == 1 and "client hung up (ConnectionResetError)" in lines[0], lines
    assert "Traceback" not in capfd.readouterr().err
    assert request(srv, "GET", f"/cdf/{PRO}")[0] == 200   # still serving


def test_concurrent_requests_are_served(bundle):
    """16 clients at once are all served. They share 127.0.0.1, so the per-address cap (which would answer the
    9th of them 503 while 8 are open, as test_one_client_address_holds_at_most_max_per_client_slots shows) is
    raised to let them stand for 16 different clients."""
    results = []
    with serving(bundle, log=lambda _l: None, max_per_client=16) as srv:
        def fetch():
            results.append(request(srv, "GET", f"/cdf/{PRO}")[0])
        threads = [threading.Thread(target=fetch) for _ in range(16)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(20)
    assert results == [200] * 16


def test_explicit_prefix_and_root_prefix(bundle):
    with serving(bundle, prefix="/", log=lambda _l: None) as srv:
        assert request(srv, "GET", f"/{PRO}")[0] == 200
        assert request(srv, "GET", f"/cdf/{PRO}")[0] == 404
    assert prefix_from_manifest(bundle) == "/cdf/"
    assert prefix_from_manifest(bundle / "sub") == "/"


def test_missing_directory_and_busy_port_are_errors(tmp_path, bundle):
    for missing in (tmp_path / "missing", tmp_path / ("d" * 300)):  # the second: a name too long
        with pytest.raises(WirisError, match="not a directory"):
            make_server(missing, "127.0.0.1", 0)
    srv = make_server(bundle, "127.0.0.1", 0, log=lambda _l: None)
    try:
        with pytest.raises(WirisError, match="cannot listen") as err:
            make_server(bundle, "127.0.0.1", srv.server_address[1])
        assert "--port" in err.value.hint
    finally:
        srv.server_close()


@pytest.mark.parametrize("prefix,text", [("/../..", "segment '..'"), ("/a//b", "an empty segment (//)"),
                                         ("/my cdf", "segment 'my cdf'"), ("/cdf/./v1", "segment '.'")])
def test_a_prefix_no_request_can_match_is_refused(bundle, prefix, text):
    # it used to be served as given, at a URL path no client sends: every request answered 404
    with pytest.raises(WirisError, match=re.escape(f"URL path {text} cannot be requested")) as err:
        make_server(bundle, "127.0.0.1", 0, prefix=prefix)
    assert err.value.where == f"--prefix {prefix}"


def test_a_percent_encoded_prefix_is_served(bundle):
    with serving(bundle, prefix="/my%20cdf/v1", log=lambda _l: None) as srv:
        assert server_url(srv).endswith("/my%20cdf/v1/")
        assert request(srv, "GET", f"/my%20cdf/v1/{PRO}")[0] == 200


@pytest.mark.parametrize("host", ["nosuchhost.invalid", "192.0.2.1"])  # unresolvable; not this machine's
def test_a_host_that_cannot_be_bound_names_the_host_option(bundle, host):
    with pytest.raises(WirisError, match=f"cannot listen on {host}:0") as err:
        make_server(bundle, host, 0)
    assert err.value.hint.startswith("give --host an address of this machine")  # was: choose another --port


def _ipv6_loopback() -> bool:
    try:
        with socket.socket(socket.AF_INET6) as s:
            s.bind(("::1", 0))
        return True
    except OSError:
        return False


@pytest.mark.skipif(not _ipv6_loopback(), reason="no IPv6 loopback on this machine")
def test_serves_on_an_ipv6_address(bundle):
    # http.server listens on IPv4 only: --host ::1 used to fail with "Address family not supported"
    with serving(bundle, "::1", log=lambda _l: None) as srv:
        url = server_url(srv)
        assert url == f"http://[::1]:{srv.server_address[1]}/cdf/"
        conn = http.client.HTTPConnection("::1", srv.server_address[1], timeout=10)
        conn.request("GET", f"/cdf/{PRO}")
        assert conn.getresponse().status == 200
        conn.close()


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_cli_serve_runs_until_interrupted(bundle, signum):
    """The real command in a subprocess: it prints its URL, serves, and stops on Ctrl-C or SIGTERM."""
    with wiris_child("cdf", "serve", str(bundle), "--port", "0") as proc:
        first = proc.stderr.readline()
        assert first.startswith(f"serving {bundle} at http://127.0.0.1:") and "/cdf/" in first
        port = int(first.split("127.0.0.1:")[1].split("/")[0])
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        conn.request("GET", f"/cdf/{PRO}")
        assert conn.getresponse().status == 200
        conn.close()
        assert proc.stderr.readline().strip() == f"GET /cdf/{PRO} 200 {(bundle / PRO).stat().st_size}"
        assert "stopped" in stop(proc, signum)


def test_random_paths_never_leave_the_bundle(server, bundle):
    """Property: whatever path a client sends, the answer is 404/403, or 200 with a file of the bundle."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    srv, _ = server
    hosted = {p.read_bytes() for p in bundle.iterdir() if p.is_file() and not p.name.startswith(".")}
    secret = (bundle.parent / "secret.txt").read_bytes()
    pieces = st.sampled_from(["..", ".", "%2e", "%2E", "%2f", "%2F", "%5c", "/", "\\", "%00", "%25", "cdf",
                              "secret.txt", "manifest.json", PRO, "sub", "leak.xml", "alias.xml", "x"])

    @settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))
    @given(st.lists(pieces, min_size=1, max_size=8))
    def check(parts):
        path = "/" + "".join(parts)
        status, _, body = request(srv, "GET", path)
        assert status in (200, 403, 404), path
        if status == 200:
            assert body in hosted and body != secret, path

    check()


def test_every_manifest_uri_is_served_and_validates_over_http(tmp_path):
    """End to end: build with the server's own base URL, then fetch every URI of the manifest with the
    validator's HTTP client (strict profile) — what a ground station would download is valid."""
    validation = pytest.importorskip("cdf.validation")
    out = tmp_path / "cdf"
    out.mkdir()
    with serving(out, prefix="/cdf", log=lambda _l: None) as srv:
        result = build_bundle(out, all_models=True, base_url=server_url(srv).rstrip("/"))
        assert result.entries
        for entry in result.entries:
            report = validation.validate_source(entry.uri, "strict")
            assert report.valid and report.parameters > 0, entry.uri
