"""The studio's HTTP server: one static page and a JSON API, on Python's standard library.

Each page (browser tab) names its own workbench with a ``session`` query parameter
(requests without one share the workbench ``default``); a workbench is dropped when its
page closes (``POST /api/close``) or after ``idle_s`` seconds without a request.

What it lets in (docs/studio.md, "Security"): a request whose ``Host`` is the address
served (DNS rebinding), a ``POST`` from the page's own origin with a body of the page's
own types (cross-site forms and ``text/plain``), the token beyond loopback, a body up to
``MAX_BODY`` read in ``timeout_s`` before any lock is taken, programs that name files under
the studio's folder only.
"""

from __future__ import annotations

import contextvars
import io
import ipaddress
import json
import math
import secrets
import sys
import tempfile
import threading
import time
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

import numpy as np

from ..caches import carried
from ._workbench import (
    DEFAULT_RPM,
    SEATING_OPTIONS,
    Busy,
    FileAccess,
    OutsideRoot,
    ReportCache,
    Workbench,
    _file_name,
    parse_json_program,
    parse_toml,
    program_files,
)

STATIC = Path(__file__).parent / "static"
IDLE_S = 1800.0
"""Seconds a workbench lives without a request (its page may have closed unseen)."""
MAX_BODY = 1 << 20
"""Largest request body accepted (a program's TOML is a few kB): larger is a 413."""
TIMEOUT_S = 10.0
"""Seconds a request may take to arrive (its headers and its whole body): a stalled one is
dropped, and never holds a workbench meanwhile."""
BODY_TYPES = ("application/json",)
"""Content types a request body may have: not a type a cross-site form or ``text/plain``
request can send without the browser asking first (which this server never allows).  The
page posts its program as JSON (its structure); the server writes TOML (``Program.to_toml``)."""
TOKEN_COOKIE = "camjax-studio-token"
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "[::1]")
_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
          ".css": "text/css; charset=utf-8", ".png": "image/png", ".svg": "image/svg+xml"}


