# %% [markdown]
# # Swinging roller follower with a flexible rod
# The cam profile from the motion program (theory of envelopes), the rod's natural
# frequencies against the pinned-pinned Rayleigh beam, and one cam turn of the flexible
# model (small by default; the full study is `experiments/examples/swinging_follower.py`).

# %%
import math

import matplotlib.pyplot as plt
import numpy as np

import camjax
from camjax import geometry
from camjax.laws import ModifiedSine
from camjax.models import SwingingFollower, spectral_peaks, spectrum

model = SwingingFollower(rise=ModifiedSine(), fall=ModifiedSine(), modes=2)
theta = np.linspace(0, 2 * math.pi, 361)
profile = geometry.cam_profile(model.follower, model.program, theta)
print("max |pressure angle| (deg):", float(np.degrees(np.max(np.abs(profile.pressure_angle)))))
flags = geometry.undercut(profile, model.roller_radius)
print("undercut inner/outer:", bool(flags.inner.any()), bool(flags.outer.any()), "min flank radii (m):", float(flags.min_inner_radius), float(flags.min_outer_radius))

# %%
fig, ax = plt.subplots(figsize=(4, 4))
for curve in (profile.pitch, profile.inner, profile.outer):
    ax.plot(curve[:, 0] * 1e3, curve[:, 1] * 1e3)
ax.set_aspect("equal")
ax.set_title("groove (mm)")

# %% [markdown]
# The first bending frequency is that of a pinned-pinned Rayleigh beam: the groove holds the
# roller end in the normal direction.

# %%
E, rho, A, I, l = model.youngs_modulus, model.density, model.area, model.second_moment, model.length
closed_form = math.sqrt(E * I * (math.pi / l) ** 4 / (rho * A * (1 + I / A * (math.pi / l) ** 2)))
print("model", float(model.fundamental_frequency()), "closed form", closed_form, "rad/s")

# %%
response = camjax.solve(None, model, turns=1, samples_per_turn=256)
print("max constraint error (m):", float(response.max_constraint_error))
plt.figure(figsize=(7, 3))
plt.plot(np.degrees(response.cam_angle), np.asarray(response.transverse) * 1e3)
plt.xlabel("cam angle (deg)")
plt.ylabel("mid-rod v (mm)")
harmonics, near = spectral_peaks(spectrum(np.asarray(response.transverse) * 1e3, 1), closed_form / model.omega)
print("odd harmonics (order, mm):", harmonics, "near fundamental:", near)
