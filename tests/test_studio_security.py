"""The studio's server lets in only its own page: files under its folder, its own host name
and origin, the token beyond loopback, bounded bodies and work, stalled requests dropped
while others are answered.  No test here analyses a program: each request is refused (or
answered) before any compiling."""

import http.client
import json
import signal
import socket
import subprocess
import sys
import time
import tomllib
import urllib.error
import urllib.parse
import urllib.request

import pytest

from camjax import program as cp
from camjax.studio import MAX_BODY, MAX_SPEEDS, Studio

FEED = cp.example_path("feed").read_text()
SECRET = "the-secret-line-7f3a"
TABLE = '[program]\nname = "t"\nfile = "{file}"\n\n[follower]\nmass_kg = 1.0\nstiffness_n_per_mm = 100.0\n'
DXF = '[program]\nname = "t"\ndxf = "{file}"\n\n[follower]\nmass_kg = 1.0\nstiffness_n_per_mm = 100.0\n'
LAW = FEED.replace('law = "polynomial"', 'law = "{file}"', 1)


@pytest.fixture
def folders(tmp_path):
    """The studio's folder (``root``) and, beside it, a folder holding a secret file."""
    root, outside = tmp_path / "root", tmp_path / "outside"
    root.mkdir()
    outside.mkdir()
    for suffix in ("csv", "json"):
        (outside / f"secret.{suffix}").write_text(f"{SECRET}\n1,2\n")
        (root / f"link.{suffix}").symlink_to(outside / f"secret.{suffix}")
    (root / "inside.csv").write_text(f"{SECRET}\n")
    return root, outside


@pytest.fixture
def running(folders):
    root, _ = folders
    studio = Studio(FEED, base=root, rpm="400:1000:4", timeout_s=1.0).start(warm=False)
    yield studio
    studio.stop()


def request(studio, method, path, body=None, headers=None, host=None):
    """(status, text) of a request to ``studio`` with exactly ``headers`` (plus Host)."""
    address, port = studio.httpd.server_address[:2]
    connection = http.client.HTTPConnection(address, port, timeout=30)
    connection.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
    connection.putheader("Host", host or f"{address}:{port}")
    data = None if body is None else body.encode()
    for key, value in (headers or {}).items():
        connection.putheader(key, value)
    if data is not None:
        connection.putheader("Content-Length", str(len(data)))
    connection.endheaders(data)
    response = connection.getresponse()
    text = response.read().decode()
    connection.close()
    return response.status, text


def as_json(text: str) -> str:
    """A program's TOML text as the page posts it: its structure as JSON."""
    return json.dumps(tomllib.loads(text)) if text else text


def post(studio, path, body, **headers):
    """A POST as the page sends it (its own origin, the program's structure as a JSON body:
    ``body`` is its TOML text), ``headers`` replacing those."""
    body = as_json(body)
    sent = {"Origin": studio.origin, "Content-Type": "application/json"}
    sent.update({k.replace("_", "-"): v for k, v in headers.items() if v is not None})
    for k in [k for k, v in headers.items() if v is None]:
        sent.pop(k.replace("_", "-"))
    return request(studio, "POST", path, body, sent)


def read_all(sock) -> str:
    """Everything the server sends before it closes the connection."""
    chunks = []
    while chunk := sock.recv(65536):
        chunks.append(chunk)
    return b"".join(chunks).decode()


def error(text: str) -> str:
    return json.loads(text)["error"]


@pytest.mark.parametrize("template", [TABLE, DXF, LAW], ids=["table", "dxf", "law"])
def test_a_file_outside_the_folder_is_refused_unread(running, folders, template):
    root, outside = folders
    names = [
        str(outside / "secret.csv"),
        "../outside/secret.csv",
        "link.csv",
        "/etc/passwd",
        "~/x.csv",
    ]
    for name in names if template is not LAW else [n.replace(".csv", ".json") for n in names[:3]]:
        status, text = post(running, "/api/program", template.replace("{file}", name))
        assert status == 403, (name, text)
        assert SECRET not in text and "root:" not in text
        assert error(text).endswith(
            "is outside the studio's folder "
            + str(root.resolve())
            + "; the studio reads only files under the folder it was started on"
        )
        assert repr(name) in error(text)


