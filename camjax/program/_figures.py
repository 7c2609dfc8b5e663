"""Figures of a cam program: one turn at one speed, the speed sweep, the profile."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import plot
from ._export import Profile
from ._program import Program

plt = plot.plt


def svaj(program: Program, rpm: float, history: dict) -> plt.Figure:
    """Lift, velocity, kinematic and payload acceleration over one turn."""
    theta = history["theta_deg"]
    _, dy, _ = program.lift(theta)
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True, constrained_layout=True)
    axes[0].plot(theta, history["lift_mm"])
    axes[0].set_ylabel("lift y (mm)")
    axes[1].plot(theta, 1e-3 * dy * 360 * rpm / 60)
    axes[1].set_ylabel("velocity y' (m/s)")
    axes[2].plot(theta, history["kinematic_acceleration_m_s2"], lw=1, label="cam y''")
    last = "payload" if program.chain is None else program.chain.names[-1]
    axes[2].plot(theta, history["payload_acceleration_m_s2"], lw=1, label=f"{last} x''")
    axes[2].set_ylabel("acceleration (m/s^2)")
    axes[2].legend(fontsize=8)
    axes[2].set_xlabel("cam angle (deg)")
    axes[0].set_title(f"{program.name} at {rpm:g} rpm (periodic steady state)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return fig


def contact_force(program: Program, rpm: float, history: dict, groove=None) -> plt.Figure:
    """Contact force over one turn, with the zero line and the preload (a spring-loaded
    cam); for a grooved cam with clearance, the force with the clearance (``groove``, a
    ``GrooveTurn``) and its strikes beside the contact-held one."""
    fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
    f = program.follower
    ax.axhline(0.0, color="k", lw=0.8)
    if groove is not None:
        ax.plot(history["theta_deg"], history["contact_force_n"], lw=0.8, ls="--", color="0.5",
                label="contact held (no clearance)")
        ax.plot(groove.theta_deg, groove.force_n, lw=1, color="C0",
                label=f"with the groove's clearance {f.groove_clearance_mm:g} mm")
        for i, impact in enumerate(groove.impacts):
            ax.axvline(impact.angle_deg, color="C3", lw=0.6, ls=":", label="strikes" if i == 0 else None)
        ax.set_ylabel("flank force (N, + inner flank)")
        what = "grooved cam"
    else:
        ax.plot(history["theta_deg"], history["contact_force_n"], lw=1,
                label="flank force" if f.form_closed else "contact force")
        static = _static_cam_force(program)
        if static is not None:
            ax.axhline(static, color="C1", lw=0.8, ls="--",
                       label="preload" if program.chain is None else "preload through the levers")
        ax.set_ylabel("flank force (N, + inner flank)" if f.form_closed else "contact force (N)")
        simulated = program.chain is not None and program.chain.has_contacts
        what = ("form-closed, contact held" if f.form_closed else "simulated with its contacts" if simulated
                else "periodic steady state")
    ax.set_xlabel("cam angle (deg)")
    ax.set_title(f"{program.name}: contact force at {rpm:g} rpm ({what})")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig


def _static_cam_force(program: Program) -> float | None:
    """The force at the cam at rest (the preload, through a chain's levers), or ``None``:
    a form-closed cam, or a chain on its seat (which carries the preload at rest)."""
    chain = program.chain
    if program.follower.form_closed or (chain is not None and chain.seat is not None):
        return None
    return program.follower.preload_n if chain is None else chain.cam_preload_n


def _values(speeds, name: str) -> np.ndarray:
    """An output over the speeds, NaN where it is not given."""
    return np.array([np.nan if getattr(s, name) is None else getattr(s, name) for s in speeds], dtype=float)


def sweep(program: Program, report) -> plt.Figure:
    """Against speed (a ``Report``): the preload needed, with the preload fitted and the
    jump speed (a spring-loaded cam), or the flank forces (a form-closed one), or the
    contact force (a chain with a seat, whose least preload is not given); peak
    accelerations."""
    speeds = report.speeds
    rpm = [s.rpm for s in speeds]
    jump = report.jump_speed_rpm
    fig, (a, b) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, constrained_layout=True)
    closed = program.follower.form_closed
    simulated = program.chain is not None and program.chain.has_contacts
    if closed or all(s.min_preload_n is None for s in speeds):  # a form-closed cam, a seated chain
        a.plot(rpm, [s.max_contact_force_n for s in speeds], marker=".",
               label="max (inner flank)" if closed else "max")
        # a simulated contact pushes only (its least force is 0 whether it separates or just
        # unloads): the speeds where it separates are marked instead
        a.plot(rpm, [s.min_contact_force_n for s in speeds], marker=".",
               label="min (outer flank < 0)" if closed else "min" if simulated else "min (< 0: the cam separates)")
        if simulated:
            apart = [(s.rpm, s.min_contact_force_n) for s in speeds if s.jump]
            if apart:
                a.plot(*zip(*apart), ls="none", marker="x", color="C3", ms=8, label="the cam separates")
        a.axhline(0.0, color="k", lw=0.8)
        a.set_ylabel("flank force, contact held (N)" if closed else "contact force at the cam (N)")
        a.legend(fontsize=8)
    if not closed:
        if not all(s.min_preload_n is None for s in speeds):
            a.plot(rpm, _values(speeds, "min_preload_n"), marker=".", label="preload needed")
            a.axhline(program.follower.preload_n, color="C1", lw=0.8, ls="--", label="preload fitted")
            a.set_ylabel("preload needed (N)")
        if jump is not None:
            for ax in (a, b):
                ax.axvline(jump, color="C3", lw=0.8)
            a.annotate(f"jump {jump:.0f} rpm", (jump, 0.0),
                       xytext=(4, 4), textcoords="offset points", fontsize=8, color="C3")
        a.legend(fontsize=8)
    a.set_title(f"{program.name}: {'simulated' if simulated else 'periodic steady state'} against speed")
    last = "payload" if program.chain is None else program.chain.names[-1]
    b.plot(rpm, _values(speeds, "max_payload_acceleration_m_s2"), marker=".", label=last)
    b.plot(rpm, [s.max_kinematic_acceleration_m_s2 for s in speeds], marker=".", label="cam (kinematic)")
    b.set_ylabel("max |acceleration| (m/s^2)")
    b.set_xlabel("speed (rpm)")
    b.legend(fontsize=8)
    for ax in (a, b):
        ax.grid(True, alpha=0.3)
    return fig


def cam(prof: Profile, name: str = "") -> plt.Figure:
    """The profile and pitch curve, with the pressure angle and radius of curvature."""
    fig = plt.figure(figsize=(11, 5), constrained_layout=True)
    fig.suptitle(f"{name}: cam profile" if name else "cam profile")
    ax = fig.add_subplot(1, 2, 1)
    ax.plot(*prof.pitch.T, lw=0.8, ls="--", label="pitch curve")
    ax.plot(*prof.profile.T, lw=1.2, label="profile")
    ax.set_aspect("equal")
    ax.set_xlabel("mm")
    ax.legend(fontsize=8)
    right = fig.add_subplot(2, 2, 2)
    right.plot(prof.theta_deg, prof.pressure_angle_deg)
    right.set_ylabel("pressure angle (deg)")
    low = fig.add_subplot(2, 2, 4, sharex=right)
    rho = np.clip(prof.profile_radius_of_curvature_mm, -500, 500)
    low.plot(prof.theta_deg, rho)
    low.set_ylabel("profile radius of curvature (mm)")
    low.set_xlabel("cam angle (deg)")
    for a in (right, low):
        a.grid(True, alpha=0.3)
    return fig


def over_turn(title: str, key: str, label: str, histories: list[tuple[float, dict]]) -> plt.Figure:
    """One history (``response`` key) over the turn at up to four speeds."""
    fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
    for rpm, h in histories[:4]:
        ax.plot(h["theta_deg"], h[key], lw=1, label=f"{rpm:g} rpm")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel("cam angle (deg)")
    ax.set_ylabel(label)
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig


def torque_sweep(speeds, title: str) -> plt.Figure:
    """Peak and RMS drive torque against speed (``SpeedReport``s or ``ShaftSpeedReport``s)."""
    fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
    rpm = [s.rpm for s in speeds]
    ax.plot(rpm, [s.max_drive_torque_n_m for s in speeds], marker=".", label="peak |T|")
    ax.plot(rpm, [s.rms_drive_torque_n_m for s in speeds], marker=".", label="RMS T")
    ax.set_xlabel("speed (rpm)")
    ax.set_ylabel("drive torque (N m)")
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig


def train_turn(program: Program, rpm: float, history: dict) -> plt.Figure:
    """A chain over one turn (``response``): the contact force at the cam (and the valve's
    seat force), the last body against its kinematic lift and its distance from it, and
    every body's acceleration."""
    chain = program.chain
    theta = history["theta_deg"]
    last = chain.names[-1]
    fig, axes = plt.subplots(4, 1, figsize=(8, 10), sharex=True, constrained_layout=True)
    a = axes[0]
    a.plot(theta, history["contact_force_n"], lw=1, label="at the cam")
    if "seat_contact_force_n" in history:
        a.plot(theta, history["seat_contact_force_n"], lw=0.8, color="C2", label=f"{last} on its seat")
    a.axhline(0.0, color="k", lw=0.8)
    a.set_ylabel("contact force (N)")
    a.legend(fontsize=8)
    b = axes[1]
    ratio = chain.lever_ratio
    kinematic = ratio * np.asarray(history["lift_mm"])
    b.plot(theta, kinematic, lw=0.8, ls="--", color="0.4",
           label="kinematic lift" + ("" if ratio == 1 else f" ({ratio:g} y)"))
    b.plot(theta, history[f"{last}_displacement_mm"], lw=1, color="C0", label=last)
    b.set_ylabel(f"{last} displacement (mm)")
    b.legend(fontsize=8)
    c = axes[2]
    c.plot(theta, history["lift_error_mm"], lw=1, color="C3")
    c.axhline(0.0, color="k", lw=0.8)
    c.set_ylabel(f"{last} less kinematic (mm)")
    d = axes[3]
    for name in chain.names:
        d.plot(theta, history[f"{name}_acceleration_m_s2"], lw=0.8, label=name)
    d.set_ylabel("acceleration (m/s^2)")
    d.set_xlabel("cam angle (deg)")
    d.legend(fontsize=8)
    simulated = "simulated with its contacts" if chain.has_contacts else "periodic steady state"
    a.set_title(f"{program.name}: the train at {rpm:g} rpm ({simulated})")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return fig


def _stagger(ax, positions: list[int]) -> None:
    """Drop every other name of neighbouring coordinates (one apart) a line lower, so that the
    bodies' names along the chain do not run into each other."""
    lower = False
    for k, tick in enumerate(ax.xaxis.get_major_ticks()):
        lower = k > 0 and positions[k] - positions[k - 1] <= 1 and not lower
        if lower:
            tick.set_pad(tick.get_pad() + 1.2 * tick.label1.get_fontsize())


def modes(program: Program, shown: int = 4) -> plt.Figure:
    """The chain's first ``shown`` undamped modes, the cam held and free, each labelled with
    its frequency: their shapes along the chain from the cam through the bodies and the
    return spring's coils to its seat (``Chain.coordinate_modes``; over the bodies alone
    on a flexible arm, whose coordinates are the arm's own)."""
    chain = program.chain
    fig, axes = plt.subplots(1, 2, figsize=(11, 5), sharey=True, constrained_layout=True)
    for ax, contact, what in ((axes[0], True, "cam held"), (axes[1], False, "cam free (in flight)")):
        if chain.arm is None:
            hz, shapes, a = chain.coordinate_modes(contact=contact)
            ticks = {0: "cam", **dict(zip(a.body_index.tolist(), chain.names)), a.seat: "spring seat"}
            coils = a.seat - 1 - int(a.body_index[-1])
            ax.set_xlabel("along the chain" + (f" (the spring's {coils} inner coil nodes between "
                                                f"{chain.names[-1]} and its seat)" if coils else ""),
                          fontsize=9)
        else:
            hz, shapes = chain.natural_frequencies(contact=contact)
            ticks = dict(enumerate(chain.names))
            ax.set_xlabel("body (from the cam; the arm's own bending between them is not drawn)", fontsize=9)
        for i in range(min(shown, hz.size)):
            ax.plot(np.arange(shapes.shape[0]), shapes[:, i], marker="o", ms=3, lw=1,
                    label=f"mode {i + 1}: {hz[i]:.4g} Hz")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xticks(list(ticks), list(ticks.values()))
        _stagger(ax, list(ticks))
        ax.set_title(f"{what}: {hz.size} mode{'s' if hz.size != 1 else ''}"
                     + (f", first {shown} shown" if hz.size > shown else ""),
                     fontsize=10)
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2)  # below: the shapes fill the axes
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("mode shape (largest motion 1)")
    closed = " (the closed chain: lash taken up, off its seat)" if chain.has_contacts else ""
    fig.suptitle(f"{program.name}: the train's natural modes{closed}")
    return fig


