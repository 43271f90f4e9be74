"""A small read-only HTTP server for a camera definition bundle (`wiris cdf serve DIR`).

QGroundControl and MAVSDK fetch the file named in CAMERA_INFORMATION.cam_definition_uri with a plain
HTTP GET (QGC accepts only status 200; MAVSDK saves whatever body it gets, a 404 page included, and
caches it — reference mavsdk-as-test-peer.md B), so the server answers exactly: 200 with the file, 404
for anything it does not host, never a directory listing.

Safety: only GET and HEAD (405 otherwise); the request path is percent-decoded once and every segment
checked (no `..`, `.`, empty, hidden or backslash segments, no NUL); the resolved real path must stay
inside the served directory, so a symlink pointing outside answers 403. Files are read, never written.
A request target over MAX_TARGET_CHARS, or with a segment over NAME_MAX_BYTES (no file name is longer),
is answered 414; a GET or HEAD carrying a body is answered 400 and the connection closed.

Every connection holds a thread and a slot, so none may hold them for ever: a connection that sends or reads
nothing for IDLE_TIMEOUT_S is closed, and so is one whose request line and headers have not all arrived
REQUEST_TIMEOUT_S after their first byte (a client trickling a header line now and then resets a per-read
timeout for ever). At most MAX_CONNECTIONS are served at once and MAX_PER_CLIENT from one client address,
so that a few slow clients cannot take every slot; one more is answered 503 with Retry-After by the
accepting thread and closed, so a flood of connections cannot start threads without bound (a GCS opens one
or two). Behind a reverse proxy every client has the proxy's address: raise max_per_client there.

Log lines write the method and path with control characters escaped (as repr() does) and cut to
LOG_FIELD_CHARS, so a request cannot write escape sequences or fake lines to the operator's terminal.

Caching: ETag is the sha256 of the content (the manifest's value for definitions), Last-Modified the
file's mtime; a matching If-None-Match (or, without it, an If-Modified-Since not older than the file)
answers 304. Versioned definition files never change (cdf.bundle refuses to), so they are cacheable for
a year; manifest.json must be revalidated on every use.
"""

from __future__ import annotations

import email.utils
import errno
import hashlib
import http.server
import io
import json
import os
import re
import socket
import sys
import threading
import time
import urllib.parse
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NamedTuple

from cdf.paths import require_directory
from wiris_tools.errors import LinkError

CONTENT_TYPES = {".xml": "application/xml", ".xz": "application/x-xz", ".json": "application/json"}
IMMUTABLE = re.compile(r"_v\d+\.xml(\.xz)?$")
MAX_FILE_BYTES = 16 * 1024 * 1024   # a bundle holds 30 KB definitions; anything bigger is not ours to serve
ALLOWED = "GET, HEAD"
IDLE_TIMEOUT_S = 30.0   # a GCS fetches a definition in one go; keep-alive connections idle longer are closed
REQUEST_TIMEOUT_S = 10.0  # a request line and its headers, from their first byte (a GCS sends them at once)
MAX_CONNECTIONS = 64    # connections served at once (a thread each); more are refused with 503
MAX_PER_CLIENT = 8      # of those, from one client address
MAX_TARGET_CHARS = 2048  # a request target; the bundle's longest is under 100
NAME_MAX_BYTES = 255    # a path segment, decoded (Linux's NAME_MAX: open() fails on longer names)
LOG_FIELD_CHARS = 200   # of a logged method or path
REFUSE_TIMEOUT_S = 0.2  # the accepting thread spends at most about this on one refusal


@dataclass(frozen=True)
class ServeConfig:
    root: Path                       # real path of the served directory
    prefix: str = "/"                # URL path the directory appears under, e.g. "/cdf/"
    log: Callable[[str], None] = lambda line: print(line, file=sys.stderr, flush=True)


def prefix_from_manifest(directory: Path) -> str:
    """The URL path of the bundle's http(s) URIs (e.g. "/cdf/" for http://host:8000/cdf/x.xml), so the
    server answers at the URIs the manifest announces; "/" when there is none, they disagree, or the path
    cannot be matched as written."""
    try:
        rows = json.loads((directory / "manifest.json").read_text(encoding="utf-8"))["models"]
        paths = {urllib.parse.urlsplit(r["uri"]).path.rsplit("/", 1)[0] + "/"
                 for r in rows if str(r["uri"]).lower().startswith(("http://", "https://"))}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return "/"
    if len(paths) != 1:
        return "/"
    path = paths.pop()
    return path if _bad_segment(path) is None else "/"


