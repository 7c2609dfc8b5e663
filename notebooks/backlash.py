# %% [markdown]
# # Backlash impact
#
# The payload leaves the driving flank when the law's deceleration exceeds its natural
# deceleration `dn = Dn T^2/h`, flies across the clearance `bk = backlash/stroke` and strikes
# the other flank with normalised velocity `v = V T/h`.  First the kinematic analysis of the
# reference note, then the dynamic SDOF with a dead zone, then a gradient for design.

# %%
import jax
import matplotlib.pyplot as plt
import numpy as np

import camjax
import camjax.models as bl

# %% [markdown]
# ## Kinematic impact velocity against backlash, for several natural decelerations

# %%
bk = np.geomspace(1e-3, 0.5, 25)
dn = [0.0, 2.0, 4.0]
fig, axes = plt.subplots(1, 3, figsize=(12, 3.5), sharey=True)
laws = [camjax.laws.SimpleHarmonic(), camjax.laws.ModifiedSine(), camjax.laws.Cycloidal()]
for ax, law in zip(axes, laws, strict=True):
    table = bl.kinematic_impact_table(law, bk, dn)
    for d, row in zip(dn, np.asarray(table.impact_velocity), strict=True):
        ax.plot(bk, row, label=f"dn = {d:g}")
    ax.set(xscale="log", title=law.name, xlabel="bk")
axes[0].set_ylabel("impact velocity v")
axes[0].legend()
plt.show()

# %% [markdown]
# At small backlash the low-jerk-at-crossover laws (harmonic, modified sine) strike
# slowest: with `dn = 0` the gap opens as `|j| u^3 / 6`, so `v ~ |j|^(1/3) (6 bk)^(2/3) / 2`.

# %%
for law in (camjax.laws.SimpleHarmonic(), camjax.laws.ModifiedSine(), camjax.laws.Cycloidal()):
    r = bl.kinematic_impact(law, 0.01, 1.0)
    print(
        f"{law.name:15s} departs {float(r.departure_tau):.4f}  strikes {float(r.impact_tau):.4f}"
        f"  v = {float(r.impact_velocity):.4f}"
    )

# %% [markdown]
# Physical impact force: a 2 kg payload on a 5 MN/m transmission, stroke 50 mm in 0.1 s.

# %%
v = float(bl.kinematic_impact(camjax.laws.ModifiedSine(), 0.01, 1.0).impact_velocity)
V = bl.impact_velocity(v, stroke=0.05, motion_time=0.1)
print(f"V = {V:.3f} m/s, impact force = {bl.impact_force(V, mass=2.0, stiffness=5e6):.0f} N")

# %% [markdown]
# ## Dynamic: the SDOF with a dead zone, one diffrax solve per contact state

# %%
law = camjax.laws.ModifiedSine()
response = camjax.solve(law, bl.Backlash(40.0, 0.02, 1.0, 0.05))
kinematic = bl.kinematic_impact(law, 0.02, 1.0)
print(
    "first impact: dynamic",
    float(response.first_impact_velocity),
    "kinematic",
    float(kinematic.impact_velocity),
    "impacts:",
    int(response.n_impacts),
)
fig, ax = plt.subplots(figsize=(8, 3))
ax.plot(response.tau, response.deflection)
ax.axhline(0, color="k", lw=0.5)
ax.axhline(-0.02, color="k", lw=0.5)
ax.set(xlabel="tau", ylabel="deflection e = s - x", title="between the flanks: 0 > e > -bk")
plt.show()

# %% [markdown]
# ## Gradient of the impact velocity in the SCCA fractions (checked by central differences)


# %%
@jax.jit
def velocity(fractions):
    return bl.kinematic_impact(camjax.laws.SCCA(*fractions), 0.02, 1.0).impact_velocity


x = jax.numpy.array([0.25, 0.05, 0.65])  # inside the valid set, so the differences stay valid
grad = jax.grad(velocity)(x)
h = 1e-6
fd = [(velocity(x.at[i].add(h)) - velocity(x.at[i].add(-h))) / (2 * h) for i in range(3)]
print("autodiff", np.asarray(grad), "\nfinite d.", np.asarray(fd))