def seat_force(program: Program, rpm: float, history: dict, histories: list[tuple[float, dict]]) -> plt.Figure:
    """The return spring's force at its seat over the turn at ``rpm`` with its static force
    ``F_0 + k_s x_N``, and its surge (the difference) at ``rpm`` and up to three of the
    fastest other ``histories``; a spring without mass does not surge: its force at those
    speeds alone."""
    theta = history["theta_deg"]
    others = sorted((item for item in histories if item[0] != rpm), key=lambda item: item[0])[-3:]
    shown = sorted([*others, (rpm, history)], key=lambda item: item[0])
    if not program.chain.spring.surges:
        fig, a = plt.subplots(figsize=(8, 4), constrained_layout=True)
        for r, h in shown:
            a.plot(h["theta_deg"], h["seat_force_n"], lw=1.4 if r == rpm else 0.8, label=f"{r:g} rpm")
        a.set_ylabel("spring force at its seat (N)")
        a.set_xlabel("cam angle (deg)")
        a.set_title(f"{program.name}: the return spring at its seat (without mass: F_0 + k_s x, no surge)")
        a.legend(fontsize=8)
        a.grid(True, alpha=0.3)
        return fig
    fig, (a, b) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, constrained_layout=True)
    force = np.asarray(history["seat_force_n"])
    a.plot(theta, force - np.asarray(history["surge_n"]), lw=0.8, ls="--", color="0.4",
           label=f"static F_0 + k_s x ({program.chain.names[-1]})")
    a.plot(theta, force, lw=1, color="C0", label=f"at {rpm:g} rpm")
    a.set_ylabel("spring force at its seat (N)")
    a.set_title(f"{program.name}: the return spring at its seat")
    a.legend(fontsize=8)
    for r, h in shown:
        b.plot(h["theta_deg"], h["surge_n"], lw=1.4 if r == rpm else 0.8, label=f"{r:g} rpm")
    b.axhline(0.0, color="k", lw=0.8)
    b.set_ylabel("surge: dynamic less static (N)")
    b.set_xlabel("cam angle (deg)")
    b.legend(fontsize=8)
    for ax in (a, b):
        ax.grid(True, alpha=0.3)
    return fig


