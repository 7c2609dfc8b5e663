# %% [markdown]
# # Motion tasks beyond rest-to-rest: a feed cam
#
# A feed needs more than rises from rest to rest: a stretch at constant velocity, a
# transition onto it and a reversal out of it.  This notebook builds the feed cam from
# Python, reads the state and continuity of every join, shows a velocity jump being
# refused, and runs the cam at two speeds.  Equations and file syntax:
# docs/motion-tasks.md.
#
# ## The four join states (VDI 2143)
#
# | state | velocity | acceleration | example |
# |---|---|---|---|
# | **R** rest | 0 | 0 | a dwell, the ends of a cycloid |
# | **G** constant velocity | ≠ 0 | 0 | a working stroke |
# | **U** reversal | 0 | ≠ 0 | the top of a harmonic rise-return |
# | **B** motion | ≠ 0 | ≠ 0 | anywhere inside a rise |
#
# A velocity that jumps at a join is an impact and is refused; an acceleration step is
# allowed and reported (the join is C1, otherwise C2).

# %%
import matplotlib.pyplot as plt

import camjax
from camjax import program as cp
from camjax.program import EndState, Follower, Program, Segment

follower = Follower(mass_kg=1.5, stiffness_n_per_mm=2000, damping_ratio=0.05, spring_rate_n_per_mm=10,
                    preload_n=300, base_radius_mm=40, roller_radius_mm=12)
feed = Program("feed", (
    Segment(30),                                    # dwell on the base circle (R)
    Segment.polynomial(50, 8, degree=5),            # R -> G: from rest onto the working speed
    Segment.constant_velocity(60, 18),              # the working stroke at 18 / 60 = 0.3 mm/deg
    Segment.polynomial(55, -3, degree=7, end=EndState(-0.4, 0.0, 0.0)),  # turn back, leave at -0.4
    Segment.polynomial(105, -23, degree=5),         # return to rest
    Segment(60),                                    # dwell
), follower)
print("the same as the built-in example:", feed == Program.load(cp.example_path("feed")))

# %% [markdown]
# ## The join report
# `"match"` (the default for `start` and `end`) reads the neighbour's state at the join, so
# every join of the feed cam is C2.  Its joins are at rest (R) or at constant velocity
# (G).  A harmonic rise straight into a harmonic return turns at a reversal (U), with an
# acceleration step at the dwells (C1); ending the feed cam's reversal still decelerating
# gives a join in motion (B).

# %%
def show_joins(cam):
    for j in cam.joins():
        print(f"  segments {j.before}-{j.after} at {j.angle_deg:5.1f} deg: v {j.velocity_mm_per_deg:+.3f} mm/deg, "
              f"a {j.acceleration_before_mm_per_deg2:+.5f} / {j.acceleration_after_mm_per_deg2:+.5f} mm/deg^2"
              f"  {j.continuity}  {j.state}")


print("feed cam:")
show_joins(feed)
harmonic = Program("harmonic", (Segment(90), Segment(90, 10.0, camjax.laws.get("harmonic")),
                                Segment(90, -10.0, camjax.laws.get("harmonic")), Segment(90)), follower)
print("harmonic rise and return:")
show_joins(harmonic)
segments = list(feed.segments)
segments[3] = Segment.polynomial(55, -3, degree=7, end=EndState(-0.4, 0.002, 0.0))
print("feed cam, reversal ending at a = 0.002 mm/deg^2:")
show_joins(Program("feed-B", tuple(segments), follower))

# %% [markdown]
# ## A velocity jump is refused
# Start the return at -0.3 mm/deg where the reversal ends at -0.4 mm/deg:

# %%
segments = list(feed.segments)
segments[4] = Segment.polynomial(105, -23, degree=5, start=EndState(-0.3))
try:
    Program("jump", tuple(segments), follower)
except ValueError as error:
    print(error)

# %% [markdown]
# ## Acceleration and contact force over the turn at two speeds
# The periodic steady state (one `SteadyState` for both speeds: the slowest fixes the
# grid).  At 650 rpm the reversal's deceleration takes the contact force close to zero.

# %%
speeds = (400.0, 650.0)
steady = cp.SteadyState(feed, min(speeds))
fig, (a, b) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
for rpm in speeds:
    history = cp.response(feed, rpm, steady=steady)
    line, = a.plot(history["theta_deg"], history["payload_acceleration_m_s2"], label=f"payload x'' {rpm:g} rpm")
    a.plot(history["theta_deg"], history["kinematic_acceleration_m_s2"], "--", lw=0.8, color=line.get_color(),
           label=f"cam y'' {rpm:g} rpm")
    b.plot(history["theta_deg"], history["contact_force_n"], color=line.get_color(), label=f"{rpm:g} rpm")
for ax in (a, b):
    for start in feed.start_deg[1:]:
        ax.axvline(start, color="0.8", lw=0.6, zorder=0)
    ax.legend(fontsize=8)
a.set_ylabel("acceleration (m/s^2)")
b.axhline(0, color="k", lw=0.8)
b.set(xlabel="cam angle (deg); grey lines: joins", ylabel="contact force (N)")
plt.show()
for r in cp.analyse(feed, list(speeds), steady=steady, with_flight=False).speeds:
    print(f"{r.rpm:g} rpm: smallest contact force {r.min_contact_force_n:.1f} N, "
          f"preload needed {r.min_preload_n:.1f} N")

# %% [markdown]
# ## Which reversal?
# `experiments/examples/motion_tasks.py` compares the preload the cam needs over 500-650 rpm with
# the reversal as a quintic, as this septic and as a `CorrectedPolynomial` designed for it
# (`camjax.program.design_segment(feed, 4, 500, 650, objective="preload")`, about 40 s):
# docs/motion-tasks.md.