def test_a_file_inside_the_folder_is_read_and_its_error_names_the_line(running):
    status, text = post(running, "/api/program", TABLE.replace("{file}", "inside.csv"))
    assert status == 400 and "line 1" in error(text) and "inside.csv" in error(text)


def test_an_opened_program_cannot_name_a_file_beside_itself(running, folders):
    root, _ = folders
    for name in ("inside.csv", "../outside/secret.csv"):  # a file opened in the page: read by the server
        status, text = request(running, "POST", "/api/open", json.dumps({"toml": TABLE.replace("{file}", name)}),
                               {"Origin": running.origin, "Content-Type": "application/json"})
        assert status == 403 and error(text).startswith(f"[program] file: {name!r} is relative to the opened file's")
        assert SECRET not in text
    status, text = post(running, "/api/program?opened=1", TABLE.replace("{file}", "inside.csv"))
    assert status == 403 and error(text).startswith(
        "[program] file: 'inside.csv' is relative to the opened file's"
    )
    status, text = post(
        running, "/api/program?opened=1", TABLE.replace("{file}", str(root / "inside.csv"))
    )
    assert status == 400 and "line 1" in error(text)  # read: a full path under the folder


@pytest.mark.parametrize("host", ["evil.example", "evil.example:80", "127.0.0.1:1", "localhost"])
def test_another_host_name_is_refused(running, host):
    status, text = request(running, "GET", "/api/program", host=host)
    assert status == 403 and error(text).startswith("Host: this studio serves http://127.0.0.1:")
    status, text = request(running, "GET", "/", host=host)
    assert status == 403 and "<html" not in text


def test_loopback_names_with_the_port_are_served(running):
    port = running.httpd.server_address[1]
    for host in (f"localhost:{port}", f"127.0.0.1:{port}", f"[::1]:{port}"):
        status, text = request(running, "GET", "/", host=host)
        assert status == 200 and "<title>camjax studio</title>" in text


@pytest.mark.parametrize("origin", ["http://evil.example", "null", None, "https://127.0.0.1"])
def test_a_post_from_another_origin_is_refused(running, origin):
    status, text = post(running, "/api/program", FEED, Origin=origin)
    assert status == 403 and error(text).startswith(
        "Origin: a change must come from the studio's own page"
    )
    status, text = post(running, "/api/close", "", Origin=origin, Content_Type=None)
    assert status == 403


def test_a_referer_from_the_page_stands_for_the_origin(running):
    status, text = post(
        running,
        "/api/program",
        TABLE.replace("{file}", "/etc/passwd"),
        Origin=None,
        Referer=running.url + "?session=x",
    )
    assert status == 403 and "outside the studio's folder" in error(text)  # past the origin check


@pytest.mark.parametrize(
    "kind", ["text/plain", "application/x-www-form-urlencoded", "multipart/form-data", None, "application/toml"]
)
@pytest.mark.parametrize("path", ["/api/program", "/api/open"])
def test_a_simple_cross_site_body_is_refused(running, kind, path):
    """A body a page elsewhere could send without the browser asking first (and any other
    than the page's JSON): refused, from any origin, before any work; the program unchanged."""
    before = running.workbench("default").data
    for origin in ("http://evil.example", running.origin):
        status, text = post(running, path, FEED.replace("lift_mm = 8\n", "lift_mm = 7\n"), Origin=origin,
                            Content_Type=kind)
        assert status == (403 if origin != running.origin else 415), text
    assert error(text) == f"Content-Type: a body must be application/json, got {kind or 'none'!r}"
    assert running.workbench("default").data is before and running.workbench("default").report is None


