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
    axes[2].plot(theta, history["payload_acceleration_m_s2"], lw=1, label="payload x''")
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
        if not f.form_closed:
            ax.axhline(f.preload_n, color="C1", lw=0.8, ls="--", label="preload")
        ax.set_ylabel("flank force (N, + inner flank)" if f.form_closed else "contact force (N)")
        what = "form-closed, contact held" if f.form_closed else "periodic steady state"
    ax.set_xlabel("cam angle (deg)")
    ax.set_title(f"{program.name}: contact force at {rpm:g} rpm ({what})")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig


def sweep(program: Program, report) -> plt.Figure:
    """Against speed (a ``Report``): the preload needed, with the preload fitted and the
    jump speed (a spring-loaded cam), or the flank forces (a form-closed one); peak
    accelerations."""
    speeds = report.speeds
    rpm = [s.rpm for s in speeds]
    jump = report.jump_speed_rpm
    fig, (a, b) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, constrained_layout=True)
    if program.follower.form_closed:
        a.plot(rpm, [s.max_contact_force_n for s in speeds], marker=".", label="max (inner flank)")
        a.plot(rpm, [s.min_contact_force_n for s in speeds], marker=".", label="min (outer flank < 0)")
        a.axhline(0.0, color="k", lw=0.8)
        a.set_ylabel("flank force, contact held (N)")
        a.legend(fontsize=8)
    else:
        a.plot(rpm, [s.min_preload_n for s in speeds], marker=".", label="preload needed")
        a.axhline(program.follower.preload_n, color="C1", lw=0.8, ls="--", label="preload fitted")
        if jump is not None:
            for ax in (a, b):
                ax.axvline(jump, color="C3", lw=0.8)
            a.annotate(f"jump {jump:.0f} rpm", (jump, 0.0),
                       xytext=(4, 4), textcoords="offset points", fontsize=8, color="C3")
        a.set_ylabel("preload needed (N)")
        a.legend(fontsize=8)
    a.set_title(f"{program.name}: periodic steady state against speed")
    b.plot(rpm, [s.max_payload_acceleration_m_s2 for s in speeds], marker=".", label="payload")
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


def save_figures(out: Path, program: Program, report, history: tuple, prof: Profile,
                 *, histories: list[tuple[float, dict]] = (), groove=None) -> None:
    """The figures of ``camjax program --out`` for a ``Report``: svaj and contact force of the turn
    ``history`` (``(rpm, response)``; ``groove`` that speed's ``GrooveTurn`` for a grooved
    cam), drive torque (and contact stress) over the turn at up to four of ``histories``,
    the sweeps against speed, the profile."""
    rpm, h = history
    histories = list(histories) or [history]
    plot.save(svaj(program, rpm, h), out / "svaj.png")
    plot.save(contact_force(program, rpm, h, groove), out / "contact_force.png")
    plot.save(over_turn(f"{program.name}: drive torque T = F_c dy/dtheta", "drive_torque_n_m",
                        "drive torque (N m)", histories), out / "drive_torque.png")
    if program.follower.contact_width_mm is not None:
        plot.save(over_turn(f"{program.name}: Hertz contact stress", "contact_stress_mpa",
                            "contact stress (MPa)", histories), out / "contact_stress.png")
    if len(report.speeds) > 1:
        plot.save(sweep(program, report), out / "sweep.png")
        plot.save(torque_sweep(report.speeds, f"{program.name}: drive torque"), out / "torque_sweep.png")
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
