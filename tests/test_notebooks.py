"""Every notebook runs top to bottom (at its small default size), and one number it computes
agrees with an independent value: a check cell runs in the notebook's kernel after the last."""

import os
from pathlib import Path

import jupytext
import nbclient
import nbformat
import pytest

NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("*.py"))

CHECKS = {
    # autodiff of the kinematic impact velocity against its central differences
    "backlash": "np.testing.assert_allclose(np.asarray(grad), np.asarray(fd), rtol=1e-5, atol=1e-9)",
    # the cycloidal law's undamped residual against 2 n |sin(pi n)| / |n^2 - 1| (0 / 0 at n = 1)
    "ct_curves": "assert np.max(np.abs(cyc.residual - closed)[n > 1]) < 1e-9",
    # the designed law beats 4-5-6-7 over the band on 2000 ratios, and reads back equal
    "design": "assert designed.max() < 0.5 * reference.max()",
    # the events path's rest offset against the closed-form free vibration with friction
    "friction_and_input_drive": "assert abs(float(fv.rest_position) - float(r.rest_offset)) <= 1e-6 * abs(float(fv.rest_position))",
    # Newton at every node: m x'' = F_c - F_0 - k_s x (x the payload's displacement)
    "motion_tasks": """
f = feed.follower
newton = (history["contact_force_n"] - f.preload_n - f.spring_rate_n_per_mm * history["payload_displacement_mm"]) / f.mass_kg
np.testing.assert_allclose(history["payload_acceleration_m_s2"], newton, rtol=0, atol=1e-9 * np.abs(newton).max())
""",
    # the pitch curve of a roller follower without offset: radius r_b + r_r + y(theta)
    "program": """
radius = np.hypot(*prof.pitch.T)
lift = cam.lift(prof.theta_deg)[0]
np.testing.assert_allclose(radius, cam.follower.base_radius_mm + cam.follower.roller_radius_mm + lift, rtol=1e-12)
assert np.abs(force[-(force.size // 3):] - settled[-(force.size // 3):]).max() < 1e-6 * np.abs(settled).max()
""",
    # the rod's first mode against the Rayleigh beam's closed form
    "studio": """
import camjax.program as cp_check
direct = cp_check.analyse(cam, np.linspace(200.0, 1400.0, 7)).jump_speed_rpm
assert abs(served["jump_speed_rpm"] - direct) <= 1e-9 * direct, (served["jump_speed_rpm"], direct)
""",
    "swinging_follower": "assert abs(float(model.fundamental_frequency()) - closed_form) <= 1e-9 * closed_form",
    # Rothbart's chain free of the cam against the two-mass closed form; the surging spring's
    # first three held frequencies within 0.5% of the continuous spring's roots
    "valve_train": """
np.testing.assert_allclose(free_hz, two_mass, rtol=1e-9)
assert np.all(np.abs(held_hz[:3] / continuous_hz - 1) < 0.005), (held_hz[:3], continuous_hz)
""",
}
"""Per notebook: Python run in its kernel after its last cell, asserting on what it computed."""


def test_every_notebook_has_a_check():
    assert sorted(CHECKS) == [p.stem for p in NOTEBOOKS]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, tmp_path):
    notebook = jupytext.read(path)
    notebook.cells.append(nbformat.v4.new_code_cell("import numpy as np\n" + CHECKS[path.stem]))
    os.environ.setdefault("MPLBACKEND", "Agg")
    client = nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
