# %% [markdown]
# # A valve train: a chain of bodies and a spring that surges
# The follower as a chain (docs/valve-trains.md): Rothbart's valve gear and its natural
# frequencies against the two-mass closed form, a valve on a spring with its own mass
# against the continuous spring, the harmonic check, and the chain's exact periodic steady
# state over the built-in `valve` program: the contact force at the cam, the valve's
# acceleration and the spring's surge against speed.

# %%
import math

import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import brentq

import camjax.program as cp

# %% [markdown]
# ## Rothbart's valve gear
# Cam Design Handbook, ch. 11: lifter plus half the pushrod 0.0327 lbm riding on the cam,
# pushrod 3.0e5 lb/in, valve side 0.110 lbm, spring 660 lb/in. In inch-pound units with
# `1 lbm = 1/386.09 lbf s^2/in`; free of the cam, the two-mass chain's frequencies are the
# roots of `m1 m2 w^4 - ((k + ks) m1 + k m2) w^2 + k ks = 0`.

# %%
G_IN = 386.09
LBF_PER_IN = 4.4482216152605 / 25.4  # N/mm
TO_KG = 4.4482216152605 / 0.0254 / G_IN  # kg per lbm, through 1 lbm = 1/386.09 lbf s^2/in
rothbart = cp.Chain(
    (cp.Body("lifter", 0.0327 * TO_KG), cp.Body("valve", 0.110 * TO_KG, 3.0e5 * LBF_PER_IN)),
    cp.Spring(660 * LBF_PER_IN, 100.0),
)
free_hz, free_shapes = rothbart.natural_frequencies(contact=False)
m1, m2, k, ks = 0.0327 / G_IN, 0.110 / G_IN, 3.0e5, 660.0
b = (k + ks) * m1 + k * m2
two_mass = np.sqrt((b + np.array([-1.0, 1.0]) * math.sqrt(b * b - 4 * m1 * m2 * k * ks)) / (2 * m1 * m2)) / (2 * math.pi)
print("free of the cam (Hz):", free_hz, " two-mass closed form:", two_mass)
print("the book prints 67 and 3400 Hz: ratios", free_hz / np.array([67.0, 3400.0]))

# %% [markdown]
# ## A valve on a surging spring
# The built-in `valve` program: a 30 g tappet riding the cam, a 50 g valve on a 200 N/mm
# element, a 52 N/mm spring of 49 g cut into 8 bar elements (the default). With the cam
# held, the continuous spring's frequencies are the roots of
# `k_e + k_s beta cot(beta) - m_v w^2 = 0` with `beta = w sqrt(m_s / k_s)`.

# %%
cam = cp.Program.load(cp.example_path("valve"))
chain = cam.chain
held_hz, held_shapes = chain.natural_frequencies(contact=True)
k_e, k_s, m_s, m_v = 200e3, 52e3, 0.049, 0.05


def continuous(w):
    beta = w * math.sqrt(m_s / k_s)
    return k_e + k_s * beta / math.tan(beta) - m_v * w * w


edges = np.linspace(1.0, 8000.0, 80001)
values = np.array([continuous(w) for w in edges])
roots = [brentq(continuous, a, c) for a, c, fa, fc in zip(edges[:-1], edges[1:], values[:-1], values[1:])
         if fa * fc < 0 and abs(fa - fc) < 1e6]
continuous_hz = np.array(roots[:3]) / (2 * math.pi)
print("held (Hz):", held_hz[:3].round(1), " continuous spring:", continuous_hz.round(1))
print("relative error:", (held_hz[:3] / continuous_hz - 1))

# %%
fig, ax = plt.subplots(figsize=(6, 3))
for i in range(3):
    ax.plot(np.arange(len(chain.names)), held_shapes[:, i], "o-", label=f"{held_hz[i]:.1f} Hz")
ax.set_xticks(range(len(chain.names)), chain.names)
ax.set_ylabel("mode shape")
ax.legend()
ax.set_title("the first three modes with the cam held")

# %% [markdown]
# ## The harmonic check
# The cam orders `k` that meet each mode inside the speed range (`k rpm / 60 = f_n`).

# %%
for hz, orders in chain.harmonic_check(1000.0, 3000.0):
    print(f"{hz:8.1f} Hz: orders {orders[0]}..{orders[-1]}")

# %% [markdown]
# ## The exact periodic steady state against speed

# %%
rpm = np.linspace(1000.0, 4000.0, 31)
steady = cp.SteadyState(cam, rpm.min())  # the one steady state: the chain is its oscillator
summary = steady.summary(rpm)
train = summary.cycles.train  # the chain's own figures (TrainPeaks)
fig, axes = plt.subplots(1, 3, figsize=(11, 3))
axes[0].plot(rpm, summary.min_contact_force_n)
axes[0].axhline(0.0, color="k", lw=0.5)
axes[0].set_title("least contact force at the cam (N)")
axes[1].plot(rpm, train.max_acceleration_m_s2[:, -1])
axes[1].set_title("valve's peak acceleration (m/s^2)")
axes[2].plot(rpm, train.max_surge_n)
axes[2].set_title("spring surge at its seat (N)")
for ax in axes:
    ax.set_xlabel("rpm")
fig.tight_layout()
print("jump speed (rpm):", cp.jump_speed_rpm(steady, 1000.0, 4000.0, tolerance_rpm=0.01))
