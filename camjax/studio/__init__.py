"""``camjax studio``: a cam workbench in the browser and the notebook.

A small server (Python's standard library) serves one page and a JSON API over the
public program API: ``GET /api/report`` is the report of ``camjax program --format json``,
``POST /api/program`` (the program's structure as a JSON body, ``?rpm=START:STOP:COUNT``)
replaces the program and answers its report, or a 400 status with ``{"error": "..."}`` holding the
library's one-line message; ``GET /api/curves?rpm=R`` gives the histories the page draws;
``POST /api/design`` designs a segment's law on a background thread (``GET /api/design``
its progress, ``POST /api/design/keep`` or ``/discard`` its outcome).
docs/studio.md describes the page and the API.
"""

from __future__ import annotations

from ._server import MAX_BODY as MAX_BODY
from ._server import TIMEOUT_S as TIMEOUT_S
from ._server import Studio as Studio
from ._workbench import DEFAULT_RPM as DEFAULT_RPM
from ._workbench import MAX_SPEEDS as MAX_SPEEDS
from ._workbench import Workbench as Workbench
from ._workbench import kinematics as kinematics
from ._workbench import parse_json_program as parse_json_program
from ._workbench import parse_program as parse_program
from ._workbench import rigid_contact_force_n as rigid_contact_force_n


def studio(program=None, *, rpm: str = DEFAULT_RPM, host: str = "127.0.0.1", port: int = 0,
           outputs=None) -> Studio:
    """A studio for ``program`` (a ``Program``, a program file's path, or a built-in
    example's name; default the ``feed`` example), serving on a background thread;
    ``outputs``: the per-speed outputs its reports hold (``camjax.program.Outputs``, or a
    list of probes beside the built-in ones; default the built-in ones)."""
    from ..program import Program, program_path
    base = None
    if isinstance(program, Program):
        toml = program.to_toml()
    else:
        path = program_path(None if program is None else str(program), default="feed")
        Program.load(path)  # its one-line error names the file
        toml, base = path.read_text(), path.parent
    parse_program(toml, base)  # the starting program must stand on its own
    return Studio(toml, base=base, rpm=rpm, host=host, port=port, outputs=outputs).start()


def show(program=None, *, rpm: str = DEFAULT_RPM, height: int = 900, outputs=None):
    """The workbench for ``program`` in a Jupyter cell (an ``IFrame`` to a studio served on a
    background thread of the kernel, which lives as long as the kernel), its reports with
    ``outputs`` (as ``studio``'s)."""
    from IPython.display import IFrame

    running = studio(program, rpm=rpm, outputs=outputs)
    frame = IFrame(running.page_url, width="100%", height=height)
    frame.studio = running
    return frame


__all__ = ["Studio", "Workbench", "studio", "show", "kinematics", "rigid_contact_force_n", "parse_program",
           "parse_json_program",
           "DEFAULT_RPM", "MAX_SPEEDS", "MAX_BODY", "TIMEOUT_S"]
