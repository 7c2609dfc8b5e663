# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Ct curves, residual vibration and Ca*Ct of the standard motion laws
#
# The linear single-degree-of-freedom model (see Conventions and units): the cam commands `s(tau)`, the
# payload follows through a spring, `x'' = w^2 (s - x) + 2 zeta w (s' - x')`, `w = 2 pi n`.
# camjax propagates it exactly and sweeps many period ratios `n` in one compiled call.
# `N_POINTS` keeps the run small; raise it for smoother curves.

# %%
import os

import matplotlib.pyplot as plt
import numpy as np

import camjax
from camjax import laws, plot

N_POINTS = int(os.environ.get("CAMJAX_NOTEBOOK_POINTS", "200"))
n = np.linspace(1.0, 30.0, N_POINTS)

# %% [markdown]
# ## The laws and their coefficients

# %%
for law in laws.standard_laws():
    c = law.peak_coefficients()
    print(f"{law.name:<20} Cv={c['Cv']:.4f}  Ca={c['Ca']:.4f}  Cj={c['Cj']:.4f}")
plot.law_curves(laws.standard_laws()[:3]);

# %% [markdown]
# ## One response: modified sine at n = 3, lightly damped

# %%
response = camjax.solve(laws.ModifiedSine(), camjax.SpringMass(3.0, damping=0.02))
m = response.metrics
print(f"Ct = {float(m.ct):.4f}, R = {float(m.residual):.4f}, "
      f"peak in motion = {float(m.peak_in_motion):.4f} (units of Ca)")
plot.response(response, "modified sine, n = 3, zeta = 0.02");

# %% [markdown]
# ## Ct and residual curves of every standard law (one vmapped call per law)

# %%
curves = camjax.ct_curves(laws.standard_laws(), n)
plot.ct_curves(curves)
plot.residual_curves(curves);

# %% [markdown]
# A closed form checks the cycloidal residual: `R = 2n|sin(pi n)|/|n^2 - 1|`.

# %%
cyc = curves["cycloidal"]
closed = 2 * n * np.abs(np.sin(np.pi * n)) / np.abs(n**2 - 1)
print("max |R - closed form| =", np.max(np.abs(cyc.residual - closed)))

# %% [markdown]
# ## Torsion-factor envelopes `Ct = p / n^q + r` and the Ca*Ct chart

# %%
fits = {name: camjax.fit_torsion_factor(c) for name, c in curves.items()}
print(f"{'law':<20} {'p':>7} {'q':>6} {'r':>6}")
for name, f in fits.items():
    print(f"{name:<20} {f.p:7.3f} {f.q:6.3f} {f.r:6.3f}")
plot.ca_ct_chart(curves, fits)
for n_switch, old, new in camjax.metrics.best_law_switches(curves, fits):
    print(f"best law changes at n = {n_switch:.2f}: {old} -> {new}")
plt.show()