class Studio:
    """A running studio: the server, its thread and its workbenches.

    ``toml`` is the program every new workbench starts from (a program file's text);
    ``base`` the folder its law files are read from.  ``port=0`` picks a free port (``url`` says which).  ``root`` is
    the folder whose files a posted program may name (default ``base``, else the current
    folder); ``token`` the secret every request must carry (``?token=`` once, then a
    cookie, or ``Authorization: token ...``): generated when serving beyond loopback, where
    it is required.  ``timeout_s``: how long a request may take to arrive.  ``outputs``: the
    per-speed outputs of every workbench's reports (``camjax.program.Outputs``, or a list of
    probes beside the built-in ones; ``None``: the built-in ones), which the page shows as
    ``GET /api/outputs`` lists them.
    """

    def __init__(self, toml: str, *, base: Path | None = None, rpm: str = DEFAULT_RPM,
                 host: str = "127.0.0.1", port: int = 0, with_flight: bool = True,
                 idle_s: float = IDLE_S, root: Path | None = None, token: str | None = None,
                 timeout_s: float = TIMEOUT_S, outputs=None):
        self.toml, self.base, self.rpm, self.with_flight, self.idle_s = toml, base, rpm, with_flight, idle_s
        from ..program import Outputs

        self.outputs = Outputs.of(outputs)  # a bad set is refused here, not on the page's first request
        self.data = parse_toml(toml)  # its structure, as the page edits it
        self.workbenches: dict[str, Workbench] = {}
        self.reports = ReportCache()  # analyses shared by the workbenches (Workbench.update)
        self._lock = threading.Lock()
        self.ready = threading.Event()  # cleared while warm() computes the first look
        self.ready.set()
        self._laws = tempfile.TemporaryDirectory(prefix="camjax-studio-")  # designed laws' files
        self.root = Path(root if root is not None else base if base is not None else Path.cwd()).resolve()
        self.access = FileAccess(self.root, (Path(self._laws.name).resolve(),),
                                 _named_files(toml, base or self.root))
        self.loopback = is_loopback(host)
        if token is None and not self.loopback:
            token = secrets.token_urlsafe(32)
        self.token, self.timeout_s = token, timeout_s
        self.httpd = _Server((host, port), _Handler)
        self.httpd.studio = self
        self.httpd.context = contextvars.copy_context()
        self.hosts = self._hosts(host)
        self.thread: threading.Thread | None = None

    def _hosts(self, host: str) -> frozenset[str] | None:
        """The ``Host`` headers accepted: the loopback names and the address served, with the
        port; ``None`` (any) when served on every address, where the token guards it."""
        port = self.httpd.server_address[1]
        if host in ("", "0.0.0.0", "::"):
            return None
        names = {host if ":" not in host else f"[{host}]", *(LOOPBACK_NAMES if self.loopback else ())}
        return frozenset(f"{name}:{port}".lower() for name in names)

    @property
    def origin(self) -> str:
        host, port = self.httpd.server_address[:2]
        return f"http://{f'[{host}]' if ':' in host else host}:{port}"

    @property
    def url(self) -> str:
        """The server's address (the API's paths follow it)."""
        return self.origin + "/"

    @property
    def page_url(self) -> str:
        """The page's address to open: ``url`` with ``?token=`` when a token is required."""
        return self.url + (f"?token={self.token}" if self.token else "")

    def workbench(self, session: str) -> Workbench:
        """The workbench of ``session``, a new one from the starting program if none."""
        now = time.monotonic()
        with self._lock:
            for key in [k for k, w in self.workbenches.items() if now - w.used > self.idle_s]:
                del self.workbenches[key]
            bench = self.workbenches.get(session)
            if bench is None:
                bench = self.workbenches[session] = Workbench(self.data, self.rpm, self.base,
                                                              with_flight=self.with_flight, cache=self.reports,
                                                              law_dir=Path(self._laws.name), access=self.access,
                                                              outputs=self.outputs)
            bench.touch()
            return bench

    def close(self, session: str) -> None:
        with self._lock:
            self.workbenches.pop(session, None)

    def warm(self) -> Studio:
        """Analyse the starting program and compute what the page draws first, on two
        background threads, before the page asks: the report, then the curves at the
        default speed (most of a cold start is compiling them), beside the profile and the
        kinematics (compiled on the other core).  Requests wait until it is done, so none
        compiles the same program twice."""
        from ..program import profile

        def first_look():
            try:
                bench = Workbench(self.data, self.rpm, self.base, with_flight=self.with_flight, cache=self.reports,
                                  outputs=self.outputs)
                bench.ensure()
                bench.curves()
            except Exception:  # the page's own request reports it
                pass

        def geometry():
            try:
                from ._workbench import PROFILE_POINTS, TURN_POINTS, kinematics, parse_program

                program = parse_program(self.toml, self.base)
                profile(program, PROFILE_POINTS)
                kinematics(program, np.linspace(0.0, 360.0, TURN_POINTS))
            except Exception:
                pass

        threads = [threading.Thread(target=carried(t), name=f"camjax-studio-warm-{i}", daemon=True)
                   for i, t in enumerate((first_look, geometry))]

        def wait():
            for thread in threads:
                thread.join()
            self.ready.set()

        self.ready.clear()
        for thread in threads:
            thread.start()
        threading.Thread(target=wait, name="camjax-studio-warm", daemon=True).start()
        return self

    def start(self, warm: bool = True) -> Studio:
        """Serve on a background thread (``warm``: starting the first analysis at once)."""
        if warm:
            self.warm()
        self.thread = threading.Thread(target=self.httpd.serve_forever, name="camjax-studio", daemon=True)
        self.thread.start()
        return self

    def stop(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()
        self._laws.cleanup()


def is_loopback(host: str) -> bool:
    """Whether ``host`` (an address or ``localhost``) reaches this machine only."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def _named_files(toml: str, base: Path) -> frozenset[Path]:
    """The files the starting program names (it may reach outside the studio's folder: it
    was given on the command line), resolved."""
    try:
        data = parse_toml(toml)
    except ValueError:
        return frozenset()
    return frozenset((base / Path(name).expanduser()).resolve() for _, name in program_files(data))


class Refused(Exception):
    """A request the server will not serve: its HTTP status and a one-line reason."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    context: contextvars.Context | None = None
    """The context of the ``Studio`` that made the server (the command's cache setting,
    ``camjax._cache_dir``): each request's thread runs in a copy of it."""

    def process_request_thread(self, request, client_address):
        if self.context is None:
            return super().process_request_thread(request, client_address)
        return self.context.copy().run(super().process_request_thread, request, client_address)

    def handle_error(self, request, client_address):
        """One line for a request the handler could not answer (a dropped connection, a
        malformed request), instead of the standard library's traceback."""
        error = sys.exc_info()[1]
        if not isinstance(error, ConnectionError):
            print(f"camjax studio: request from {client_address[0]}: {type(error).__name__}: {error}",
                  file=sys.stderr)


class _Handler(BaseHTTPRequestHandler):
    server_version = "camjax-studio"

    def setup(self) -> None:
        self.timeout = self.server.studio.timeout_s  # the socket's: a stalled read ends
        super().setup()

    def log_message(self, format, *args):  # noqa: A002 - the base class's name
        pass  # one line per request would drown the URL; errors are reported below

    # -- replies ---------------------------------------------------------------------------

    def _send(self, status: int, body: bytes, content_type: str, headers: dict | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        for key, value in (headers or {}).items():
            self.send_header(key, value)
        for value in getattr(self, "_cookies", ()):
            self.send_header("Set-Cookie", value)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, value, status: int = 200) -> None:
        self._send(status, json.dumps(value, allow_nan=False).encode(), "application/json")

    def _error(self, status: int, message: str) -> None:
        self._json({"error": message}, status)

    # -- routing ---------------------------------------------------------------------------

    def do_GET(self):
        self._route("GET")

    def do_POST(self):
        self._route("POST")

    def _route(self, method: str) -> None:
        from ..errors import SolverError

        studio: Studio = self.server.studio
        parts = urlsplit(self.path)
        query = {k: v[-1] for k, v in parse_qs(parts.query).items()}
        session = query.get("session", "default")[:64]
        route = (method, parts.path)
        self._cookies = []
        try:
            self._admit(studio, method, query)
            self.body = self._body() if method == "POST" else ""  # all of it, before any lock
            if method == "GET" and (parts.path == "/" or parts.path.startswith("/static/")):
                return self._static(parts.path)
            if route not in _ROUTES:
                return self._error(HTTPStatus.NOT_FOUND, f"no such address: {method} {parts.path}")
            if route == ("POST", "/api/close"):
                studio.close(session)
                return self._json({"closed": session})
            studio.ready.wait()
            bench = studio.workbench(session)
            with bench.lock:
                _ROUTES[route](self, bench, query)
        except Refused as error:
            self.close_connection = True
            self._error(error.status, str(error))
        except TimeoutError:
            self.close_connection = True  # a stalled request: dropped, no answer
        except OutsideRoot as error:
            self._error(HTTPStatus.FORBIDDEN, str(error))
        except ValueError as error:
            self._error(HTTPStatus.BAD_REQUEST, str(error))
        except OverflowError as error:  # a number of the program too large for the arrays' type
            self._error(HTTPStatus.BAD_REQUEST, f"a number of the program is too large to compute with ({error}); "
                        "write large numbers as floats (1e12)")
        except Busy as error:
            self._error(HTTPStatus.CONFLICT, str(error))
        except SolverError as error:
            self._error(HTTPStatus.UNPROCESSABLE_ENTITY, str(error))
        except (BrokenPipeError, ConnectionResetError):
            pass  # the page went away
        except Exception as error:  # a fault of the studio itself: one line, the page lives on
            print(f"camjax studio: {method} {parts.path}: {type(error).__name__}: {error}", file=sys.stderr)
            self._error(HTTPStatus.INTERNAL_SERVER_ERROR, f"{type(error).__name__}: {error}")

    def _static(self, path: str) -> None:
        name = "index.html" if path == "/" else path.removeprefix("/static/")
        file = STATIC / name
        if "/" in name or name.startswith(".") or not file.is_file():
            return self._error(HTTPStatus.NOT_FOUND, f"no such file: {path}")
        self._send(200, file.read_bytes(), _TYPES.get(file.suffix, "application/octet-stream"))

    def _admit(self, studio: Studio, method: str, query: dict) -> None:
        """Refuse (403) a request for another host name, one without the token where one is
        required, and a ``POST`` from another origin; a token given as ``?token=`` is
        kept as a cookie for the page's own requests."""
        host = (self.headers.get("Host") or "").lower()
        if studio.hosts is not None and host not in studio.hosts:
            raise Refused(HTTPStatus.FORBIDDEN, f"Host: this studio serves {studio.origin}, not {host or 'no host'!r}")
        if studio.token is not None:
            cookie = f"{TOKEN_COOKIE}-{studio.httpd.server_address[1]}"  # cookies do not tell ports apart
            given = query.get("token") or _cookie(self.headers.get("Cookie"), cookie)
            auth = self.headers.get("Authorization") or ""
            if auth.lower().startswith("token "):
                given = auth[6:].strip()
            if not given or not secrets.compare_digest(given.encode(), studio.token.encode()):
                raise Refused(HTTPStatus.FORBIDDEN, "token: this studio needs its token (the URL it printed "
                              "holds it as ?token=...)")
            if "token" in query:
                self._cookies = [f"{cookie}={studio.token}; Path=/; HttpOnly; SameSite=Strict"]
        fetched_from = self.headers.get("Sec-Fetch-Site", "same-origin")
        if self.path.startswith("/api/") and fetched_from not in ("same-origin", "none"):
            # a browser says another site's page asked (an image, a script): no work for it
            raise Refused(HTTPStatus.FORBIDDEN, f"Sec-Fetch-Site: the API answers the studio's own page, "
                          f"not a {fetched_from} one")
        if method != "POST":
            return
        origin = self.headers.get("Origin")
        if origin is None and self.headers.get("Referer"):
            referer = urlsplit(self.headers["Referer"])
            origin = f"{referer.scheme}://{referer.netloc}"
        if origin is None or origin.lower() != f"http://{host}":
            raise Refused(HTTPStatus.FORBIDDEN, f"Origin: a change must come from the studio's own page "
                          f"(http://{host}), not {origin or 'no origin'!r}")

    def _body(self) -> str:
        """The whole request body (at most ``MAX_BODY`` bytes, arriving within the studio's
        ``timeout_s``; a stalled one raises ``TimeoutError``), as text."""
        text = self.headers.get("Content-Length")
        if self.headers.get("Transfer-Encoding"):
            raise Refused(HTTPStatus.LENGTH_REQUIRED, "Content-Length: a body must say its length "
                          "(no Transfer-Encoding)")
        try:
            length = int(text or 0)
        except ValueError:
            length = -1
        if length < 0 or (text is not None and not text.strip().isdigit()):
            raise Refused(HTTPStatus.BAD_REQUEST, f"Content-Length: must be a whole number of bytes, got {text!r}")
        if length > MAX_BODY:
            raise Refused(HTTPStatus.REQUEST_ENTITY_TOO_LARGE,
                          f"the request body is {length:,} bytes, more than {MAX_BODY:,}")
        if length == 0:
            return ""
        kind = (self.headers.get("Content-Type") or "").split(";")[0].strip().lower()
        if kind not in BODY_TYPES:
            raise Refused(HTTPStatus.UNSUPPORTED_MEDIA_TYPE,
                          f"Content-Type: a body must be {' or '.join(BODY_TYPES)}, got {kind or 'none'!r}")
        deadline = time.monotonic() + self.server.studio.timeout_s
        chunks, left = [], length
        while left:
            if time.monotonic() > deadline:
                raise TimeoutError
            chunk = self.rfile.read1(min(left, 65536))
            if not chunk:
                raise Refused(HTTPStatus.BAD_REQUEST, f"the body ended after {length - left:,} of the "
                              f"{length:,} bytes its Content-Length says")
            chunks.append(chunk)
            left -= len(chunk)
        try:
            return b"".join(chunks).decode("utf-8")
        except UnicodeDecodeError:
            raise ValueError("the program text is not UTF-8") from None

    # -- the API ---------------------------------------------------------------------------

    def report(self, bench: Workbench, query: dict) -> None:
        self._json(bench.ensure())

    def post_program(self, bench: Workbench, query: dict) -> None:
        """The program's structure posted as JSON (as the TOML reader gives it)."""
        self._json(bench.update(parse_json_program(self.body), query.get("rpm"), opened=query.get("opened") == "1"))

    def open_file(self, bench: Workbench, query: dict) -> None:
        """A program file's text opened in the page, posted as JSON ``{"toml": TEXT}``: read
        here (the page has no TOML reader), a file it names relative to itself refused."""
        body = parse_json_program(self.body)
        if set(body) != {"toml"} or not isinstance(body["toml"], str):
            raise ValueError('the body must be {"toml": the program file\'s text}')
        self._json(bench.update(parse_toml(body["toml"]), query.get("rpm"), opened=True))

    def get_program(self, bench: Workbench, query: dict) -> None:
        bench.ensure()
        self._json(bench.state())

    def curves(self, bench: Workbench, query: dict) -> None:
        text = query.get("rpm")
        try:
            rpm = None if text in (None, "") else float(text)
        except ValueError:
            raise ValueError(f"rpm: the chosen speed must be a number, got {text!r}") from None
        self._json(bench.curves(rpm))

    def toml(self, bench: Workbench, query: dict) -> None:
        bench.ensure()
        name = bench.program.name
        self._send(200, bench.toml.encode(), "application/toml; charset=utf-8",
                   {"Content-Disposition": f'attachment; filename="{_file_name(name)}.toml"'})

    def export(self, bench: Workbench, query: dict, suffix: str) -> None:
        from ..program import profile, write_csv, write_dxf

        bench.ensure()
        points = query.get("points", "3600")
        try:
            points = int(points)
        except ValueError:
            raise ValueError(f"points: must be a whole number, got {points!r}") from None
        prof = profile(bench.program, points)  # its ValueError names the range
        writer = write_csv if suffix == "csv" else write_dxf
        with tempfile.TemporaryDirectory() as folder:
            path = writer(prof, Path(folder) / f"profile.{suffix}", outer=bench.program.follower.form_closed)
            body = path.read_bytes()
        kind = "text/csv; charset=utf-8" if suffix == "csv" else "application/dxf"
        self._send(200, body, kind, {"Content-Disposition":
                                     f'attachment; filename="{_file_name(bench.program.name)}-profile.{suffix}"'})

    def bundle(self, bench: Workbench, query: dict) -> None:
        """The program as ``camjax design --program`` writes it (``write_program``): its
        TOML and each law that is not a registry name as a JSON file beside it, zipped."""
        import zipfile

        from ..program import write_program

        bench.ensure()
        with tempfile.TemporaryDirectory() as folder:
            write_program(bench.program, Path(folder) / "program")
            buffer = io.BytesIO()
            with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
                for file in sorted((Path(folder) / "program").iterdir()):
                    archive.write(file, file.name)
        self._send(200, buffer.getvalue(), "application/zip",
                   {"Content-Disposition": f'attachment; filename="{_file_name(bench.program.name)}.zip"'})

    # -- designing a segment's law ----------------------------------------------------------

    def start_design(self, bench: Workbench, query: dict) -> None:
        segment = _number(query, "segment", int)
        text = query.get("rpm", "")
        parts = text.split(":")
        if len(parts) != 2:
            raise ValueError(f"rpm: expected LO:HI (rpm), got {text!r}")
        lo, hi = (_number({"rpm": p}, "rpm", float) for p in parts)
        options = {k: _number(query, k, int) for k in ("steps", "knots", *SEATING_OPTIONS) if k in query}
        self._json(bench.start_design(segment, query.get("objective", "preload"), lo, hi, **options),
                   HTTPStatus.ACCEPTED)

    def design(self, bench: Workbench, query: dict) -> None:
        self._json({"state": "none"} if bench.job is None else bench.job.as_dict())


def _cookie(header: str | None, name: str) -> str | None:
    for part in (header or "").split(";"):
        key, _, value = part.strip().partition("=")
        if key == name:
            return value
    return None


def _number(query: dict, key: str, kind):
    """``query[key]`` as an ``int`` or a ``float``, or a one-line ValueError naming ``key``."""
    text = query.get(key, "")
    try:
        value = kind(text)
    except ValueError:
        raise ValueError(f"{key}: must be a {'whole ' if kind is int else ''}number, got {text!r}") from None
    if kind is float and not math.isfinite(value):
        raise ValueError(f"{key}: must be a finite number, got {text!r}")
    return value


_ROUTES = {
    ("GET", "/api/report"): _Handler.report,
    ("POST", "/api/program"): _Handler.post_program,
    ("POST", "/api/open"): _Handler.open_file,
    ("GET", "/api/program"): _Handler.get_program,
    ("GET", "/api/curves"): _Handler.curves,
    ("GET", "/api/outputs"): lambda h, b, q: h._json(b.output_columns()),
    ("GET", "/api/program.toml"): _Handler.toml,
    ("GET", "/api/profile.csv"): lambda h, b, q: h.export(b, q, "csv"),
    ("GET", "/api/profile.dxf"): lambda h, b, q: h.export(b, q, "dxf"),
    ("GET", "/api/program.zip"): _Handler.bundle,
    ("POST", "/api/design"): _Handler.start_design,
    ("GET", "/api/design"): _Handler.design,
    ("POST", "/api/design/keep"): lambda h, b, q: h._json(b.keep_design()),
    ("POST", "/api/design/discard"): lambda h, b, q: h._json(b.discard_design()),
    ("POST", "/api/close"): None,
}
