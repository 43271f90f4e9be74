"""Safe loading of untrusted camera definition files: files, `.xml.xz`, and http(s) URLs.

Camera definitions come from cameras and web servers nobody here controls, so every step has a limit:
- size: 4 MiB on the wire and 4 MiB after xz inflation (MAVProxy's MAX_DEFINITION_SIZE; the largest
  public CDF, the Yuneec E90, is 64 KB);
- xz: detected by its magic number, not by the file name (a `.xml` URL may serve xz and vice versa),
  inflated with a memory limit and a bounded output, and must be one complete stream;
- XML: lxml with no DTD loading, no entity expansion, no network, no huge-tree mode; any DTD is
  reported (MAVProxy refuses them); nesting deeper than MAX_DEPTH or more than MAX_ELEMENTS nodes is
  refused (real files nest 8 deep and have under 900 elements);
- HTTP: a total timeout, redirects only to http/https (a redirect to file:// would read local files).

Content problems (too big, broken xz, not XML) become `LoadProblem`s that the validator reports as
findings; a source that cannot be read at all (no file, HTTP error, timeout, refused redirect) raises
CdfError.
"""

from __future__ import annotations

import functools
import http.client
import lzma
import re
import socket
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from dataclasses import dataclass
from pathlib import Path

from cdf.errors import CdfError
from cdf.userfile import UserFile, read_user_file

MAX_BYTES = 4 * 1024 * 1024
MAX_INFLATED_BYTES = 4 * 1024 * 1024
# liblzma memory for the decoder: xz presets up to -9 need 65 MiB for the dictionary.
XZ_MEMLIMIT = 96 * 1024 * 1024
MAX_DEPTH = 64
# The largest public file (historic Yuneec E90) has 893 elements; xmlschema needs ~0.4 ms per element.
MAX_ELEMENTS = 5000
HTTP_TIMEOUT_S = 15.0
XZ_MAGIC = b"\xfd7zXZ\x00"


@dataclass(frozen=True)
class LoadProblem:
    """A content problem found while loading; `rule` is a rule id of cdf.validation.rules."""

    rule: str
    message: str
    line: int | None = None


@dataclass(frozen=True)
class Loaded:
    """Bytes of one definition after the size check and xz inflation."""

    name: str
    raw_size: int
    data: bytes | None  # None when a problem stops loading
    compressed: bool
    problems: tuple[LoadProblem, ...] = ()


def inflate(raw: bytes, name: str) -> Loaded:
    """Check the size and inflate xz (by magic number) with bounded memory and output."""
    if len(raw) > MAX_BYTES:
        return Loaded(name, len(raw), None, False, (LoadProblem(
            "CDF002", f"file is {len(raw)} bytes; the limit is {MAX_BYTES} (MAVProxy's 4 MiB cap)"),))
    if not raw.startswith(XZ_MAGIC):
        return Loaded(name, len(raw), raw, False)
    dec = lzma.LZMADecompressor(format=lzma.FORMAT_XZ, memlimit=XZ_MEMLIMIT)
    try:
        out = dec.decompress(raw, max_length=MAX_INFLATED_BYTES + 1)
    except lzma.LZMAError as err:
        return Loaded(name, len(raw), None, True, (LoadProblem("CDF003", f"broken xz stream: {err}"),))
    if len(out) > MAX_INFLATED_BYTES:
        return Loaded(name, len(raw), None, True, (LoadProblem(
            "CDF002", f"xz content inflates beyond {MAX_INFLATED_BYTES} bytes"),))
    if not dec.eof:
        return Loaded(name, len(raw), None, True, (LoadProblem(
            "CDF003", "xz stream is truncated (no end-of-stream marker)"),))
    if dec.unused_data.strip(b"\0"):
        # GCS inflaters (MAVSDK InflateLZMA, QGC QGCCompression) read one stream; more is ignored or fails.
        return Loaded(name, len(raw), out, True, (LoadProblem(
            "CDF003", "data after the end of the xz stream (concatenated streams are not read by GCSs)"),))
    return Loaded(name, len(raw), out, True)


# A local definition file: more than MAX_BYTES is read as MAX_BYTES + 1 and reported as finding CDF002.
DEFINITION_FILE = UserFile("camera definition file", MAX_BYTES, CdfError, size_hint=None,
                           hint="name the .xml or .xml.xz file itself (a bundle lists its files in "
                                "manifest.json) and check the path")


def read_file(path: str | Path) -> bytes:
    """At most MAX_BYTES + 1 bytes of a local file (the size check then reports the excess)."""
    return read_user_file(path, DEFINITION_FILE)