# a path segment as a client sends it (RFC 3986 pchar): requests are matched before percent-decoding
_SEGMENT = re.compile(r"(?:[A-Za-z0-9._~!$&'()*+,;=:@-]|%[0-9A-Fa-f]{2})+")


def _bad_segment(prefix: str) -> str | None:
    """The first segment of a URL path that no request can match literally, or None."""
    inner = prefix.strip("/")
    for seg in inner.split("/") if inner else ():
        if seg in (".", "..") or not _SEGMENT.fullmatch(seg):
            return seg
    return None


def _normal_prefix(prefix: str) -> str:
    bad = _bad_segment(prefix)
    if bad is not None:
        what = f"segment {bad[:40]!r}" if bad else "an empty segment (//)"
        raise LinkError(f"URL path {what} cannot be requested as written (clients drop . and .. segments "
                        "and percent-encode other characters)", where=f"--prefix {prefix[:60]}",
                        hint="use plain segments such as /cdf: letters, digits and - _ . ~")
    p = "/" + prefix.strip("/")
    return p if p == "/" else p + "/"


def _loggable(text: str, limit: int = LOG_FIELD_CHARS) -> str:
    """`text` cut to `limit` characters, control characters (and backslashes) escaped as repr() writes them."""
    cut = text if len(text) <= limit else text[:limit] + "…"
    return "".join(c if c.isprintable() and c != "\\" else repr(c)[1:-1] for c in cut)


def _linger(sock: socket.socket, seconds: float) -> None:
    """End the answer (FIN) and read what the client still sends, for at most `seconds`, before the socket is
    closed: closing it with unread data resets the connection, and the client could lose the answer."""
    try:
        sock.settimeout(seconds)
        sock.shutdown(socket.SHUT_WR)
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline and sock.recv(65536):
            pass
    except OSError:
        pass


class _RequestReader(io.RawIOBase):
    """A connection's reads: each waits at most `idle_timeout_s`, and those of one request's line and headers
    together at most `request_timeout_s` from the first byte read of it, then TimeoutError (http.server closes
    the connection). A per-read timeout alone is reset by every byte: a client sending a header line every
    few seconds would hold its thread and slot for as long as it likes."""

    def __init__(self, sock: socket.socket, idle_timeout_s: float, request_timeout_s: float) -> None:
        super().__init__()
        self._sock, self._idle_s, self._request_s = sock, idle_timeout_s, request_timeout_s
        self._reading_request = False
        self._deadline: float | None = None   # set by the request's first byte

    def readable(self) -> bool:
        return True

    def start_request(self) -> None:
        self._reading_request, self._deadline = True, None

    def end_request(self) -> None:
        """The request is read: answers are written under the idle timeout."""
        self._reading_request, self._deadline = False, None
        self._sock.settimeout(self._idle_s)

    def readinto(self, buffer) -> int:
        timeout = self._idle_s
        if self._deadline is not None:
            timeout = self._deadline - time.monotonic()
            if timeout <= 0:
                raise TimeoutError(f"request not complete {self._request_s:g} s after its first byte")
            timeout = min(timeout, self._idle_s)
        self._sock.settimeout(timeout)
        n = self._sock.recv_into(buffer)
        if n and self._reading_request and self._deadline is None:
            self._deadline = time.monotonic() + self._request_s
        return n


