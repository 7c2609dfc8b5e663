# %% [markdown]
# # A machine cam from file to profile
#
# A cam program (rises, dwells and returns over 360 degrees, in mm) and its follower (mass,
# train stiffness, return spring, preload) at machine speed: the exact periodic steady state,
# the contact force and the spring preload it needs, the speed at which the follower jumps,
# the flight and re-impact past it, and the profile for the machine shop.  Equations:
# docs/program.md.

# %%
import matplotlib.pyplot as plt
import numpy as np

import camjax
from camjax import program as cp

cam = camjax.Program.load(cp.example_path("indexer"))
for seg in cam.segments:
    print(f"{seg.angle_deg:6.1f} deg  lift {seg.lift_mm:+6.1f} mm  {seg.law.name if seg.law else 'dwell'}")
print(f"natural frequency {cam.follower.natural_frequency_hz:.1f} Hz")

# %% [markdown]
# ## One speed: lift, accelerations and contact force over a turn
# The payload acceleration departs from the cam's: vibration left by the rise carries
# through the dwell and round the turn (the periodic steady state, not a start from rest).

# %%
rpm = 600.0
steady = cp.SteadyState(cam, 300.0)  # the grid is fixed by the slowest speed we will ask for
history = cp.response(cam, rpm, steady=steady)
fig, (a, b) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
a.plot(history["theta_deg"], history["kinematic_acceleration_m_s2"], label="cam y''")
a.plot(history["theta_deg"], history["payload_acceleration_m_s2"], label="payload x''")
a.set_ylabel("m/s^2")
a.legend()
b.plot(history["theta_deg"], history["contact_force_n"])
b.axhline(0, color="k", lw=0.8)
b.axhline(cam.follower.preload_n, ls="--", color="C1")
b.set(xlabel="cam angle (deg)", ylabel="contact force (N)")
plt.show()

# %% [markdown]
# ## The start-up from rest settles onto the steady state

# %%
s, accel, force = cp.startup(cam, rpm, 3, steady=steady)
settled = np.tile(history["contact_force_n"][:-1], 3)
print("largest difference in each turn (N):",
      [f"{np.abs(d).max():.2e}" for d in np.split(force - settled, 3)])

# %% [markdown]
# ## Across the speed range: minimum preload and the jump speed
# One vmapped, compiled call covers the whole sweep.

# %%
report = cp.analyse(cam, np.linspace(300, 900, 31), steady=steady, with_flight=False)
speeds = [r.rpm for r in report.speeds]
plt.plot(speeds, [r.min_preload_n for r in report.speeds], marker=".")
plt.axhline(cam.follower.preload_n, ls="--", color="C1", label="preload")
plt.axvline(report.jump_speed_rpm, color="k", lw=0.8, label="jump speed")
plt.xlabel("rpm")
plt.ylabel("minimum preload (N)")
plt.legend()
plt.show()
print(f"jump speed {report.jump_speed_rpm:.1f} rpm")

# %% [markdown]
# ## Past the jump speed: flight and re-impact
# Every flight of the turn that follows the steady state's first separation: after a
# re-impact the roller may take off again.

# %%
for each in cp.flights(steady, 900.0):
    print(each)

# %% [markdown]
# ## Designing the rise for the least preload over 300-600 rpm
# The whole program's steady state (vibration carried in from the return counts), made
# differentiable in the rise's spline coefficients; a short run for the notebook.

# %%
designed, result = cp.design_segment(cam, 1, 300.0, 600.0, objective="preload", knots=8, steps=200,
                                     progress=False)
before = max(r.min_preload_n for r in report.speeds if r.rpm <= 600)  # the sweep above
print(f"largest preload needed over 300-600 rpm: {before:.1f} N with the cycloidal rise, "
      f"{result.values[result.objectives[0].label]:.1f} N designed")

# %% [markdown]
# ## The profile, its pressure angle and radius of curvature, and the DXF for the shop

# %%
prof = cp.profile(cam, 720)
fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.5))
a.plot(*prof.pitch.T, ls="--", label="pitch curve")
a.plot(*prof.profile.T, label="profile")
a.set_aspect("equal")
a.legend()
b.plot(prof.theta_deg, prof.pressure_angle_deg)
b.set(xlabel="cam angle (deg)", ylabel="pressure angle (deg)")
plt.show()
print("undercut anywhere:", bool(prof.undercut.any()),
      f"; smallest profile radius of curvature {np.abs(prof.profile_radius_of_curvature_mm).min():.1f} mm")
cp.write_dxf(prof, "indexer.dxf")
cp.write_csv(prof, "indexer.csv");