class _HttpOnlyRedirects(urllib.request.HTTPRedirectHandler):
    max_redirections = 5

    def redirect_request(self, req, fp, code, msg, headers, newurl):
        scheme = urllib.parse.urlsplit(newurl).scheme.lower()
        if scheme not in ("http", "https"):
            raise CdfError(f"redirect to a {scheme or 'relative'}:// URL refused ({newurl})",
                           where=req.full_url, hint="camera definitions may only redirect to http(s) URLs")
        return super().redirect_request(req, fp, code, msg, headers, newurl)


def fetch_url(url: str, *, timeout_s: float = HTTP_TIMEOUT_S) -> bytes:
    """GET an http(s) URL: at most MAX_BYTES + 1 bytes, http(s)-only redirects, each socket operation
    bounded by timeout_s and the whole download by 2 * timeout_s + 1 s.

    The download runs in a daemon thread the caller stops waiting for at the deadline: a server can
    trickle header lines slowly enough that no single socket operation times out.
    """
    try:
        scheme = urllib.parse.urlsplit(url).scheme.lower()
    except ValueError as err:  # "Invalid IPv6 URL"
        raise CdfError(f"malformed URL: {err}", where=url, hint="check the host part of the URL") from None
    if scheme not in ("http", "https"):
        raise CdfError(f"unsupported URL scheme {scheme!r}", where=url,
                       hint="use http:// or https:// (mftp:// needs a MAVLink link: download it first)")
    total_s = 2 * timeout_s + 1.0
    outcome: list = []
    worker = threading.Thread(target=lambda: outcome.append(_fetch_outcome(url, timeout_s, total_s)),
                              name="cdf-fetch", daemon=True)
    worker.start()
    worker.join(total_s)
    if not outcome:
        raise CdfError(f"no complete answer within {total_s:g} s (server sends too slowly)", where=url,
                       hint="is the server overloaded or hostile?")
    result = outcome[0]
    if isinstance(result, CdfError):
        raise result
    return result


def _fetch_outcome(url: str, timeout_s: float, total_s: float) -> bytes | CdfError:
    try:
        return _fetch(url, timeout_s, time.monotonic() + total_s - 1.0)
    except CdfError as err:
        return err


def _fetch(url: str, timeout_s: float, deadline: float) -> bytes:
    opener = urllib.request.build_opener(_HttpOnlyRedirects())
    req = urllib.request.Request(url, headers={"User-Agent": "wiris-tools-cdf-validate"})
    try:
        with opener.open(req, timeout=timeout_s) as resp:
            return _read_bounded(resp, url, deadline)
    except CdfError:
        raise
    except urllib.error.HTTPError as err:
        raise CdfError(f"HTTP {err.code} {err.reason}", where=url,
                       hint="a GCS would cache this error page as the definition; serve the XML with status 200") from None
    except (socket.timeout, TimeoutError):
        raise CdfError(f"no answer within {timeout_s:g} s", where=url, hint="is the server up and reachable?") from None
    except urllib.error.URLError as err:
        reason = err.reason
        if isinstance(reason, (socket.timeout, TimeoutError)):
            raise CdfError(f"no answer within {timeout_s:g} s", where=url,
                           hint="is the server up and reachable?") from None
        raise CdfError(f"cannot fetch: {reason}", where=url, hint="check the URL and the network") from None
    except http.client.HTTPException as err:  # malformed status line, too many headers, ...
        if isinstance(err, http.client.InvalidURL):  # http.client refuses the URL itself: nothing was asked
            raise CdfError(f"not a valid URL ({err})", where=url,
                           hint="fix the URL (a space as %20, the port in digits)") from None
        raise CdfError(f"broken HTTP answer: {type(err).__name__}: {err}", where=url,
                       hint="is it an HTTP server? check the URL's host and port") from None
    except (OSError, ValueError) as err:
        raise CdfError(f"cannot fetch: {err}", where=url, hint="check the URL and the network") from None


def _read_bounded(resp, url: str, deadline: float) -> bytes:
    # The socket timeout bounds each read; the deadline bounds a server that trickles bytes forever.
    chunks, total = [], 0
    while total <= MAX_BYTES:
        if time.monotonic() > deadline:
            raise CdfError("download took too long (server sends too slowly)", where=url,
                           hint="is the server overloaded or hostile?")
        # read1: at most one recv, so a trickling server cannot keep us inside one read() call
        chunk = resp.read1(min(65536, MAX_BYTES + 1 - total))
        if not chunk:
            break
        chunks.append(chunk)
        total += len(chunk)
    return b"".join(chunks)