class BundleHandler(http.server.BaseHTTPRequestHandler):
    server_version = "wiris-cdf-serve"
    sys_version = ""
    protocol_version = "HTTP/1.1"
    config: ServeConfig   # set per server by make_server (a subclass per server, no shared state)
    request_timeout_s: float = REQUEST_TIMEOUT_S   # likewise (`timeout`, the idle timeout, too)

    # ------------------------------------------------------------------ plumbing
    def version_string(self) -> str:
        return self.server_version   # no Python version in the Server header

    def log_message(self, format: str, *args) -> None:  # noqa: A002 (http.server API)
        pass  # one line per request is written by _log instead

    def _log(self, status: int, nbytes: int) -> None:
        # path and command are unset when the request line did not parse
        method, path = _loggable(getattr(self, "command", None) or "-"), _loggable(getattr(self, "path", None) or "-")
        self.config.log(f"{method} {path} {status} {nbytes}")

    def setup(self) -> None:
        super().setup()
        self.rfile.close()   # the plain socket file: reads go through the request deadline instead
        self._reader = _RequestReader(self.connection, self.timeout, self.request_timeout_s)
        self.rfile = io.BufferedReader(self._reader)

    def handle_one_request(self) -> None:
        self._reader.start_request()
        super().handle_one_request()

    def parse_request(self) -> bool:
        try:
            ok = super().parse_request()
        finally:
            self._reader.end_request()
        if ok and self.request_version == "HTTP/0.9":
            # a bare "GET /x" line: no headers either way, and no ground station speaks HTTP/0.9
            self.send_error(400, "HTTP/0.9 requests are not supported")
            return False
        if ok and self.command in ("GET", "HEAD") and self._has_body():
            # Refused, and the connection closed, rather than the body left unread: it would be parsed as the
            # next request on the connection, and behind a proxy (which forwards it as part of this request)
            # that is request smuggling, a request the proxy never saw nor checked.
            self.send_error(400, f"a {self.command} request has no body")
            _linger(self.connection, REFUSE_TIMEOUT_S)
            return False
        return ok

    def _has_body(self) -> bool:
        lengths = self.headers.get_all("Content-Length") or []
        return "Transfer-Encoding" in self.headers or any(v.strip() != "0" for v in lengths)

    def handle_expect_100(self) -> bool:
        return True   # no request body is ever read: the final answer comes instead of "100 Continue"

    def _plain(self, status: int, text: str, extra: dict[str, str] | None = None) -> None:
        body = (text + "\n").encode("utf-8")
        # logged before answering, so the line exists by the time a client has its response
        self._log(status, 0 if self.command == "HEAD" else len(body))
        self.send_response(status)
        self.send_header("Content-Type", "text/plain; charset=utf-8")
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        for k, v in (extra or {}).items():
            self.send_header(k, v)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def send_error(self, code: int, message: str | None = None, explain: str | None = None) -> None:
        # malformed request lines, over-long headers and the like (raised inside http.server)
        self.close_connection = True
        self._reader.end_request()
        if getattr(self, "request_version", "HTTP/0.9") == "HTTP/0.9":
            self.request_version = "HTTP/1.0"   # answer with a status line and headers all the same
        try:
            self._plain(code, message or http.HTTPStatus(code).phrase, {"Connection": "close"})
        except (OSError, ValueError):
            pass

    def __getattr__(self, name: str):
        # every method other than GET and HEAD: 405 with Allow (http.server would answer 501)
        if name.startswith("do_"):
            return self._not_allowed
        raise AttributeError(name)

    def _not_allowed(self) -> None:
        self.close_connection = True
        self._plain(405, "method not allowed: this server is read-only", {"Allow": ALLOWED})

    # ------------------------------------------------------------------ resolution
    def _resolve(self) -> tuple[int, Path | None]:
        """(status, file): 200 and a regular file inside the root, or an error status."""
        if len(self.path) > MAX_TARGET_CHARS:
            return 414, None
        try:
            raw_path = urllib.parse.urlsplit(self.path).path
        except ValueError:  # e.g. an absolute-form target with a broken IPv6 host: "GET http://[::1/x"
            return 400, None
        prefix = self.config.prefix
        if not raw_path.startswith(prefix):
            return 404, None
        rel = raw_path[len(prefix):]
        try:
            decoded = urllib.parse.unquote(rel, errors="strict")
        except UnicodeDecodeError:
            return 404, None
        segments = decoded.split("/")
        if any(len(s.encode("utf-8", "surrogatepass")) > NAME_MAX_BYTES for s in segments):
            return 414, None   # no file has such a name, and the file system would refuse to look (ENAMETOOLONG)
        if not decoded or any(s in ("", ".", "..") or s.startswith(".") or "\\" in s or "\x00" in s
                              for s in segments):
            return 404, None
        candidate = self.config.root.joinpath(*segments)
        try:
            real = Path(os.path.realpath(candidate))
        except (OSError, ValueError):
            return 404, None
        if os.path.commonpath([str(real), str(self.config.root)]) != str(self.config.root):
            return 403, None   # a symlink that leads out of the bundle
        if not os.path.isfile(real):   # False for any error, where Path.is_file() raises some (a name too long)
            return 404, None
        return 200, real

    # ------------------------------------------------------------------ methods
    def do_HEAD(self) -> None:  # noqa: N802 (http.server API)
        self._serve(body=False)

    def do_GET(self) -> None:  # noqa: N802 (http.server API)
        self._serve(body=True)

    def _serve(self, body: bool) -> None:
        status, path = self._resolve()
        if path is None:
            self._plain(status, {400: "bad request", 403: "forbidden", 414: "URI too long"}.get(status, "not found"))
            return
        try:
            st = path.stat()
            if st.st_size > MAX_FILE_BYTES:
                self._plain(403, "forbidden")
                return
            data = path.read_bytes()
        except OSError:
            self._plain(404, "not found")
            return
        etag = f'"{hashlib.sha256(data).hexdigest()}"'
        mtime = int(st.st_mtime)
        headers = {
            "Content-Type": CONTENT_TYPES.get(path.suffix.lower(), "application/octet-stream"),
            "ETag": etag,
            "Last-Modified": email.utils.formatdate(mtime, usegmt=True),
            "Cache-Control": ("public, max-age=31536000, immutable" if IMMUTABLE.search(path.name)
                              else "no-cache"),
        }
        if self._not_modified(etag, mtime):
            self._log(304, 0)
            self.send_response(304)
            for k, v in headers.items():
                if k != "Content-Type":
                    self.send_header(k, v)
            self.end_headers()
            return
        self._log(200, len(data) if body else 0)
        self.send_response(200)
        for k, v in headers.items():
            self.send_header(k, v)
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        if body:
            self.wfile.write(data)

    def _not_modified(self, etag: str, mtime: int) -> bool:
        inm = self.headers.get("If-None-Match")
        if inm is not None:
            tags = [t.strip().removeprefix("W/") for t in inm.split(",")]
            return "*" in tags or etag in tags
        ims = self.headers.get("If-Modified-Since")
        if ims:
            try:
                since = email.utils.parsedate_to_datetime(ims)
            except (TypeError, ValueError):
                return False
            if since is None:
                return False
            return mtime <= since.timestamp()
        return False