def train_sweep(program: Program, train: dict) -> plt.Figure:
    """Against speed (the report's ``train`` section): each body's peak acceleration, the
    spring's least and largest seat force and its largest surge (a spring with mass)."""
    speeds = train["speeds"]
    rpm = [s["rpm"] for s in speeds]
    sprung = program.chain.spring is not None  # form-closed without: no seat force to draw
    surges = sprung and program.chain.spring.surges
    panels = 1 + sprung + surges
    fig, axes = plt.subplots(panels, 1, figsize=(8, 2 + 2 * panels), sharex=True, constrained_layout=True,
                             squeeze=False)
    axes = axes[:, 0]
    a = axes[0]
    for name in train["bodies"]:
        a.plot(rpm, [s["max_acceleration_m_s2"][name] for s in speeds], marker=".", label=name)
    a.set_ylabel("max |acceleration| (m/s^2)")
    a.set_title(f"{program.name}: the train against speed")
    a.legend(fontsize=8)
    if sprung:
        b = axes[1]
        b.plot(rpm, [s["max_seat_force_n"] for s in speeds], marker=".", label="max seat force")
        b.plot(rpm, [s["min_seat_force_n"] for s in speeds], marker=".", label="min seat force")
        b.set_ylabel("spring force at its seat (N)")
        b.legend(fontsize=8)
    if surges:
        axes[2].plot(rpm, [s["max_surge_n"] for s in speeds], marker=".", color="C2")
        axes[2].set_ylabel("max |surge| (N)")
    axes[-1].set_xlabel("speed (rpm)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if train["jump_speed_rpm"] is not None:
            ax.axvline(train["jump_speed_rpm"], color="C3", lw=0.8)
    return fig


def save_figures(out: Path, program: Program, report, history: tuple, prof: Profile,
                 *, histories: list[tuple[float, dict]] = (), groove=None) -> None:
    """The figures of ``camjax program --out`` for a ``Report``: svaj and contact force of the turn
    ``history`` (``(rpm, response)``; ``groove`` that speed's ``GrooveTurn`` for a grooved
    cam), drive torque (and contact stress) over the turn at up to four of ``histories``
    (where the response has them: not a chain with lash or a seat), the sweeps against
    speed, the profile; for a chain (``Program.chain``) the train over the turn, its modes,
    the spring's seat force and surge, and the train against speed."""
    rpm, h = history
    histories = list(histories) or [history]
    plot.save(svaj(program, rpm, h), out / "svaj.png")
    plot.save(contact_force(program, rpm, h, groove), out / "contact_force.png")
    if "drive_torque_n_m" in h:
        plot.save(over_turn(f"{program.name}: drive torque T = F_c dy/dtheta", "drive_torque_n_m",
                            "drive torque (N m)", histories), out / "drive_torque.png")
    if program.follower.contact_width_mm is not None and "contact_stress_mpa" in h:
        plot.save(over_turn(f"{program.name}: Hertz contact stress", "contact_stress_mpa",
                            "contact stress (MPa)", histories), out / "contact_stress.png")
    if len(report.speeds) > 1:
        plot.save(sweep(program, report), out / "sweep.png")
        if not all(s.max_drive_torque_n_m is None for s in report.speeds):
            plot.save(torque_sweep(report.speeds, f"{program.name}: drive torque"), out / "torque_sweep.png")
    if program.chain is not None:
        plot.save(train_turn(program, rpm, h), out / "train.png")
        plot.save(modes(program), out / "modes.png")
        if program.chain.spring is not None:
            plot.save(seat_force(program, rpm, h, histories), out / "seat_force.png")
        if len(report.speeds) > 1:
            plot.save(train_sweep(program, report.train), out / "train_sweep.png")
    plot.save(cam(prof, program.name), out / "profile.png")


def shaft_figures(out: Path, machine, report, rpm) -> None:
    """The shaft's torque over the turn at up to four speeds, and against speed (a ``MachineReport``)."""
    from ._dynamics import SteadyState
    from ._machine import shaft_torque
    from ._speeds import Speeds

    rpm = Speeds.of(rpm)
    steadies = [SteadyState(p, rpm) for p, _ in machine.cams]
    histories = []
    for r in list(rpm)[:4]:
        nodes, values, _, _ = shaft_torque([s.cycle(r) for s in steadies], [s.grid.nodes for s in steadies],
                                           [phase for _, phase in machine.cams])
        histories.append((float(r), {"theta_deg": 360.0 * nodes, "drive_torque_n_m": values}))
    plot.save(over_turn(f"{machine.name}: shaft torque", "drive_torque_n_m", "drive torque (N m)", histories),
              out / "shaft_torque.png")
    if len(report.shaft) > 1:
        plot.save(torque_sweep(report.shaft, f"{machine.name}: shaft torque"),
                  out / "shaft_torque_sweep.png")


def motor_figure(sizings, path) -> Path:
    """The motor's (speed, torque) points over one turn, dynamic and rigid, over its
    torque-speed envelope, one colour per master speed (``MotorSizing`` of each); saved to
    ``path``."""
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    motor = sizings[0].motor
    if motor.envelope is not None:
        envelope = np.asarray(motor.envelope)
    else:
        envelope = np.array([[0.0, motor.maximum_torque_n_m], [motor.maximum_speed_rpm, motor.maximum_torque_n_m]])
    for sign in (1, -1):
        ax.plot(sign * envelope[:, 0], envelope[:, 1], "k-", lw=1.5, label="envelope" if sign == 1 else None)
        ax.plot(sign * envelope[:, 0], -envelope[:, 1], "k-", lw=1.5)
    ax.axhline(sizings[0].rms_share_limit * motor.continuous_stall_torque_n_m, color="k", ls=":", lw=1,
               label=f"{100 * sizings[0].rms_share_limit:g}% of continuous stall torque")
    for s in sizings:
        line, = ax.plot(s.dynamic.speed_rpm, s.dynamic.torque_n_m, ".", ms=3, label=f"{s.rpm:g} rpm dynamic")
        ax.plot(s.rigid.speed_rpm, s.rigid.torque_n_m, "-", lw=0.8, color=line.get_color(), alpha=0.6,
                label=f"{s.rpm:g} rpm rigid")
        ax.plot([0], [s.dynamic.rms_torque_n_m], "s", color=line.get_color(), label=f"{s.rpm:g} rpm RMS")
    ax.set_xlabel("motor speed (rpm)")
    ax.set_ylabel("motor torque (N m)")
    ax.set_title(f"motor {motor.name}: torque against speed over one turn")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    path = Path(path)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
