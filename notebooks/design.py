# %% [markdown]
# # Designing a B-spline motion law
#
# A small end-to-end run: minimise the worst residual vibration over the period-ratio band
# [6, 12] with Ca <= 7.5 and Cj <= 100, compare with the 4-5-6-7 polynomial (the standard
# law with that Ca), check the caps, save the law and load it back.

# %%
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import camjax.law_design as D
from camjax.laws import get, load, save

# %%
objective = D.MaxResidual(6.0, 12.0, samples=128)
caps = D.Caps(max_ca=7.5, max_jerk=100.0)
result = D.design(objective, caps=caps, knots=12, steps=300, progress=False)
print(result.values, result.coefficients, f"{result.seconds:.1f} s")

# %%
ratios = np.linspace(6.0, 12.0, 2000)
designed = np.asarray(D.residual(result.law, ratios))
reference = np.asarray(D.residual(get("poly4567"), ratios))
print(f"max R designed {designed.max():.4f}, 4-5-6-7 {reference.max():.4f}")
assert designed.max() < reference.max()
assert all(v <= 0 for v in caps.violations(result.law).values())

# %%
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.semilogy(ratios, designed, "k", label="designed (12 knots)")
ax.semilogy(ratios, reference, label="4-5-6-7")
ax.set(xlabel="period ratio n", ylabel="residual R (units of Ca)")
ax.legend()

# %%
import tempfile
from pathlib import Path

path = save(result.law, Path(tempfile.mkdtemp()) / "law.json")
loaded = load(path)
assert float(np.max(np.asarray(D.residual(loaded, ratios)))) == designed.max()
