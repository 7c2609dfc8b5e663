"""Time one design from a fresh Python process (compile included) and again warm.

The issue's target: one design of 20 to 32 knots in under 10 s on the 2-core machine,
compile included.  Each case runs in its own fresh interpreter (nothing compiled yet);
the same process then designs again with another Ca cap (compiled code reused), which
is the baseline the cold figure is compared with.

Usage: python experiments/benchmarks/design_speed.py  (writes results/design_speed/)
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

CASE = """
import json, time
started = time.perf_counter()
import camjax.law_design as D
imported = time.perf_counter() - started
def one(cap):
    r = D.design(D.MaxResidual(6.0, 12.0), caps=D.Caps(cap, 100.0), knots={knots}, progress=False)
    return r.seconds, r.values["max R over [6, 12]"]
cold, cold_r = one(7.5)
warm, warm_r = one(7.4)
print(json.dumps(dict(knots={knots}, import_s=imported, cold_s=cold, warm_s=warm, max_r=cold_r)))
"""


def main(out=Path("results/design_speed")):
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for knots in (20, 24, 32):
        text = subprocess.run([sys.executable, "-c", CASE.format(knots=knots)], check=True,
                              capture_output=True, text=True).stdout
        rows.append(json.loads(text.strip().splitlines()[-1]))
        print(rows[-1], flush=True)
    (out / "speed.json").write_text(json.dumps(rows, indent=1))
    lines = ["One design, max R over [6, 12], Ca <= 7.5, Cj <= 100, 6000 L-BFGS steps "
             "(fresh process; `import` not included in the design time)", "",
             "| knots | design, compile included (s) | same process, again (s) | cold / warm | import (s) | max R |",
             "|---|---|---|---|---|---|"]
    lines += [f"| {r['knots']} | {r['cold_s']:.1f} | {r['warm_s']:.1f} | {r['cold_s'] / r['warm_s']:.1f} | "
              f"{r['import_s']:.1f} | {r['max_r']:.5f} |" for r in rows]
    (out / "speed.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main(*(Path(a) for a in sys.argv[1:]))
