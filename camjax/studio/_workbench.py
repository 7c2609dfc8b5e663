"""One workbench's state: the program (its structure, as the TOML reader takes it), the
speed range and its report.

Everything the page shows comes from the public program API (``camjax.program``): the
report is ``camjax.program.analyse``'s, as ``camjax program --format json`` prints it.  The
page posts the program's structure as JSON; wherever TOML is needed (the download, a
design's program) it is ``Program.to_toml``'s, the one writer of a program file.
"""

from __future__ import annotations

import dataclasses
import json
import math
import tempfile
import threading
import time
import tomllib
import uuid
from pathlib import Path

import numpy as np

from .._plain import DEFAULT_SPEED_FLUCTUATION, json_ready, plot_speed
from ..caches import carried, relieve_memory_maps
from ..checks import MAX_SPEEDS as MAX_SPEEDS

DEFAULT_RPM = "200:1400:101"
"""The speed range a workbench starts with: wide enough to show the examples' jump speeds,
dense enough for smooth curves over it, an edit about half a second (docs/studio.md)."""
TURN_POINTS = 721
"""Cam angles over the turn for the kinematic curves (every half degree)."""
PROFILE_POINTS = 720
"""Profile points the page draws."""
CACHED_REPORTS = 16
"""Analyses a studio keeps (oldest dropped first), shared by its workbenches."""
DESIGN_STEPS = 60
"""Optimiser steps of a design started from the page: about 15 s of optimising for a segment of the feed
cam on a 2-core machine (``camjax design`` takes 6000 for its best law; a designer waits
here, and may ask for more)."""
DESIGN_KNOTS = 12
"""Free B-spline coefficients of a design from the page (``camjax design``: 24)."""
DESIGN_OBJECTIVES = {"preload": "least preload over the band", "residual": "least residual vibration",
                     "seating": "least seating velocity of the valve"}
"""The page's objectives, as ``camjax.program.design_segment`` names them, with what the
page calls them; a program is offered those it takes (``design_choices``)."""
SEATING_ROUNDS = 3
"""Rounds of a seating design from the page (``camjax.program.seating_design``: 6), each a
design of ``DESIGN_STEPS`` steps and a simulation of the chain at every speed of the band."""
SEATING_OPTIONS = ("rounds", "seating_speeds")
"""A design's options for the seating objective only (``seating_design``'s rounds, its
speeds over the band)."""
PROGRAM_FILE_KEYS = ("file", "dxf")
"""Keys of ``[program]`` and of a ``[[segment]]`` that name a file to read (and ``law``
when it ends in ``.json``)."""


class Busy(Exception):
    """A request that conflicts with work under way (a design running): HTTP 409."""


