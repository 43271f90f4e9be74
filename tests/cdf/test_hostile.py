"""Hostile camera definitions: each gets a clear finding or CdfError, with bounded memory, no expansion,
no file or network access. HTTP cases use a real http.server on 127.0.0.1 (port 0)."""

from __future__ import annotations

import http.server
import lzma
import socket
import struct
import threading
import time
import tracemalloc
from contextlib import contextmanager

import pytest
from click.testing import CliRunner

from cdf.errors import CdfError
from cdf.validate import validate_bytes, validate_source
from cdf.xmlsafe import MAX_BYTES
from wiris_tools.cli import cli

GOOD = (b'<?xml version="1.0" encoding="UTF-8"?>\n<mavlinkcamera>\n<definition version="1"><model>M</model>'
        b'<vendor>V</vendor></definition>\n<parameters>\n<parameter name="CAM_MODE" type="uint32" default="0" '
        b'control="0"><description>Mode</description><options><option name="Photo" value="0"/>'
        b'<option name="Video" value="1"/></options></parameter>\n</parameters>\n</mavlinkcamera>\n')

LAUGHS = b"""<?xml version="1.0" encoding="UTF-8"?>
<!DOCTYPE mavlinkcamera [
 <!ENTITY lol "lol">
 <!ENTITY lol1 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
 <!ENTITY lol2 "&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;">
 <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
 <!ENTITY lol4 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
 <!ENTITY lol5 "&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;">
 <!ENTITY lol6 "&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;">
 <!ENTITY lol7 "&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;">
 <!ENTITY lol8 "&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;">
 <!ENTITY lol9 "&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;">
]>
<mavlinkcamera><definition version="1"><model>&lol9;</model><vendor>V</vendor></definition>
<parameters><parameter name="A" type="uint8" default="0" min="0" max="1"><description>&lol9;</description>
</parameter></parameters></mavlinkcamera>
"""


@contextmanager
def bounded_memory(limit_mb: float = 64):
    tracemalloc.start()
    try:
        yield
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < limit_mb * 1024 * 1024, f"peak {peak / 1e6:.1f} MB"


def rules(report, severity=None):
    return report.rules(severity)


def test_billion_laughs_is_not_expanded():
    with bounded_memory():
        for profile in ("qgc", "mavsdk", "strict"):
            r = validate_bytes(LAUGHS, "laughs.xml", profile)
            assert "CDF005" in rules(r)
    r = validate_bytes(LAUGHS, "laughs.xml", "strict")
    assert not r.valid and "CDF005" in rules(r, "error")
    assert all("lollol" not in f.message for f in r.findings)


def test_external_entity_reads_no_file(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("TOP-SECRET-CONTENT")
    data = (f'<?xml version="1.0"?><!DOCTYPE m [<!ENTITY x SYSTEM "file://{secret}">]>'
            '<mavlinkcamera><definition version="1"><model>&x;</model><vendor>V</vendor></definition>'
            '<parameters/></mavlinkcamera>').encode()
    r = validate_bytes(data, "xxe.xml")
    assert "CDF005" in rules(r, "error")
    assert all("TOP-SECRET" not in f.message for f in r.findings)


class _Handler(http.server.BaseHTTPRequestHandler):
    routes: dict = {}
    hits: list = []

    def do_GET(self):  # noqa: N802 (http.server API)
        self.hits.append(self.path)
        status, headers, body = self.routes.get(self.path, (404, {}, b"not found"))
        self.send_response(status)
        for k, v in headers.items():
            self.send_header(k, v)
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *a):
        pass


@pytest.fixture
def server():
    handler = type("H", (_Handler,), {"routes": {}, "hits": []})
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    base = f"http://127.0.0.1:{httpd.server_address[1]}"
    yield base, handler
    httpd.shutdown()
    httpd.server_close()


