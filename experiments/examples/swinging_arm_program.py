"""The paper's flexible swinging rod on a whole cam: its tables through the program file.

    python experiments/examples/swinging_arm_program.py [--sets base,omega640,...] [--laws cycloidal,...]
        [--elements N] [--csv PATH]

Reads camjax/program/examples/trains/swinging_arm.toml (the paper's cam and rod), varies it
as the paper's parameter study does (speed, rod length and radius, roller mass, total swing)
and four laws, and compares the arm's first bending frequency and the cam-order harmonics
of its mid-rod bending (the exact periodic steady state of the linear chain) with the
full differential-algebraic model's spectral peaks (results/swinging_follower/peaks.csv,
camjax.models.SwingingFollower, three turns from rest).  Writes
results/swinging_follower/arm_program.csv and docs/swinging-arm.png.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from camjax.program import Program, analyse, example_path  # noqa: E402

LAWS = {
    "cycloidal": "cycloidal",
    "modified sine": "modified-sine",
    "modified trapezoid": "modified-trapezoid",
    "3-4-5": "poly345",
}
SETS = {
    "base": {},
    "omega640": {"omega": 640.0},
    "length118": {"length_mm": 118.0},
    "radius6": {"radius_mm": 6.0},
    "radius10": {"radius_mm": 10.0},
    "roller10g": {"roller_kg": 0.010},
    "roller100g": {"roller_kg": 0.100},
    "rise_pi12": {"swing": math.pi / 12},
}
STEEL_E, STEEL_RHO = 210e9, 7800.0
FULL_MODEL = Path("results/swinging_follower/peaks.csv")
OUT = Path("results/swinging_follower/arm_program.csv")
FIGURE = Path("docs/swinging-arm.png")


def paper_program(
    law="cycloidal",
    *,
    length_mm=98.0,
    radius_mm=5.0,
    roller_kg=0.025,
    swing=math.pi / 18,
    elements=None,
    **_,
):
    """The program file's cam and rod with the paper's parameters changed."""
    data = tomllib.loads(example_path("swinging_arm").read_text())
    lift = length_mm * swing
    for segment, sign in zip(data["segment"][::2], (1, -1)):
        segment["law"], segment["lift_mm"] = law, sign * lift
    follower = data["follower"]
    follower["arm_mm"] = length_mm
    follower["pivot_mm"] = math.hypot(
        length_mm, follower["base_radius_mm"] + follower["roller_radius_mm"]
    )
    r = 1e-3 * radius_mm
    area, second = math.pi * r * r, math.pi * r**4 / 4
    data["arm"].update(
        bending_stiffness_n_m2=STEEL_E * second,
        mass_per_length_kg_per_m=STEEL_RHO * area,
        rotary_inertia_kg_m=STEEL_RHO * second,
    )
    if elements is not None:
        data["arm"]["elements"] = elements
    data["train"][0]["mass_kg"] = roller_kg
    data["train"][1]["at_mm"] = length_mm / 2
    return Program.from_dict(data)


def rpm_of(omega):
    return omega * 60.0 / (2 * math.pi)


def full_model_table():
    with FULL_MODEL.open() as f:
        return {(r["set"], r["law"]): r for r in csv.DictReader(f)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", default=",".join(SETS))
    parser.add_argument("--laws", default=",".join(LAWS), help="of: " + ", ".join(LAWS))
    parser.add_argument("--elements", type=int, default=None)
    parser.add_argument("--csv", type=Path, default=OUT)
    args = parser.parse_args()
    full = full_model_table()
    rows, histories = [], {}
    for name in args.sets.split(","):
        params = SETS[name]
        omega = params.get("omega", 320.0)
        for label in args.laws.split(","):
            law = LAWS[label]
            start = time.perf_counter()
            program = paper_program(law, elements=args.elements, **params)
            report = analyse(program, [rpm_of(omega)], with_flight=False)
            arm = report.train["arm"]
            speed = arm["speeds"][0]
            ref = full[(name, label)]
            row = {
                "set": name,
                "law": label,
                "fundamental_rad_s": arm["fundamental_rad_s"],
                "full_rad_s": float(ref["natural_rad_s"]),
            }
            for k in (1, 3, 5):
                row[f"v_{k}"] = speed["bending_harmonics_mm"][k - 1]
                row[f"full_v_{k}"] = float(ref[f"v_{k}"])
            row["seconds"] = time.perf_counter() - start
            rows.append(row)
            print(
                f"{name:>11} {label:>18}: {row['fundamental_rad_s']:8.0f} rad/s "
                + " ".join(
                    f"{k} Omega {row[f'v_{k}']:.3e} ({row[f'v_{k}'] / row[f'full_v_{k}'] - 1:+.2%})"
                    for k in (1, 3, 5)
                )
                + f"  {row['seconds']:.1f} s",
                flush=True,
            )
            if name == "base":
                histories[label] = bending_history(program, rpm_of(omega))
    args.csv.parent.mkdir(parents=True, exist_ok=True)
    with args.csv.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    if len(histories) == len(LAWS):
        figure(histories, [r for r in rows if r["set"] == "base"])


def bending_history(program, rpm):
    """Mid-rod bending over the turn (cam angle in degrees, mm) from the steady state."""
    from camjax.program import SteadyState, arm_bending

    steady = SteadyState(program, rpm)
    return 360.0 * steady.grid.nodes, arm_bending(steady, steady.cycles([rpm]), [rpm])[0]


def figure(histories, rows):
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    for label, (theta, v) in histories.items():
        left.plot(theta, 1e3 * v, label=label, lw=1)
    left.set_xlabel("cam angle (deg)")
    left.set_ylabel("mid-rod bending (um)")
    left.set_title("periodic steady state, Omega = 320 rad/s")
    left.legend(fontsize=8)
    x = np.arange(3)
    width = 0.2
    for i, row in enumerate(rows):
        right.bar(
            x + (i - 1.5) * width,
            [1e3 * row[f"v_{k}"] for k in (1, 3, 5)],
            width,
            label=row["law"],
        )
        right.plot(
            x + (i - 1.5) * width,
            [1e3 * row[f"full_v_{k}"] for k in (1, 3, 5)],
            "k_",
            ms=12,
            mew=2,
        )
    right.set_xticks(x, ["1 Omega", "3 Omega", "5 Omega"])
    right.set_ylabel("amplitude (um)")
    right.set_title("bars: program file; black: full DAE model")
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(FIGURE, dpi=110)
    print(f"wrote {FIGURE}")


if __name__ == "__main__":
    main()
