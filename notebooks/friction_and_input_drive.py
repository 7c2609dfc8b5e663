# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     name: python3
# ---

# %% [markdown]
# # Coulomb friction and an elastic input drive
#
# Two scenes the linear SDOF cannot answer.
#
# **Friction.** A constant friction force on the payload, normalised as
# `mu = F_friction T^2 / (W h)`, adds `-mu sign(x')` to the SDOF; the payload sticks when
# its velocity vanishes inside the stick band. The note says friction kills residual
# vibration once the vibration reverses the motion, hardly touches the in-motion peak,
# and can leave the payload at rest out of position.

# %%
import matplotlib.pyplot as plt
import numpy as np

import camjax
from camjax.models import CoulombFriction, TwoMass, free_vibration

law = camjax.laws.Cycloidal()
n = 5.25
w = 2 * np.pi * n
fig, ax = plt.subplots(figsize=(9, 4))
for mu in (0.0, 0.3, 1.0):
    r = camjax.solve(law, CoulombFriction(n, mu), samples=1024)
    ax.plot(r.tau, r.payload_acceleration / law.Ca, lw=1, label=f"mu = {mu}")
    print(f"mu = {mu}: peak in motion {float(r.metrics.peak_in_motion):.4f} Ca, "
          f"rest offset {float(r.rest_offset):+.2e} (stick band {mu / w**2:.2e}), "
          f"settled {bool(r.settled)}")
ax.plot(r.tau, law.a(r.tau) / law.Ca, "k--", lw=0.8, label="command")
ax.set(xlabel="tau", ylabel="x'' / Ca")
ax.legend()

# %% [markdown]
# The dwell is a free vibration, and that has an exact piecewise solution: each half
# cycle swings about a centre shifted by `mu / w^2`, so the amplitude falls by
# `4 mu / w^2` a cycle until a reversal lands inside the stick band.

# %%
r = camjax.solve(law, CoulombFriction(n, 0.3), samples=1024)
end = int(np.argmin(np.abs(np.asarray(r.tau) - 1.0)))
fv = free_vibration(CoulombFriction(n, 0.3), r.position[end] - 1.0, r.velocity[end])
print("reversal positions (stroke):", np.asarray(fv.reversal_position)[:6])
print("closed-form rest offset", float(fv.rest_position), " events path", float(r.rest_offset))

# %% [markdown]
# **Elastic input drive.** The camshaft (inertia `I`) is driven at constant speed through
# an input shaft; the follower's command is `s(theta)` at the camshaft's actual angle.
# Normalised by the stiffness ratio `k = R beta^2 / (S h^2)` and the inertia ratio
# `m = W h^2 / (I beta^2)`. As `k` grows, Ct tends to the rigid-input SDOF.

# %%
modsine = camjax.laws.ModifiedSine()
rigid = camjax.solve(modsine, camjax.SpringMass(6.4)).metrics.ct
for k in (1.0, 10.0, 100.0):
    r2 = camjax.solve(modsine, TwoMass(6.4, k, 1.0), samples=1024)
    print(f"k = {k:6g}: Ct = {float(r2.metrics.ct):.4f}   (rigid input: {float(rigid):.4f})")
plt.figure(figsize=(9, 3))
plt.plot(r2.tau, r2.twist, label="camshaft lag phi (k = 100)")
plt.xlabel("tau")
plt.legend()