def test_external_dtd_is_not_fetched(server):
    base, handler = server
    handler.routes["/evil.dtd"] = (200, {}, b'<!ENTITY x "EXPANDED">')
    data = (f'<?xml version="1.0"?><!DOCTYPE mavlinkcamera SYSTEM "{base}/evil.dtd">').encode() + GOOD.split(b"?>", 1)[1]
    r = validate_bytes(data, "dtd.xml")
    assert "CDF005" in rules(r, "error")
    assert handler.hits == []


def test_fifty_megabyte_file_is_refused_without_reading_it(tmp_path):
    big = tmp_path / "big.xml"
    with big.open("wb") as fh:
        fh.write(GOOD[:-len(b"</mavlinkcamera>\n")])
        fh.write(b"<!--" + b"x" * (50 * 1024 * 1024) + b"-->")
        fh.write(b"</mavlinkcamera>\n")
    with bounded_memory(limit_mb=3 * MAX_BYTES / 1024 / 1024):
        r = validate_source(big)
    assert [f.rule for f in r.findings] == ["CDF002"] and not r.valid


def test_deep_nesting_is_refused():
    deep = b"<a>" * 100_000 + b"</a>" * 100_000
    data = b'<?xml version="1.0" encoding="UTF-8"?><mavlinkcamera>' + deep + b"</mavlinkcamera>"
    with bounded_memory():
        r = validate_bytes(data, "deep.xml")
    assert [f.rule for f in r.findings] == ["CDF006"]
    moderately = b"<a>" * 100 + b"</a>" * 100  # below libxml2's own limit, above ours
    r = validate_bytes(GOOD.replace(b"</parameters>", b"</parameters>" + moderately), "deep2.xml")
    assert [f.rule for f in r.findings] == ["CDF006"]
    # known elements only (the depth test is left out when libxml2's vocabulary proof settles a file)
    known = b"<option><exclusions>" * 40 + b"</exclusions></option>" * 40
    r = validate_bytes(GOOD.replace(b"<options>", b"<options>" + known), "deep3.xml")
    assert [f.rule for f in r.findings] == ["CDF006"]


@pytest.mark.parametrize("codec,declared", [("utf-8", "UTF-8"), ("utf-16-le", "UTF-16LE"),
                                            ("utf-16-be", "UTF-16BE"), ("utf-16", "UTF-16"),
                                            ("utf-32-le", "UTF-32LE")])
def test_element_cap_counts_exactly_in_any_encoding(codec, declared):
    # the cap is counted from the tree unless the bytes alone show it holds (xmlsafe._may_exceed): the
    # smallest elements, in several encodings, one element under, at and over MAX_ELEMENTS
    from cdf.xmlsafe import MAX_ELEMENTS

    def doc(n: int) -> bytes:  # the root, <parameters> and n - 2 <a/>
        return (f'<?xml version="1.0" encoding="{declared}"?><mavlinkcamera><parameters>{"<a/>" * (n - 2)}'
                "</parameters></mavlinkcamera>").encode(codec)

    for n, capped in ((MAX_ELEMENTS - 1, False), (MAX_ELEMENTS, False), (MAX_ELEMENTS + 1, True)):
        rules = [f.rule for f in validate_bytes(doc(n), f"{declared}-{n}.xml", "qgc").findings]
        assert "CDF004" not in rules and ("CDF006" in rules) == capped, (declared, n, rules)


def test_invalid_utf8_is_not_well_formed():
    data = GOOD.replace(b"Mode", b"Mo\xff\xfede")
    r = validate_bytes(data, "bad-utf8.xml", "qgc")
    assert [f.rule for f in r.findings] == ["CDF004"] and r.findings[0].line == 5
    assert "not well-formed" in r.findings[0].message