class Refusal(NamedTuple):
    why: str


class Slot:
    """One connection's place in Slots. Given back once, whoever gives it back first: the connection's thread
    when it ends, or the accepting thread when starting that thread failed. (A Ctrl-C can land in
    Thread.start after the thread has already served its request and given the slot back; a second give-back
    then raised KeyError, which the server logged as an internal error -- swallowing the Ctrl-C.)"""

    def __init__(self, slots: "Slots", client: str) -> None:
        self._slots, self.client = slots, client
        self._held = True

    def give_back(self) -> None:
        self._slots._release(self)


class Slots:
    """Connections served at once: at most `total`, and at most `per_client` from one client address, so
    that one client (64 slow connections, say) cannot take every slot and have everyone else refused."""

    def __init__(self, total: int, per_client: int) -> None:
        self.total, self.per_client = total, per_client
        self._lock = threading.Lock()
        self._in_use = 0
        self._by_client: dict[str, int] = {}

    def take(self, client: str) -> Slot | Refusal:
        """A slot for `client`, or why there is none."""
        with self._lock:
            if self._in_use >= self.total:
                return Refusal(f"over the limit of {self.total} connections")
            held = self._by_client.get(client, 0)
            if held >= self.per_client:
                return Refusal(f"over the limit of {self.per_client} connections from one address")
            self._in_use += 1
            self._by_client[client] = held + 1
            return Slot(self, client)

    @property
    def in_use(self) -> int:
        with self._lock:
            return self._in_use

    def _release(self, slot: Slot) -> None:
        with self._lock:
            if not slot._held:
                return
            slot._held = False
            self._in_use -= 1
            held = self._by_client.pop(slot.client) - 1
            if held:
                self._by_client[slot.client] = held


