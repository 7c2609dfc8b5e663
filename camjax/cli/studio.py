"""``camjax studio``: the cam workbench in the browser (camjax.studio)."""

from __future__ import annotations

import sys

from ._common import CliError, add_probes_option, outputs_of

DEFAULT_PORT = 8765
DEFAULT_RPM = "200:1400:101"  # camjax.studio.DEFAULT_RPM (not imported: JAX loads late)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "studio",
        help="a cam workbench in the browser: edit a program, see its report redrawn",
        description=(
            "Serve the cam workbench: the program's segments and follower as editable tables, "
            "the lift and its derivatives, the profile, the response at one speed and the "
            "report over a speed range (minimum preload, jump speed, residual vibration, drive "
            "torque, Hertz stress), redrawn after every edit; design a segment's law for a "
            "speed band and keep or discard it; open and save the program as "
            "TOML, export the profile (CSV, DXF).  FILE is a program TOML file or a built-in "
            "example's name ('indexer', 'feed'; default feed).  Ctrl-C stops the server."
        ),
    )
    parser.add_argument("file", nargs="?", metavar="FILE",
                        help="program TOML file or built-in example name (default: feed)")
    parser.add_argument("--rpm", default=DEFAULT_RPM, metavar="START:STOP:COUNT|V1,V2,...",
                        help="the speed range the workbench starts with, rpm")
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to serve on (beyond this machine, e.g. 0.0.0.0: requests need the "
                             "token the printed URL holds)")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help="port to serve on (0: any free port)")
    parser.add_argument("--no-browser", action="store_true", help="do not open a browser")
    add_probes_option(parser)
    parser.set_defaults(func=run)


def run(args) -> int:
    from ..program import Program, Speeds
    from ..studio import Studio, parse_program
    from .program import is_machine, program_path

    if not 0 <= args.port <= 65535:
        raise CliError(f"--port: must be from 0 to 65535, got {args.port}")
    try:
        Speeds.parse(args.rpm, "--rpm")
    except ValueError as error:
        raise CliError(str(error)) from None
    outputs = outputs_of(args.probes)
    path = program_path(args.file, default="feed")
    if is_machine(path):
        raise CliError(f"{path}: a machine file ([[cam]] tables); the studio edits one program file")
    Program.load(path)  # its one-line error names the file
    toml = path.read_text()
    parse_program(toml, path.parent)
    try:
        studio = Studio(toml, base=path.parent, rpm=args.rpm, host=args.host, port=args.port, outputs=outputs)
    except OSError as error:
        raise CliError(f"--host/--port: cannot serve on {args.host}:{args.port} "
                       f"({error.strerror or error})") from None
    studio.warm()  # the first analysis starts while the browser opens the page
    if not studio.loopback:
        print(f"camjax studio: warning: serving on {args.host}, beyond this machine: whoever has the URL "
              f"below (it holds the token) can read program files under {studio.root} and run analyses",
              file=sys.stderr, flush=True)
    print(f"camjax studio: {path.name} at {studio.page_url} (files under {studio.root}; Ctrl-C stops)", flush=True)
    if not args.no_browser:
        import webbrowser

        webbrowser.open(studio.page_url)
    try:
        studio.httpd.serve_forever()
    except KeyboardInterrupt:
        print("camjax studio: stopped", file=sys.stderr)
    finally:
        studio.httpd.server_close()
    return 0
