"""Open the built documentation site in headless Chromium, check three pages, screenshot them.

Serves ``site/`` (``mkdocs build --strict`` first) on a local port and loads, in a real
browser, the home page, the API entry of ``camjax.ct_curve`` and the Ct-curves notebook.
Each page's rendered DOM must hold what a reader comes for (the page title, the rendered
signature of ``ct_curve``, the notebook's executed figures); the screenshots go to
``docs/screenshots/`` (docs/development.md shows the home page's).

    mkdocs build --strict && python experiments/examples/docs_screenshots.py

Chromium comes from Debian's packages (``apt-get install chromium``); ``--browser`` names
another binary.  Exits 1 with the failed checks if a page does not render as expected.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import http.server
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# (screenshot name, path in the site, window height, strings the rendered DOM must contain)
PAGES = [
    ("home", "", 1000, ["camjax", "Getting started", "ct_curves.png"]),
    # ct_curve is the page's first entry: no anchor, whose scroll leaves a blank band.
    ("api_ct_curve", "api/camjax/", 1000,
     ['id="camjax.ct_curve"', 'class="doc-signature highlight"', "period_ratios"]),
    ("notebook_ct_curves", "notebooks/ct_curves/", 1800,
     ["Ct curves, residual vibration", "data:image/png", "max |R - closed form|"]),
]


@contextlib.contextmanager
def serve(directory: Path):
    """An HTTP server for ``directory`` on a free local port; yields its base URL."""
    handler = functools.partial(_QuietHandler, directory=str(directory))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def chromium(browser: str, profile: Path, *args: str) -> subprocess.CompletedProcess:
    command = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
               "--no-first-run", f"--user-data-dir={profile}", "--virtual-time-budget=5000",
               *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--site", type=Path, default=ROOT / "site", help="built site (default site/)")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "screenshots",
                        help="where the PNGs go (default docs/screenshots/)")
    parser.add_argument("--browser", default="chromium", help="Chromium binary (default chromium)")
    parser.add_argument("--width", type=int, default=1280, help="window width in pixels (default 1280)")
    args = parser.parse_args(argv)
    browser = shutil.which(args.browser)
    if browser is None:
        parser.error(f"no browser {args.browser!r} on PATH (apt-get install chromium)")
    if not (args.site / "index.html").exists():
        parser.error(f"no built site in {args.site} (run mkdocs build --strict first)")
    args.out.mkdir(parents=True, exist_ok=True)
    failures = []
    with serve(args.site) as base, tempfile.TemporaryDirectory() as profile:
        for name, path, height, expected in PAGES:
            url = base + path
            dom = chromium(browser, Path(profile), "--dump-dom", url).stdout
            missing = [text for text in expected if text not in dom]
            if missing:
                failures.append(f"{url}: rendered page lacks {missing}")
            shot = args.out / f"{name}.png"
            run = chromium(browser, Path(profile), f"--screenshot={shot}",
                           f"--window-size={args.width},{height}", url)
            if not shot.exists() or shot.stat().st_size == 0:
                failures.append(f"{url}: no screenshot ({run.stderr.strip()[-200:]})")
            print(f"{url} -> {shot.relative_to(ROOT) if shot.is_relative_to(ROOT) else shot}"
                  f"{'' if not missing else '  MISSING ' + ', '.join(missing)}")
    for failure in failures:
        print(f"docs_screenshots: {failure}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