def test_beyond_loopback_a_token_is_required(folders):
    root, _ = folders
    studio = Studio(FEED, base=root, host="0.0.0.0", timeout_s=1.0).start(warm=False)
    try:
        assert (
            studio.token
            and len(studio.token) >= 40
            and studio.page_url.endswith(f"/?token={studio.token}")
        )
        port = studio.httpd.server_address[1]

        def get(path, **headers):
            return request(studio, "GET", path, headers=headers, host=f"127.0.0.1:{port}")

        status, text = get("/")
        assert status == 403 and error(text).startswith("token: this studio needs its token")
        assert get("/?token=wrong")[0] == 403 and get("/", Cookie="camjax-studio-token=x")[0] == 403
        address = studio.httpd.server_address
        connection = http.client.HTTPConnection("127.0.0.1", address[1], timeout=30)
        connection.request("GET", f"/?token={studio.token}")
        response = connection.getresponse()
        assert response.status == 200 and "<title>camjax studio</title>" in response.read().decode()
        cookie = response.getheader("Set-Cookie")
        assert (
            cookie.startswith(f"camjax-studio-token-{port}={studio.token};")
            and "HttpOnly" in cookie
        )
        assert (
            get("/", Cookie=cookie.split(";")[0])[0] == 200
        )  # then the page's own requests carry it
        assert get("/", Authorization=f"token {studio.token}")[0] == 200
    finally:
        studio.stop()


def test_a_body_too_large_is_a_413_unread(running):
    """Refused from its Content-Length, before a byte of it is read."""
    address, port = running.httpd.server_address[:2]
    with socket.create_connection((address, port), timeout=30) as sock:
        sock.sendall(
            (
                f"POST /api/program HTTP/1.1\r\nHost: {address}:{port}\r\nOrigin: {running.origin}\r\n"
                f"Content-Type: application/json\r\nContent-Length: {MAX_BODY + 1}\r\n\r\n"
            ).encode()
        )
        answer = read_all(sock)
    assert answer.startswith("HTTP/1.0 413") or answer.startswith("HTTP/1.1 413"), answer
    assert f"the request body is {MAX_BODY + 1:,} bytes, more than {MAX_BODY:,}" in answer


@pytest.mark.parametrize("length", ["abc", "-5", "1e3"])
def test_a_bad_content_length_is_a_400_in_one_line(running, length):
    address, port = running.httpd.server_address[:2]
    with socket.create_connection((address, port), timeout=30) as sock:
        sock.sendall(
            (
                f"POST /api/program HTTP/1.1\r\nHost: {address}:{port}\r\nOrigin: {running.origin}\r\n"
                f"Content-Type: application/json\r\nContent-Length: {length}\r\n\r\n"
            ).encode()
        )
        answer = read_all(sock)
    assert " 400 " in answer.splitlines()[0]
    assert json.loads(answer.split("\r\n\r\n", 1)[1]) == {
        "error": f"Content-Length: must be a whole number of bytes, got {length!r}"
    }


def test_a_stalled_request_is_dropped_and_others_are_answered(running):
    """Half a body (its Content-Length larger than what follows) on the default workbench:
    another request for that workbench is answered meanwhile, and the stalled one is closed
    after the studio's timeout (1 s here)."""
    address, port = running.httpd.server_address[:2]
    stalled = socket.create_connection((address, port), timeout=30)
    stalled.sendall(
        (
            f"POST /api/program HTTP/1.1\r\nHost: {address}:{port}\r\nOrigin: {running.origin}\r\n"
            f"Content-Type: application/json\r\nContent-Length: {len(as_json(FEED))}\r\n\r\n"
        ).encode()
        + as_json(FEED)[:100].encode()
    )
    time.sleep(0.2)  # the server is reading it
    started = time.monotonic()
    status, text = post(running, "/api/program", TABLE.replace("{file}", "/etc/passwd"))
    assert (
        status == 403 and time.monotonic() - started < 0.9
    )  # answered before the stalled one's timeout
    status, _ = request(running, "GET", "/")
    assert status == 200
    stalled.settimeout(10)
    assert stalled.recv(65536) == b""  # closed, with no answer
    assert time.monotonic() - started < 5
    stalled.close()