def parse_toml(text: str) -> dict:
    """TOML text as its structure, or a one-line ``ValueError``."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"not valid TOML ({error})") from None


def parse_program(text: str, base: Path | None = None):
    """A ``Program`` from TOML text (law files relative to ``base``), or a one-line ``ValueError``."""
    from ..program import Program

    return Program.from_dict(parse_toml(text), base=base)


JSON_INT_LIMIT = 2**31
"""A whole number in a posted program at or beyond this size is read as a float: a length,
not an index (a TOML file's integer past 64 bits overflows the arrays; the follower reads
its own fields as floats, but a table's points do not)."""


def parse_json_program(text: str) -> dict:
    """A program's structure posted as JSON (what ``Program.from_dict`` takes, as the TOML
    reader gives it), or a one-line ``ValueError``: an object, no ``null`` (TOML has none:
    leave the key out), no NaN or infinity."""

    def constant(name):
        raise ValueError(f"the program holds {name}: every number must be finite")

    def whole(digits: str):
        value = int(digits)
        return value if abs(value) < JSON_INT_LIMIT else float(digits)

    try:
        data = json.loads(text, parse_constant=constant, parse_int=whole)
    except json.JSONDecodeError as error:
        raise ValueError(f"not valid JSON ({error})") from None
    if not isinstance(data, dict):
        raise ValueError(f"the program must be a JSON object (its tables by name), got {type(data).__name__}")
    _no_null(data, "")
    return data


def _no_null(value, where: str) -> None:
    if value is None:
        raise ValueError(f"{where or 'the program'}: null is no value (TOML has none): leave the key out")
    if isinstance(value, dict):
        for key, item in value.items():
            _no_null(item, f"{where}.{key}" if where else key)
    elif isinstance(value, list):
        for i, item in enumerate(value, 1):
            _no_null(item, f"{where} {i}")


def law_file_names(data: dict) -> dict[int, str]:
    """The law files a program's structure names, by 1-based segment (``Program.to_toml``'s
    ``law_files``: the TOML names them as the structure does)."""
    segments = data.get("segment") if isinstance(data, dict) else None
    return {i: seg["law"] for i, seg in enumerate(segments if isinstance(segments, list) else (), 1)
            if isinstance(seg, dict) and isinstance(seg.get("law"), str) and seg["law"].endswith(".json")}


def parse_speeds(text: str):
    """The speed range ``text`` (``START:STOP:COUNT`` or ``V1,V2,...``, rpm) as
    ``camjax.program.Speeds``, or a one-line ValueError; more than ``MAX_SPEEDS`` speeds (the
    library's limit on one analysis) are refused before any is built."""
    from ..program import Speeds

    return Speeds.parse(text, "rpm")


class OutsideRoot(ValueError):
    """A program names a file the studio may not read (HTTP 403)."""


@dataclasses.dataclass(frozen=True)
class FileAccess:
    """Which files a program posted to the studio may name: those under ``root`` (the folder
    the studio was started on) or under one of ``folders`` (the studio's designed laws), and
    the exact ``files`` the starting program names.  Paths are resolved (``..`` and symbolic
    links followed) before they are compared, and nothing is read here."""

    root: Path
    folders: tuple[Path, ...] = ()
    files: frozenset[Path] = frozenset()

    def check(self, data: dict, base: Path | None, *, relative: bool = True) -> None:
        """A one-line ``OutsideRoot`` naming the key of the first file reference outside;
        ``relative=False`` (a program opened in the page, whose own folder is unknown)
        refuses every relative reference."""
        for where, name in program_files(data):
            path = Path(name).expanduser()
            if not path.is_absolute():
                if not relative:
                    raise OutsideRoot(f"{where}: {name!r} is relative to the opened file's folder, which the "
                                      f"page cannot know; give its full path under {self.root}, or start "
                                      "camjax studio on the program file")
                path = (base or self.root) / path
            path = path.resolve()
            inside = any(path.is_relative_to(folder) for folder in (self.root, *self.folders))
            if not inside and path not in self.files:
                raise OutsideRoot(f"{where}: {name!r} is outside the studio's folder {self.root}; the studio "
                                  "reads only files under the folder it was started on")


def program_files(data: dict) -> list[tuple[str, str]]:
    """``(where, name)`` of every file a program's TOML structure names (``where`` as its
    errors say it: ``[program] file``, ``segment 2: law``)."""
    found = []
    header = data.get("program") if isinstance(data, dict) else None
    tables = [("[program]", header)] if isinstance(header, dict) else []
    segments = data.get("segment") if isinstance(data, dict) else None
    if isinstance(segments, list):
        tables += [(f"segment {i}:", s) for i, s in enumerate(segments, 1) if isinstance(s, dict)]
    for where, table in tables:
        for key in PROGRAM_FILE_KEYS:
            if isinstance(table.get(key), str):
                found.append((f"{where} {key}", table[key]))
        law = table.get("law")
        if isinstance(law, str) and law.endswith(".json"):
            found.append((f"{where} law", law))
    return found


class ReportCache:
    """Analyses shared by a studio's workbenches, keyed by program and speeds (oldest dropped
    first beyond ``size``); a second request for an analysis under way waits for it."""

    def __init__(self, size: int = CACHED_REPORTS):
        self.size = size
        self._lock = threading.Lock()
        self._done: dict = {}
        self._pending: dict = {}

    def __len__(self) -> int:
        return len(self._done)

    def get(self, key, compute):
        """The analysis of ``key``, from ``compute()`` when neither kept nor under way."""
        while True:
            with self._lock:
                hit = self._done.get(key)
                pending = None if hit is not None else self._pending.get(key)
                if hit is None and pending is None:
                    self._pending[key] = threading.Event()
            if hit is not None:
                return hit
            if pending is None:
                break
            pending.wait()  # another request analyses it: its answer is this one's
        try:
            hit = compute()
            with self._lock:
                self._done[key] = hit
                while len(self._done) > self.size:
                    self._done.pop(next(iter(self._done)))
        finally:
            with self._lock:
                self._pending.pop(key).set()
        return hit


def kinematics(program, theta_deg: np.ndarray) -> dict[str, np.ndarray]:
    """Lift and its first three derivatives in cam angle (mm/deg^k) at ``theta_deg``, from
    the program's turn (``Program.turn``)."""
    y, dy, ddy, jerk = program.turn.jet(theta_deg)
    return {"lift_mm": y, "velocity_mm_per_deg": dy, "acceleration_mm_per_deg2": ddy,
            "jerk_mm_per_deg3": jerk}


def rigid_contact_force_n(program, lift_mm: np.ndarray, acceleration_m_s2: np.ndarray) -> np.ndarray:
    """The contact force of a rigid follower train: ``F_0 + k_s y + m y''`` (docs/program.md,
    the limit ``k -> inf``); a grooved cam has no spring and no preload (``m y''``)."""
    f = program.follower
    preload = 0.0 if f.form_closed else f.preload_n  # a groove holds the follower: no spring, no preload
    return preload + f.spring_rate * 1e-3 * lift_mm + f.mass_kg * acceleration_m_s2


def _canonical(value):
    """A TOML structure with every number a float: ``8`` and ``8.0`` are the same lift."""
    if isinstance(value, dict):
        return {k: _canonical(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_canonical(v) for v in value]
    if isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


@dataclasses.dataclass
class Workbench:
    """A program being edited: its last good structure (``data``, as the TOML reader gives
    it and the page posts it), speeds, report and steady state."""

    data: dict
    rpm_text: str = DEFAULT_RPM
    base: Path | None = None
    with_flight: bool = True
    speed_fluctuation: float = DEFAULT_SPEED_FLUCTUATION
    program: object = None
    rpm: object = None  # camjax.program.Speeds
    report: dict | None = None
    steady: object = None
    warnings: list = dataclasses.field(default_factory=list)
    used: float = dataclasses.field(default_factory=time.monotonic)
    lock: threading.Lock = dataclasses.field(default_factory=threading.Lock, repr=False)
    cache: ReportCache = dataclasses.field(default_factory=ReportCache, repr=False)
    law_dir: Path | None = None
    job: DesignJob | None = None
    access: FileAccess | None = None
    """Which files a program may name (``None``: any, as the program API reads them)."""
    outputs: object = None
    """The per-speed outputs its reports hold (``camjax.program.Outputs``, or a list of
    probes beside the built-in ones); ``None``: the built-in ones."""

    def output_set(self):
        """The per-speed outputs its reports hold, as a ``camjax.program.Outputs``."""
        from ..program import Outputs

        return Outputs.of(self.outputs)

    def output_columns(self) -> list[dict]:
        """Name, label, unit, format and doc of every per-speed output (``GET /api/outputs``)."""
        return [p.as_dict() for p in self.output_set().values()]

    def touch(self) -> None:
        self.used = time.monotonic()

    def ensure(self) -> dict:
        """The report, computed on first need."""
        if self.report is None:
            self.update(self.data, self.rpm_text)
        return self.report

    @property
    def toml(self) -> str:
        """The last good program as TOML: ``Program.to_toml`` (the one writer of a program
        file), law files named as the structure names them."""
        self.ensure()
        return self.program.to_toml(law_files=law_file_names(self.data))

    def update(self, data: dict, rpm_text: str | None = None, *, opened: bool = False) -> dict:
        """Replace the program (its structure) and the speeds: the new report, or a
        ValueError that leaves the last good state as it was.  ``opened``: a file opened in
        the page, so a file it names relative to itself cannot be found (refused)."""
        rpm_text = self.rpm_text if rpm_text is None else str(rpm_text)
        rpm = parse_speeds(rpm_text)
        self.program, self.steady, self.report, self.warnings = self.analysed(data, rpm, opened=opened)
        self.data, self.rpm_text, self.rpm = data, rpm_text, rpm
        return self.report

    def analysed(self, data: dict, rpm, *, opened: bool = False) -> tuple:
        """``(program, steady state, report, warnings)`` of the structure ``data`` at
        ``rpm``, changing nothing.  The same program (the same structure, whole numbers and
        floats alike) at the same speeds and outputs (``output_set``) is analysed once per
        ``cache``."""
        from ..program import Program, analyse, program_motor_choice, steady_state

        if not isinstance(data, dict):
            raise ValueError(f"the program must be a table of tables, got {type(data).__name__}")
        if self.access is not None:
            self.access.check(data, self.base, relative=not opened)
        program = Program.from_dict(data, base=self.base)
        outputs = self.output_set()
        key = (json.dumps(_canonical(data), sort_keys=True, default=str), tuple(rpm.tolist()), self.with_flight,
               self.speed_fluctuation, str(self.base), outputs)

        def compute():
            relieve_memory_maps()  # a studio open all day compiles many programs
            steady = steady_state(program, rpm)  # a chain with lash or a seat: its simulation
            report = json_ready(analyse(program, rpm, with_flight=self.with_flight, steady=steady,
                                        speed_fluctuation=self.speed_fluctuation, outputs=outputs))
            if program.motors:  # a servo: the motor sizing at the same speeds (the page's motor panel)
                choice = program_motor_choice(program, rpm, steady=steady)
                # the shown motor's continuous stall torque: its RMS limit drawn as motor.png draws it
                report["motor"] = json_ready({**choice.shown_dict(),
                                              "continuous_stall_torque_n_m": choice.shown.continuous_stall_torque_n_m})
            # the segments each speed's residual_vibration_mm belongs to, in order (1-based):
            # the program's rule, not the page's
            report["residual_segments"] = [i + 1 for i in program.residual_segments()]
            # the objectives a design of this program takes: the library's rule, not the page's
            report["design_objectives"] = design_choices(program)
            return program, steady, report, list(report.get("warnings", ()))

        return self.cache.get(key, compute)

    def curves(self, rpm: float | None = None) -> dict:
        """Everything the page draws beside the report: the kinematics over the turn, the
        histories at ``rpm`` (default: ``plot_speed``'s choice), the profile."""
        from ..program import profile, response

        report = self.ensure()
        program = self.program
        lowest = self.rpm.min()
        if rpm is None:
            rpm = plot_speed(report, None)
        if not (isinstance(rpm, int | float) and math.isfinite(rpm) and rpm >= lowest):
            raise ValueError(f"rpm: the chosen speed must be at or above the lowest speed of the "
                             f"range ({lowest:g} rpm), got {rpm!r}")
        theta = np.linspace(0.0, 360.0, TURN_POINTS)
        try:
            with np.errstate(over="raise"):
                h = response(program, float(rpm), steady=self.steady)
        except (OverflowError, FloatingPointError):
            raise ValueError(f"rpm: {rpm:g} rpm is too fast to compute a turn at (a number overflows)") from None
        # the rigid follower's force is the one-body train's limit; a chain's stand-in mass is not its own
        h["rigid_contact_force_n"] = (rigid_contact_force_n(program, h["lift_mm"], h["kinematic_acceleration_m_s2"])
                                      if program.one_body else None)
        prof = profile(program, PROFILE_POINTS)
        f = program.follower
        return json_ready({
            "rpm": float(rpm),
            "kinematics": {"theta_deg": theta, **kinematics(program, theta)},
            "response": h,
            "profile": {"theta_deg": prof.theta_deg, "pitch": prof.pitch, "profile": prof.profile,
                        "outer": prof.outer if f.form_closed else None,
                        "flat_face": prof.flat_face},
            "follower": dataclasses.asdict(f) | {"form_closed": f.form_closed, "flat_face": f.flat_face,
                                                 "swinging": f.swinging},
            "warnings": self.warnings + ([f"follower.preload_n = {f.preload_n:g} N does nothing on a grooved cam "
                                          "(no spring_rate_n_per_mm): the groove holds the follower"]
                                         if f.form_closed and f.preload_n else []),
        })

    def state(self) -> dict:
        """The program as its structure (for the page's tables), its TOML text and the speeds,
        what an empty follower or ``[materials]`` field stands for, the fields the page
        edits (``fields``, from the program's own types); ``bundle``: whether it holds a
        designed law (saved as a zip with its law files)."""
        from .. import laws
        from ..program import Follower, Materials

        defaults = {f.name: f.default for f in dataclasses.fields(Follower) if f.default is not dataclasses.MISSING}
        materials = {f.name: f.default for f in dataclasses.fields(Materials)}
        designed = self.law_dir is not None and any(Path(name).is_relative_to(self.law_dir)
                                                    for name in law_file_names(self.data).values())
        return {"toml": self.toml, "program": self.data, "rpm": self.rpm_text,
                "laws": [*laws.names(), "constant-velocity", "polynomial"], "follower_defaults": defaults,
                "materials_defaults": materials, "fields": program_fields(), "bundle": designed,
                "design": {"steps": DESIGN_STEPS, "knots": DESIGN_KNOTS,
                           "objectives": design_choices(self.program)}}

    # -- designing a segment's law -------------------------------------------------------

    def start_design(self, segment: int, objective: str, rpm_lo: float, rpm_hi: float, *,
                     steps: int = DESIGN_STEPS, knots: int = DESIGN_KNOTS, rounds: int | None = None,
                     seating_speeds: int | None = None) -> dict:
        """Start designing segment ``segment``'s law (``camjax.program.design_segment``) on a
        background thread; its progress is ``self.job``.  ``rounds`` (default
        ``SEATING_ROUNDS``) and ``seating_speeds`` (default the library's) only with the
        seating objective.  A bad request, or an objective the program does not take
        (``camjax.program.design_refusal``), is a one-line ValueError before any work; a
        design already running is ``Busy``."""
        from .. import law_design
        from ..program import design_refusal, segment_band

        if self.job is not None and self.job.state == "running":
            raise Busy("a design is running: wait for it (GET /api/design) before starting another")
        self.ensure()
        if objective not in DESIGN_OBJECTIVES:
            raise ValueError(f"objective: must be one of {', '.join(DESIGN_OBJECTIVES)}, got {objective!r}")
        given = {name: value for name, value in (("rounds", rounds), ("seating_speeds", seating_speeds))
                 if value is not None}
        if given and objective != "seating":
            raise ValueError(f"{', '.join(given)}: only with objective 'seating', got {objective!r}")
        for name, value, most in (("steps", steps, law_design.MAX_STEPS), ("knots", knots, law_design.MAX_KNOTS),
                                  *((name, value, law_design.MAX_STEPS) for name, value in given.items())):
            if not 1 <= value <= most:
                raise ValueError(f"{name}: must be from 1 to {most:,}, got {value}")
        segment_band(self.program, segment, rpm_lo, rpm_hi)  # its one-line error names what is wrong
        refusal = design_refusal(self.program, objective)
        if refusal is not None:
            raise ValueError(refusal)
        options = {"rounds": SEATING_ROUNDS, **given} if objective == "seating" else {}
        job = self.job = DesignJob(segment, objective, float(rpm_lo), float(rpm_hi), steps, knots,
                                   data=self.data, rpm=self.rpm, before=self.report, options=options)
        threading.Thread(target=carried(self._design), args=(job, self.program), name="camjax-studio-design",
                         daemon=True).start()
        return job.as_dict()

    def _design(self, job: DesignJob, program) -> None:
        """The design thread: the law, then the designed program's report at the workbench's
        speeds (kept in the cache, so keeping the law answers at once)."""
        from .. import laws
        from ..errors import SolverError
        from ..program import design_segment

        def progress(step, total, loss):
            job.step, job.steps, job.loss = step, total, loss
            job.phase = "optimising" if step < total else "checking the law"

        try:
            new, result = design_segment(program, job.segment, job.rpm_lo, job.rpm_hi, objective=job.objective,
                                         steps=job.steps, knots=job.knots, progress=progress, **job.options)
            (job.label, job.after_value), = result.values.items()
            job.before_value, job.kept_initial = result.initial_values[job.label], result.kept_initial
            job.step = job.steps
            if not result.kept_initial:
                if self.law_dir is None:  # a workbench outside a studio: a folder of its own
                    self.law_dir = Path(tempfile.mkdtemp(prefix="camjax-studio-"))
                self.law_dir.mkdir(parents=True, exist_ok=True)
                path = self.law_dir / f"{_file_name(program.name)}-segment{job.segment}-{uuid.uuid4().hex[:8]}.json"
                laws.save(new.segments[job.segment - 1].law, path)
                job.designed = designed_data(job.data, new, job.segment, path, self.base)
                job.phase = "analysing the designed program"
                job.after = self.analysed(job.designed, job.rpm)[2]
            job.state, job.phase = "done", "done"
        except (ValueError, SolverError) as error:
            job.state, job.message = "error", str(error)
        except Exception as error:  # a fault of the studio itself: one line, the page lives on
            job.state, job.message = "error", f"{type(error).__name__}: {error}"
        job.seconds = time.monotonic() - job.started

    def keep_design(self) -> dict:
        """Replace the segment's law by the finished design's: the new report."""
        job = self._finished()
        if self.data != job.data:
            raise Busy("the program changed since the design started: design it again")
        job.state = "kept"
        return self.report if job.designed is None else self.update(job.designed)

    def discard_design(self) -> dict:
        """Forget the finished design; the program stays as it is."""
        self._finished().state = "discarded"
        return self.job.as_dict()

    def _finished(self) -> DesignJob:
        if self.job is None or self.job.state != "done":
            state = "none" if self.job is None else self.job.state
            why = {"none": "none was started", "running": "the design is running", "kept": "it was kept",
                   "discarded": "it was discarded", "error": "the design failed"}[state]
            raise (Busy if state == "running" else ValueError)(f"no finished design to keep or discard: {why}")
        return self.job


def designed_data(data: dict, program, segment: int, law_path: Path, base: Path | None) -> dict:
    """The structure of ``program`` (a design of segment ``segment`` of the program
    ``data``), as ``Program.to_toml`` writes it: the designed law by its file ``law_path``,
    any other law file by its full path (the program must stand where ``base`` is not its
    folder)."""
    files = {i: (Path(law) if base is None else (base / law).resolve()).as_posix()
             for i, law in law_file_names(data).items() if i != segment}
    return parse_toml(program.to_toml(law_files={**files, segment: law_path.as_posix()}))


ARM_EMPTY = {"length_mm": "the follower's arm_mm (the arm ends at the roller)"}
"""What an empty ``[arm]`` field whose default is ``None`` stands for, beside the library's
own defaults (``elements``: ``camjax.program.DEFAULT_ELEMENTS``)."""


def program_fields() -> dict:
    """The fields the page edits, from the program's own types: the follower's kinds
    (``camjax.program.follower_kinds``: each with its keys, whether it has a roller and
    whether it swings) and fields, the chain's
    body, spring and seat fields with their defaults (``required``: none), the
    ``[follower]`` fields a chain replaces, and the ``[arm]`` table's fields
    (``camjax.program.ARM_FIELDS``, in the order of ``Arm``'s; ``empty``: what an empty
    one stands for where its default is ``None``)."""
    from ..program import (
        ARM_FIELDS,
        CLASSIC_FIELDS,
        DEFAULT_ELEMENTS,
        Arm,
        Body,
        Follower,
        Seat,
        Spring,
        follower_kinds,
    )

    def fields(record, names=None) -> list[dict]:
        return [{"name": f.name, "required": f.default is dataclasses.MISSING,
                 "default": None if f.default is dataclasses.MISSING else f.default}
                for f in dataclasses.fields(record) if names is None or f.name in names]

    follower = [f.name for f in dataclasses.fields(Follower)]
    empty = {**ARM_EMPTY, "elements": f"{DEFAULT_ELEMENTS} over the length"}
    arm = [{**f, **({"empty": empty[f["name"]]} if f["name"] in empty else {})} for f in fields(Arm, ARM_FIELDS)]
    return {"follower_kinds": follower_kinds(),
            "follower": ["kind", *(name for name in follower if name != "kind")],
            "body": fields(Body), "spring": fields(Spring), "seat": fields(Seat),
            "chain_replaces": list(CLASSIC_FIELDS), "arm": arm}


def design_choices(program) -> list[dict]:
    """The page's objectives (``DESIGN_OBJECTIVES``) that ``program`` takes
    (``camjax.program.design_objectives``: the library's rule), as ``{name, label}``."""
    from ..program import design_objectives

    takes = design_objectives(program)
    return [{"name": name, "label": label} for name, label in DESIGN_OBJECTIVES.items() if name in takes]


def _file_name(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name) or "program"


def _speed_curves(report: dict | None) -> dict | None:
    """The speeds of a report, its minimum preload and its largest residual vibration at
    each, and for a chain with a seat the valve's seating velocity (m/s; ``None``
    elsewhere)."""
    if report is None:
        return None
    speeds = report["speeds"]
    contacts = (report.get("train") or {}).get("contacts")
    seated = contacts is not None and any(c["seating_velocity_m_s"] is not None for c in contacts["speeds"])
    return {"rpm": [s["rpm"] for s in speeds], "min_preload_n": [s["min_preload_n"] for s in speeds],
            "max_residual_mm": [max(s["residual_vibration_mm"]) if s["residual_vibration_mm"] else None
                                for s in speeds],
            "seating_velocity_m_s": [c["seating_velocity_m_s"] for c in contacts["speeds"]] if seated else None}


@dataclasses.dataclass
class DesignJob:
    """A design started from the page: what was asked, its progress and its outcome.

    ``state`` is ``running`` (``phase``: compiling, optimising, checking the law, analysing
    the designed program), ``done`` (to keep or discard), ``kept``, ``discarded`` or
    ``error`` (``message`` says why)."""

    segment: int
    objective: str
    rpm_lo: float
    rpm_hi: float
    steps: int
    knots: int
    data: dict | None = None  # the program's structure when it started
    options: dict = dataclasses.field(default_factory=dict)  # design_segment's further options
    rpm: object = None  # camjax.program.Speeds
    before: dict | None = None
    state: str = "running"
    phase: str = "compiling"
    step: int = 0
    loss: float | None = None
    label: str | None = None
    before_value: float | None = None
    after_value: float | None = None
    kept_initial: bool = False
    designed: dict | None = None  # the designed program's structure
    after: dict | None = None
    message: str | None = None
    started: float = dataclasses.field(default_factory=time.monotonic)
    seconds: float | None = None

    def as_dict(self) -> dict:
        done = self.state in ("done", "kept", "discarded")
        return json_ready({
            "state": self.state, "phase": self.phase, "step": self.step, "steps": self.steps, "loss": self.loss,
            "segment": self.segment, "objective": self.objective, "rpm": [self.rpm_lo, self.rpm_hi],
            "knots": self.knots, "label": self.label, "before": self.before_value, "after": self.after_value,
            "kept_initial": self.kept_initial, "message": self.message,
            "seconds": time.monotonic() - self.started if self.seconds is None else self.seconds,
            "curves": {"before": _speed_curves(self.before),
                       "after": _speed_curves(self.after if self.after is not None or not done else self.before)}
            if done else None,
        })
