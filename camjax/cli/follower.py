"""``camjax follower``: swinging roller follower with a flexible rod, three cam turns.

Prints the rod's fundamental frequency and the spectral peaks of the transverse deflection
(mid-rod) and the axial deflection (roller end) at the odd harmonics 1..9 Omega and near the
fundamental, with the largest constraint drift of the run.
"""

from __future__ import annotations

import math
import sys

from ._common import (
    LAW_HELP,
    CliError,
    add_format,
    dump_json,
    law_of,
    options_named,
    output_dir,
)

_TURNS = 3


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "follower",
        help="flexible swinging roller follower: deflection spectra",
        description=__doc__.replace("``", ""),
    )
    parser.add_argument("--law", required=True, metavar="NAME",
                        help=f"rise and fall law: {LAW_HELP}")
    parser.add_argument("--omega", type=float, default=320.0, help="cam speed, rad/s (default 320)")
    parser.add_argument("--length", type=float, default=98.0, help="rod length l, mm (default 98)")
    parser.add_argument("--radius", type=float, default=5.0, help="rod section radius, mm (default 5)")
    parser.add_argument("--roller-mass", type=float, default=25.0, help="roller mass, g (default 25)")
    parser.add_argument("--rise", type=float, default=math.pi / 18, help="total swing phi_T, rad (default pi/18)")
    parser.add_argument("--modes", type=int, default=3, help="assumed modes per direction N (default 3)")
    parser.add_argument(
        "--axial-modes",
        type=int,
        default=None,
        help="axial assumed modes (default N); 1 treats the stiff axial sin modes quasi-statically (about 3x faster)",
    )
    add_format(parser, ("table", "json"))
    parser.add_argument("--out", help="directory for follower.json and follower.csv (time history)")
    parser.set_defaults(func=run)


def _model(args):
    from ..models import SwingingFollower

    law = law_of(args.law, tool="camjax follower")
    for name in ("omega", "length", "radius", "roller_mass", "rise"):
        value = getattr(args, name)
        if not (math.isfinite(value) and value > 0):
            raise CliError(f"--{name.replace('_', '-')}: must be a positive number, got {value}")
    with options_named(total_swing="--rise", modes="--modes", axial_modes="--axial-modes",
                       rod_radius="--radius"):
        return SwingingFollower(
            rise=law,
            fall=law,
            omega=args.omega,
            length=args.length * 1e-3,
            rod_radius=args.radius * 1e-3,
            roller_mass=args.roller_mass * 1e-3,
            total_swing=args.rise,
            modes=args.modes,
            axial_modes=args.axial_modes,
        )


def follower_report(model, law_name: str) -> tuple[dict, object]:
    """The JSON-ready report of one three-turn run (a ``SwingingFollower``), and the response."""
    from concurrent.futures import ThreadPoolExecutor

    import numpy as np

    from ..caches import carried
    from ..models import solve, spectral_peaks, spectrum, trace_solve

    # The solve is traced first (Python holds the GIL); its compile then releases the GIL,
    # and the natural frequency's program is traced and compiled beside it on a thread.
    trace_solve(None, model, turns=_TURNS)
    with ThreadPoolExecutor(1) as pool:
        fundamental = pool.submit(carried(model.fundamental_frequency))
        response = solve(None, model, turns=_TURNS)
        natural = float(fundamental.result())
    order = natural / float(model.omega)
    report = {
        "law": law_name,
        "omega_rad_s": float(model.omega),
        "length_mm": float(model.length) * 1e3,
        "radius_mm": float(model.rod_radius) * 1e3,
        "roller_mass_g": float(model.roller_mass) * 1e3,
        "total_swing_rad": float(model.total_swing),
        "modes": model.modes,
        "axial_modes": model.n_axial,
        "natural_frequency_rad_s": natural,
        "natural_order": order,
    }
    for key, signal in (("transverse_peaks", response.transverse), ("axial_peaks", response.axial_end)):
        harmonics, near = spectral_peaks(spectrum(np.asarray(signal) * 1e3, _TURNS), order)
        report[key] = [{"order": o, "amplitude_mm": a} for o, a in harmonics + [near]]
    report["max_transverse_mm"] = float(np.max(np.abs(response.transverse))) * 1e3
    report["max_axial_mm"] = float(np.max(np.abs(response.axial_end))) * 1e3
    report["max_constraint_error"] = float(response.max_constraint_error)
    report["steps"] = int(response.stats["steps"])
    return report, response


def run(args) -> int:
    import numpy as np

    model = _model(args)
    out = output_dir(args.out)
    report, response = follower_report(model, args.law)
    deflection = max(report["max_transverse_mm"], report["max_axial_mm"])
    if deflection > report["radius_mm"]:  # the assumed-modes beam is a small-deflection model
        print(f"warning: the rod deflects by {deflection:.3g} mm, more than its radius "
              f"({report['radius_mm']:g} mm): far outside the small-deflection beam model; lower "
              "--omega or stiffen the rod (--radius, --length)", file=sys.stderr)
    if out is not None:
        dump_json(report, out / "follower.json")
        table = np.column_stack(
            [np.asarray(response.cam_angle), np.asarray(response.transverse) * 1e3, np.asarray(response.axial_end) * 1e3]
        )
        np.savetxt(out / "follower.csv", table, delimiter=",", header="cam_angle_rad,transverse_mm,axial_end_mm", comments="")
    if args.format == "json":
        print(dump_json(report))
        return 0
    print(f"law {report['law']}, omega {report['omega_rad_s']:g} rad/s, N = {report['modes']}")
    print(f"fundamental natural frequency {report['natural_frequency_rad_s']:.1f} rad/s = {report['natural_order']:.2f} Omega")
    print(f"{'order':>8} {'transverse mm':>14} {'axial mm':>12}")
    for t, a in zip(report["transverse_peaks"], report["axial_peaks"]):
        print(f"{t['order']:8.2f} {t['amplitude_mm']:14.4e} {a['amplitude_mm']:12.4e}")
    print(f"max constraint error {report['max_constraint_error']:.2e} m, {report['steps']} steps")
    return 0