def test_a_slow_drip_body_is_dropped_at_the_timeout(running):
    """A byte at a time, each within the socket's timeout: the whole body must still arrive
    within ``timeout_s``."""
    address, port = running.httpd.server_address[:2]
    with socket.create_connection((address, port), timeout=30) as sock:
        sock.sendall(
            (
                f"POST /api/program HTTP/1.1\r\nHost: {address}:{port}\r\nOrigin: {running.origin}\r\n"
                f"Content-Type: application/json\r\nContent-Length: 100\r\n\r\n"
            ).encode()
        )
        started, closed = time.monotonic(), False
        while time.monotonic() - started < 10:
            try:
                sock.sendall(b"#")
            except OSError:
                closed = True
                break
            time.sleep(0.3)
            sock.setblocking(False)
            try:
                closed = sock.recv(1) == b""
            except BlockingIOError:
                pass
            sock.setblocking(True)
            if closed:
                break
    assert closed and time.monotonic() - started < 5


@pytest.mark.parametrize(
    "rpm", ["200:1400:100000", f"200:1400:{MAX_SPEEDS + 1}", ",".join(["500"] * (MAX_SPEEDS + 1))]
)
def test_too_many_speeds_are_refused_before_any_work(running, rpm):
    started = time.monotonic()
    status, text = post(running, "/api/program?" + urllib.parse.urlencode({"rpm": rpm}), FEED)
    assert time.monotonic() - started < 2
    count = int(rpm.rsplit(":", 1)[1]) if ":" in rpm else MAX_SPEEDS + 1
    assert (
        status == 400
        and error(text).startswith(f"rpm has {count:,} speeds, more than the {MAX_SPEEDS:,} one analysis takes")
    )


def test_the_studio_package_exports_what_it_names():
    namespace = {}
    exec("from camjax.studio import *", namespace)  # noqa: S102 - the statement under test
    import camjax.studio

    assert set(camjax.studio.__all__) <= namespace.keys()


def test_the_starting_program_may_name_files_beside_its_folder(tmp_path):
    """A program given on the command line is the user's own: the files it names are read
    even outside its folder, and only those."""
    (tmp_path / "laws").mkdir()
    (tmp_path / "cams").mkdir()
    law = tmp_path / "laws" / "rise.json"
    from camjax import laws

    laws.save(laws.get("cycloidal"), law)
    toml = LAW.replace("{file}", "../laws/rise.json")
    studio = Studio(toml, base=tmp_path / "cams", timeout_s=1.0).start(warm=False)
    try:
        studio.access.check(tomllib.loads(toml), tmp_path / "cams")
        other = LAW.replace("{file}", "../laws/other.json")
        with pytest.raises(ValueError, match="'../laws/other.json' is outside the studio's folder"):
            studio.access.check(tomllib.loads(other), tmp_path / "cams")
    finally:
        studio.stop()


def test_the_command_beyond_loopback_warns_and_prints_the_token():
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "camjax",
            "studio",
            "indexer",
            "--no-browser",
            "--port",
            "0",
            "--host",
            "0.0.0.0",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        warning, line = server.stderr.readline(), server.stdout.readline()
        assert warning.startswith(
            "camjax studio: warning: serving on 0.0.0.0, beyond this machine: whoever has"
        )
        url = line[line.index("http://") :].split()[0]
        base, token = url.split("/?token=")
        assert len(token) >= 40
        port = base.rsplit(":", 1)[1]
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=60)
        assert refused.value.code == 403
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/?token={token}", timeout=60) as page:
            assert "<title>camjax studio</title>" in page.read().decode()
    finally:
        server.send_signal(signal.SIGINT)
        server.communicate(timeout=60)
    assert server.returncode == 0


@pytest.mark.parametrize("site", ["cross-site", "same-site"])
def test_another_sites_page_gets_no_work_done(running, site):
    """A browser names who asked (``Sec-Fetch-Site``): another site's image or script asking
    the API is refused before any work; a link to the page itself is followed."""
    status, text = request(running, "GET", "/api/report", headers={"Sec-Fetch-Site": site})
    assert (
        status == 403
        and error(text)
        == f"Sec-Fetch-Site: the API answers the studio's own page, not a {site} one"
    )
    assert request(running, "GET", "/", headers={"Sec-Fetch-Site": site})[0] == 200