def test_truncated_xz():
    xz = lzma.compress(GOOD, format=lzma.FORMAT_XZ)
    r = validate_bytes(xz[: len(xz) // 2], "cut.xml.xz")
    assert [f.rule for f in r.findings] == ["CDF003"] and "truncated" in r.findings[0].message


def test_corrupt_xz():
    xz = bytearray(lzma.compress(GOOD, format=lzma.FORMAT_XZ))
    xz[30] ^= 0xFF
    r = validate_bytes(bytes(xz), "corrupt.xml.xz")
    assert [f.rule for f in r.findings] == ["CDF003"]


def test_xz_bomb_is_capped():
    bomb = lzma.compress(b"<a>" + b" " * (200 * 1024 * 1024) + b"</a>", format=lzma.FORMAT_XZ, preset=1)
    assert len(bomb) < MAX_BYTES
    with bounded_memory(limit_mb=32):
        r = validate_bytes(bomb, "bomb.xml.xz")
    assert [f.rule for f in r.findings] == ["CDF002"]


def test_concatenated_xz_streams():
    xz = lzma.compress(GOOD, format=lzma.FORMAT_XZ)
    r = validate_bytes(xz + xz, "two.xml.xz")
    assert "CDF003" in rules(r, "error")


def test_redirect_to_file_url_is_refused(server, tmp_path):
    base, handler = server
    target = tmp_path / "local.xml"
    target.write_bytes(GOOD)
    handler.routes["/cdf.xml"] = (302, {"Location": f"file://{target}"}, b"")
    with pytest.raises(CdfError) as err:
        validate_source(f"{base}/cdf.xml")
    assert "redirect" in str(err.value) and "file" in str(err.value)


def test_redirect_to_other_schemes_is_refused(server):
    base, handler = server
    handler.routes["/a.xml"] = (301, {"Location": "ftp://127.0.0.1/x.xml"}, b"")
    with pytest.raises(CdfError, match="redirect"):
        validate_source(f"{base}/a.xml")


def test_redirect_to_a_malformed_url_is_refused(server):
    base, handler = server
    handler.routes["/bad.xml"] = (302, {"Location": "http://[::1/x.xml"}, b"")
    with pytest.raises(CdfError, match="Invalid IPv6 URL"):
        validate_source(f"{base}/bad.xml")


@pytest.mark.parametrize("url", ["http://[::1", "https://[::1/cdf.xml", "http://[zz]/cdf.xml"])
def test_a_malformed_url_is_a_cdf_error(url):
    with pytest.raises(CdfError, match="malformed URL"):
        validate_source(url)


def test_redirect_to_http_is_followed(server):
    base, handler = server
    handler.routes["/old.xml"] = (302, {"Location": f"{base}/new.xml"}, b"")
    handler.routes["/new.xml"] = (200, {}, GOOD)
    r = validate_source(f"{base}/old.xml")
    assert r.valid and r.parameters == 1 and handler.hits == ["/old.xml", "/new.xml"]


def test_http_error_is_a_cdf_error(server):
    base, _ = server
    with pytest.raises(CdfError, match="HTTP 404"):
        validate_source(f"{base}/missing.xml")


def test_http_body_over_the_cap(server):
    base, handler = server
    handler.routes["/big.xml"] = (200, {}, GOOD + b"<!--" + b"x" * (MAX_BYTES + 10) + b"-->")
    r = validate_source(f"{base}/big.xml")
    assert [f.rule for f in r.findings] == ["CDF002"]


def test_http_xz_over_http_is_inflated(server):
    base, handler = server
    handler.routes["/c.xml.xz"] = (200, {}, lzma.compress(GOOD, format=lzma.FORMAT_XZ))
    assert validate_source(f"{base}/c.xml.xz").valid


def test_server_that_never_answers_times_out():
    silent = socket.socket()
    silent.bind(("127.0.0.1", 0))
    silent.listen(1)  # the kernel completes the handshake; nobody ever reads or writes
    try:
        url = f"http://127.0.0.1:{silent.getsockname()[1]}/cdf.xml"
        with pytest.raises(CdfError, match="no answer within 0.5 s"):
            validate_source(url, timeout_s=0.5)
        r = CliRunner().invoke(cli, ["cdf", "validate", "--timeout", "0.5", url])
        assert r.exit_code == 1 and "CDF001" in r.output and "Traceback" not in r.output
    finally:
        silent.close()


def test_unsupported_scheme_and_missing_file(tmp_path):
    with pytest.raises(CdfError, match="scheme") as err:
        validate_source("mftp://camera.xml")
    assert "http" in err.value.hint
    with pytest.raises(CdfError, match="no such file") as err:
        validate_source(tmp_path / "nope.xml")
    assert err.value.hint
    with pytest.raises(CdfError, match="directory") as err:
        validate_source(tmp_path)
    assert err.value.where == str(tmp_path) and ".xml" in err.value.hint
    (tmp_path / "a.xml").write_bytes(GOOD)
    with pytest.raises(CdfError, match="cannot read") as err:   # a path through a file
        validate_source(tmp_path / "a.xml" / "b.xml")
    assert err.value.hint


@pytest.mark.parametrize("url", ["http://127.0.0.1:abc/cdf.xml", "http://127.0.0.1:1/a b.xml"])
def test_a_url_http_client_refuses_says_to_fix_the_url(url):
    with pytest.raises(CdfError, match="not a valid URL") as err:
        validate_source(url, timeout_s=2)
    assert err.value.where == url and "fix the URL" in err.value.hint


def test_a_connection_reset_while_downloading_is_a_cdf_error_with_a_hint():
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)

    def reset():
        conn, _ = listener.accept()
        conn.recv(65536)
        conn.sendall(b"HTTP/1.0 200 OK\r\nContent-Type: application/xml\r\n\r\n<mavlinkcamera>")
        time.sleep(0.2)   # the client is reading the body by now
        conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))   # close with RST
        conn.close()

    t = threading.Thread(target=reset, daemon=True)
    t.start()
    url = f"http://127.0.0.1:{listener.getsockname()[1]}/cdf.xml"
    try:
        with pytest.raises(CdfError, match="cannot fetch") as err:
            validate_source(url, timeout_s=2)
        assert err.value.where == url and err.value.hint
    finally:
        listener.close()
        t.join(5)


