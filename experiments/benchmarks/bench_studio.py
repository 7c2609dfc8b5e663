"""Time the studio through its JSON API and its page, as a designer uses them.

Starts ``camjax studio FILE --no-browser --port P`` in fresh processes and times

- the cold start: from launching the process, with an empty compilation cache (a new
  ``CAMJAX_CACHE_DIR``), until ``GET /api/report`` answers with the report; and, where
  Chromium and Playwright are installed, until the page has drawn its plots (the browser is
  started first, so its own start is not counted);
- the start with the persistent cache as earlier runs left it: the first report and the
  first curves;
- a sequence of edits that keep the program's shape (the number and kinds of segments):
  each ``POST /api/program`` (the report) and the ``GET /api/curves`` after it;
- a design from the page's defaults (``POST /api/design``, polled to done): the first rise
  of the feed cam for the least preload over the range.

    python experiments/benchmarks/bench_studio.py [--file feed] [--rpm 200:1400:7] [--edits 4] [--no-design] [--no-cold]
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CHROMIUM = "/usr/bin/chromium"


def _get(url: str):
    with urllib.request.urlopen(url, timeout=900) as response:
        return json.load(response)


def _post(url: str, program: dict):
    """POST the program's structure as the page does: from the studio's own origin, as JSON
    (else refused)."""
    parts = urllib.parse.urlsplit(url)
    headers = {"Origin": f"{parts.scheme}://{parts.netloc}", "Content-Type": "application/json"}
    body = json.dumps(program).encode()
    request = urllib.request.Request(url, data=body, headers=headers, method="POST")
    with urllib.request.urlopen(request, timeout=900) as response:
        return json.load(response)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _launch(args, cache: str | None = None):
    """``(process, url, start time)`` of ``camjax studio`` on a free port; ``cache`` the
    compilation cache folder (default: the user's, as earlier runs left it)."""
    env = dict(os.environ)
    if cache is not None:
        env["CAMJAX_CACHE_DIR"] = cache
    port = _free_port()
    start = time.perf_counter()
    server = subprocess.Popen([sys.executable, "-m", "camjax", "studio", args.file, "--rpm", args.rpm,
                               "--no-browser", "--port", str(port)], stdout=subprocess.PIPE, text=True,
                              cwd=ROOT, env=env)
    return server, f"http://127.0.0.1:{port}/", start


def _cpu_s(server) -> float | None:
    """CPU seconds (user and system) the server process has used so far (Linux), a figure
    that other work on a busy machine does not inflate as it does the wall time."""
    try:
        fields = Path(f"/proc/{server.pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _load() -> str:
    try:
        return f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
    except OSError:
        return "load unknown"


def _stop(server) -> None:
    server.terminate()
    server.wait(timeout=30)


def _first_report(url: str):
    """The report, asked for as soon as the server listens."""
    while True:
        try:
            return _get(url + "api/report")
        except urllib.error.URLError as error:
            if not isinstance(error.reason, ConnectionRefusedError):
                raise
            time.sleep(0.02)


def cold_report(args) -> tuple[float, float | None]:
    """Seconds from launching the studio (empty cache) until the report answers, and the
    CPU seconds the server used by then."""
    with tempfile.TemporaryDirectory() as cache:
        server, url, start = _launch(args, cache)
        try:
            _first_report(url)
            return time.perf_counter() - start, _cpu_s(server)
        finally:
            _stop(server)


def cold_page(args) -> float | None:
    """Seconds from launching the studio (empty cache) until the page has drawn its plots,
    or None without Chromium or Playwright."""
    try:
        from playwright.sync_api import Error, sync_playwright
    except ImportError:
        return None
    if not Path(CHROMIUM).exists():
        return None
    with sync_playwright() as p, tempfile.TemporaryDirectory() as cache:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--headless", "--no-sandbox", "--disable-gpu"])
        page = browser.new_page(viewport={"width": 1600, "height": 1250})
        server, url, start = _launch(args, cache)
        try:
            while True:
                try:
                    page.goto(url)
                    break
                except Error:
                    time.sleep(0.05)
            page.wait_for_function("document.body.dataset.busy === '0' && "
                                   "document.querySelector('#c-preload canvas') !== null", timeout=600_000)
            return time.perf_counter() - start
        finally:
            _stop(server)
            browser.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--file", default="feed", help="program file or built-in example (default feed)")
    parser.add_argument("--rpm", default="200:1400:7", help="speed range (default 200:1400:7)")
    parser.add_argument("--edits", type=int, default=4, help="edits that keep the shape (default 4)")
    parser.add_argument("--no-design", action="store_true", help="skip the design")
    parser.add_argument("--no-cold", action="store_true",
                        help="skip the cold start (an empty compilation cache, the page in Chromium)")
    args = parser.parse_args()

    print(_load())
    report_s = None
    if not args.no_cold:
        report_s, cpu_s = cold_report(args)
        page_s = cold_page(args)
        print(f"cold start (empty compilation cache): report after {report_s:.1f} s ("
              + ("" if cpu_s is None else f"{cpu_s:.1f} CPU s; ") + f"{_load()}), page drawn after "
              + ("(no Chromium/Playwright)" if page_s is None else f"{page_s:.1f} s"))

    server, url, start = _launch(args)
    try:
        report = _first_report(url)
        first_report = time.perf_counter() - start
        _get(url + "api/curves")
        first_curves = time.perf_counter() - start
        print(f"start (persistent cache as left): first report after {first_report:.1f} s, first curves after "
              f"{first_curves:.1f} s (jump speed {report['jump_speed_rpm']})")

        state = _get(url + "api/program")
        program = state["program"]
        segments = program["segment"]
        first_rise = next(i for i, s in enumerate(segments) if s.get("lift_mm", 0) > 0)
        last_fall = max(i for i, s in enumerate(segments) if s.get("lift_mm", 0) < 0)
        rise, fall = segments[first_rise]["lift_mm"], segments[last_fall]["lift_mm"]
        posts, curves = [], []
        for i in range(1, args.edits + 1):
            delta = 0.25 * i * (-1) ** i  # the first rise and the last return change together
            edited = json.loads(json.dumps(program))
            edited["segment"][first_rise]["lift_mm"] = rise + delta
            edited["segment"][last_fall]["lift_mm"] = fall - delta
            t = time.perf_counter()
            jump = _post(url + f"api/program?rpm={args.rpm}", edited)["jump_speed_rpm"]
            posts.append(time.perf_counter() - t)
            t = time.perf_counter()
            _get(url + "api/curves")
            curves.append(time.perf_counter() - t)
            print(f"edit {i}: lift {rise + delta:g}/{fall - delta:g} mm: report {posts[-1]:.2f} s, "
                  f"curves {curves[-1]:.2f} s (jump speed {jump})")
        print(f"per edit (median of {args.edits}, {args.rpm} rpm): report {statistics.median(posts):.2f} s, "
              f"curves {statistics.median(curves):.2f} s ({_load()})")
        if report_s is not None:
            print(f"cold start to the report {report_s:.1f} s against a warm edit's report "
                  f"{statistics.median(posts):.2f} s")

        if not args.no_design:
            _post(url + f"api/program?rpm={args.rpm}", program)
            segment = 1 + first_rise
            speeds = [s["rpm"] for s in report["speeds"]]
            t, cpu = time.perf_counter(), _cpu_s(server)
            job = _post(url + f"api/design?segment={segment}&objective=preload&rpm={min(speeds)}:{max(speeds)}", "")
            optimised = None
            while job["state"] == "running":
                time.sleep(0.2)
                job = _get(url + "api/design")
                if optimised is None and job["phase"] == "analysing the designed program":
                    optimised = time.perf_counter() - t
            print(f"design of segment {segment} ({job['steps']} steps, {job['knots']} knots, the page's "
                  f"defaults): {job['state']} after {time.perf_counter() - t:.1f} s (law after "
                  f"{optimised or float('nan'):.1f} s; "
                  + ("" if cpu is None else f"{_cpu_s(server) - cpu:.1f} CPU s; ")
                  + f"{_load()}); {job['label']}: {job['before']:.5g} -> {job['after']:.5g}")
    finally:
        _stop(server)


if __name__ == "__main__":
    main()