class BundleServer(http.server.ThreadingHTTPServer):
    daemon_threads = True
    block_on_close = False
    max_connections = MAX_CONNECTIONS   # make_server sets them per server
    max_per_client = MAX_PER_CLIENT

    def server_activate(self) -> None:
        super().server_activate()
        self._slots = Slots(self.max_connections, self.max_per_client)

    def process_request(self, request, client_address) -> None:
        slot = self._slots.take(client_address[0])
        if isinstance(slot, Refusal):
            self._refuse(request, client_address, slot.why)
            return
        thread = threading.Thread(target=self._serve_connection, args=(request, client_address, slot),
                                  daemon=True)
        try:
            thread.start()
        except BaseException:
            slot.give_back()   # no thread to give it back (or it already did: a slot is given back once)
            raise

    def _serve_connection(self, request, client_address, slot: Slot) -> None:
        try:
            self.process_request_thread(request, client_address)   # socketserver's: handle, then close
        finally:
            slot.give_back()

    def _refuse(self, request, client_address, why: str) -> None:
        """503 to a connection over a cap, without reading its request or starting a thread (the unread
        request is drained briefly after the answer: see _linger)."""
        body = b"too many connections; retry shortly\n"
        head = ("HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain; charset=utf-8\r\n"
                f"Content-Length: {len(body)}\r\nRetry-After: 1\r\nCache-Control: no-store\r\n"
                "Connection: close\r\n\r\n").encode("ascii")
        host, port = client_address[:2]
        self.RequestHandlerClass.config.log(f"- {host}:{port} 503 {why}")
        try:
            request.settimeout(REFUSE_TIMEOUT_S)
            request.sendall(head + body)
            _linger(request, REFUSE_TIMEOUT_S)
        except OSError:
            pass
        finally:
            request.close()

    def handle_error(self, request, client_address) -> None:
        """One log line instead of socketserver's traceback on stderr: a client that hangs up while it
        is answered is routine, anything else is reported (WIRIS_DEBUG=1 keeps the traceback)."""
        err = sys.exc_info()[1]
        if isinstance(err, ConnectionError):
            line = f"client hung up ({type(err).__name__})"
        else:
            if os.environ.get("WIRIS_DEBUG"):
                super().handle_error(request, client_address)
            line = (f"internal error: {type(err).__name__}: {_loggable(str(err))} "
                    "(rerun with WIRIS_DEBUG=1 for a traceback)")
        host, port = client_address[:2]
        self.RequestHandlerClass.config.log(f"- {host}:{port} {line}")


def host_port(host: str, port: int) -> str:
    """host:port as a URL writes it ([::1]:8000 for an IPv6 address)."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def bind_http(server_class: type[http.server.HTTPServer], host: str, port: int, handler, *, what: str,
              host_option: str, port_option: str):
    """server_class bound to (host, port), IPv6 when `host` is an IPv6 address (http.server listens on
    IPv4 only); a LinkError whose hint names the option to change when binding fails."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    try:
        return type(server_class.__name__, (server_class,), {"address_family": family})((host, port), handler)
    except OSError as err:
        if isinstance(err, socket.gaierror) or err.errno in (errno.EADDRNOTAVAIL, errno.EAFNOSUPPORT):
            hint = f"give {host_option} an address of this machine (127.0.0.1, ::1, 0.0.0.0 for all) or its name"
        elif err.errno == errno.EACCES:
            hint = f"ports below 1024 need privileges; choose another {port_option} (0 picks a free one)"
        else:
            hint = f"choose another {port_option} (0 picks a free one), or stop what uses it"
        raise LinkError(f"cannot {what} on {host_port(host, port)}: {err.strerror or err}", hint=hint) from None


def make_server(directory: str | Path, host: str = "127.0.0.1", port: int = 8000, *, prefix: str | None = None,
                log: Callable[[str], None] | None = None, idle_timeout_s: float = IDLE_TIMEOUT_S,
                request_timeout_s: float = REQUEST_TIMEOUT_S, max_connections: int = MAX_CONNECTIONS,
                max_per_client: int = MAX_PER_CLIENT) -> BundleServer:
    """A bound (not yet serving) threaded server for `directory`; port 0 picks a free port.
    `prefix` None: the URL path of the manifest's http URIs (see prefix_from_manifest).
    `idle_timeout_s`: the longest wait for one read or write; `request_timeout_s`: for a request's line and
    headers from their first byte. `max_connections`: served at once, `max_per_client` of them from one
    client address; more are answered 503."""
    require_directory(directory, LinkError, hint="build a bundle first: wiris cdf build --all -o DIR")
    root = Path(os.path.realpath(directory))
    config = ServeConfig(root=root, prefix=_normal_prefix(prefix if prefix is not None else prefix_from_manifest(root)),
                         **({"log": log} if log is not None else {}))
    # StreamRequestHandler applies `timeout` to the socket; http.server closes the connection when a read
    # or write of it times out (and logs nothing: there is no request to log)
    handler = type("BoundBundleHandler", (BundleHandler,),
                   {"config": config, "timeout": idle_timeout_s, "request_timeout_s": request_timeout_s})
    server_class = type("CappedBundleServer", (BundleServer,),
                        {"max_connections": max_connections, "max_per_client": max_per_client})
    return bind_http(server_class, host, port, handler, what="listen", host_option="--host", port_option="--port")


def server_url(server: BundleServer) -> str:
    host, port = server.server_address[:2]
    return f"http://{host_port(str(host), port)}{server.RequestHandlerClass.config.prefix}"


__all__ = ["BundleHandler", "BundleServer", "bind_http", "host_port", "make_server", "prefix_from_manifest",
           "server_url"]