def is_url(source: str) -> bool:
    # the scheme as urlsplit would find it, without urlsplit's ValueError for a broken host ("http://[::1")
    scheme, sep, _rest = source.partition("://")
    return bool(sep) and scheme.lower() in ("http", "https", "file", "ftp", "mftp", "mavlinkftp")


def read_source(source: str | Path, *, timeout_s: float = HTTP_TIMEOUT_S) -> bytes:
    """Bytes of a path or an http(s) URL (bounded); raises CdfError when the source cannot be read."""
    s = str(source)
    if is_url(s):
        return fetch_url(s, timeout_s=timeout_s)
    return read_file(s)


def parse_xml(data: bytes, name: str):
    """Parse with lxml, hardened. Returns (root element or None, problems)."""
    from lxml import etree

    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False,
                             dtd_validation=False, remove_comments=False, collect_ids=False)
    problems: list[LoadProblem] = []
    try:
        root = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as err:
        msg = str(err.msg or err)
        line = err.lineno if isinstance(err.lineno, int) and err.lineno > 0 else None
        if "depth" in msg.lower():
            return None, (LoadProblem("CDF006", f"nesting too deep ({msg}); real definitions nest 8 deep",
                                      line),)
        if "entity" in msg.lower() and b"<!DOCTYPE" in data[:4096]:
            return None, (LoadProblem("CDF005", f"DTD entities are not allowed ({msg})", line),)
        if _declares_other_encoding(data):
            return _parse_as_utf8(data, name, msg, line)
        return None, (LoadProblem("CDF004", f"not well-formed XML: {msg}", line),)
    except ValueError as err:  # e.g. a str with an encoding declaration; bytes never get here
        return None, (LoadProblem("CDF004", f"not parseable: {err}"),)
    tree = root.getroottree()
    if tree.docinfo.doctype or tree.docinfo.internalDTD is not None:
        problems.append(LoadProblem("CDF005", "document has a DTD (<!DOCTYPE>); it was not loaded and no "
                                              "entity was expanded", 1))
    if too_deep(root):
        return None, (*problems, TOO_DEEP)
    if int(_shape_xpaths()[0](root)) > MAX_ELEMENTS:
        return None, (*problems, LoadProblem("CDF006", f"more than {MAX_ELEMENTS} elements; real definitions have "
                                                       "under 900 (schema validation time grows with the count)"))
    return root, tuple(problems)


_DECLARED_ENCODING = re.compile(rb"^(?:\xef\xbb\xbf)?\s*<\?xml[^>]*encoding\s*=\s*[\"']([A-Za-z0-9._-]+)[\"'][^>]*\?>")


def _declares_other_encoding(data: bytes) -> bool:
    """8-bit bytes (not UTF-16/32) whose XML declaration names an encoding other than UTF-8."""
    m = _DECLARED_ENCODING.match(data[:300])
    return m is not None and m.group(1).upper().replace(b"_", b"-") not in (b"UTF-8", b"UTF8")


def _parse_as_utf8(data: bytes, name: str, msg: str, line: int | None):
    """A file whose declaration names an encoding its bytes are not in (UTF-8 bytes saying UTF-16) fails in
    lxml, expat and QDom; MAVSDK's tinyxml2 ignores declarations and reads UTF-8. When the bytes parse as
    UTF-8 the rules run on the file as MAVSDK sees it, with CDF009 for the declaration."""
    m = _DECLARED_ENCODING.match(data[:300])
    assert m is not None
    as_utf8 = data[:m.start(1)] + b"UTF-8" + data[m.end(1):]
    if _DECLARED_ENCODING.match(as_utf8[:300]) is None:
        return None, (LoadProblem("CDF004", f"not well-formed XML: {msg}", line),)
    root, problems = parse_xml(as_utf8, name)
    if root is None:
        return None, (LoadProblem("CDF004", f"not well-formed XML: {msg}", line),)
    wrong = LoadProblem("CDF009", f"the XML declaration names {m.group(1).decode()}, but the bytes are not in it "
                                  f"({msg}); declare encoding=\"UTF-8\"", 1)
    return root, (wrong, *problems)


TOO_DEEP = LoadProblem("CDF006", f"elements nest more than {MAX_DEPTH} deep")


def too_deep(root) -> bool:
    """Whether elements nest more than MAX_DEPTH deep."""
    return _shape_xpaths()[1](root)


@functools.lru_cache(maxsize=1)
def _shape_xpaths():
    """The element count and the depth test, compiled once per process (compiling costs more than
    evaluating them on a real file). An element MAX_DEPTH + 1 levels down exists iff the nesting is too deep."""
    from lxml import etree

    return etree.XPath("count(//*)"), etree.XPath("boolean(/" + "*/" * MAX_DEPTH + "*)")