def test_empty_and_binary_input():
    for data in (b"", b"\x00\x01\x02garbage", b"<?xml version='1.0'?>"):
        r = validate_bytes(data, "junk")
        assert not r.valid and [f.rule for f in r.findings] == ["CDF004"]


def test_server_that_trickles_forever_is_cut_off():
    # each read gets a byte before the socket timeout, so only the overall deadline stops it
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    stop = threading.Event()

    def trickle():
        conn, _ = listener.accept()
        with conn:
            conn.sendall(b"HTTP/1.0 200 OK\r\nContent-Type: application/xml\r\n\r\n<mavlinkcamera>")
            while not stop.wait(0.1):
                try:
                    conn.sendall(b" ")
                except OSError:
                    return

    t = threading.Thread(target=trickle, daemon=True)
    t.start()
    try:
        with pytest.raises(CdfError, match="too slowly"):
            validate_source(f"http://127.0.0.1:{listener.getsockname()[1]}/cdf.xml", timeout_s=0.5)
    finally:
        stop.set()
        listener.close()
        t.join(5)


@pytest.mark.parametrize("answer", [b"HTTP/1.0 200 OK\r\n", b"garbage that is not HTTP\r\n\r\n"])
def test_server_with_endless_headers_or_garbage(answer):
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    stop = threading.Event()

    def serve():
        conn, _ = listener.accept()
        with conn:
            try:
                conn.sendall(answer)
                i = 0
                while not stop.wait(0.05):  # one header line at a time, each before the socket timeout
                    conn.sendall(f"X-Slow-{i}: y\r\n".encode())
                    i += 1
            except OSError:
                return

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    try:
        with pytest.raises(CdfError) as err:
            validate_source(f"http://127.0.0.1:{listener.getsockname()[1]}/cdf.xml", timeout_s=0.5)
        assert "HTTP" in str(err.value) or "too slowly" in str(err.value)
        assert err.value.hint
    finally:
        stop.set()
        listener.close()
        t.join(5)
