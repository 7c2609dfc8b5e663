"""A cam program compiles once per shape: an edit that keeps the shape compiles nothing.

The program's values (grid, forcing, follower, contact factors) are arguments of
module-level compiled functions, padded to bucketed shapes, so analysing an edited
program (other lifts, another mass, stiffness or preload) reuses every compiled program,
the jump speed's search and the flights included.  Counted with ``jax.monitoring``'s
backend-compile events, not timed.
"""

import dataclasses

import jax
import numpy as np
import pytest

import camjax.program as cp

_COMPILES = []
jax.monitoring.register_event_duration_secs_listener(
    lambda event, duration, **kw: _COMPILES.append(event)
    if event == "/jax/core/compile/backend_compile_duration" else None)


def _scaled(program, factor):
    return dataclasses.replace(program, segments=tuple(
        dataclasses.replace(s, lift_mm=s.lift_mm * factor) if s.moving else s for s in program.segments))


@pytest.fixture(scope="module")
def feed():
    return cp.Program.load(cp.example_path("feed"))


def test_edited_program_compiles_nothing(feed):
    rpm = np.array([300.0, 600.0, 900.0])
    first = cp.analyse(feed, rpm)
    assert first.speeds[-1].flights  # the flights' search runs too
    before = len(_COMPILES)
    follower = dataclasses.replace(feed.follower, mass_kg=1.6, preload_n=320.0)
    for edited in (_scaled(feed, 1.02), dataclasses.replace(_scaled(feed, 0.97), follower=follower)):
        report = cp.analyse(edited, rpm)
        assert report.speeds[-1].max_contact_force_n != first.speeds[-1].max_contact_force_n
    assert len(_COMPILES) == before, f"{len(_COMPILES) - before} compilations for edits of the same shape"
