"""Swinging roller-follower cam with a flexible follower rod (Rayleigh beam, assumed modes).

The rod is pinned at a pivot a distance ``d`` from the cam centre and carries a roller that
runs in a groove of a rigid disk cam turning at ``omega``.  Its reference frame swings with
the rigid follower motion ``phi(Omega t)`` of the motion program; relative to that frame the
rod deflects axially ``u(x) = sum a_i phi_i(x)`` and transversely ``v(x) = sum b_i phi_i(x)``
with ``phi_1 = x / l`` and ``phi_i = sin((i - 1) pi x / l)`` (the paper's assumed modes).
Rotary inertia of the section is kept (Rayleigh beam).  The coordinates are
``q = (a_1..a_N, b_1..b_N, delta)``, where ``theta_c = Omega t + delta`` is the unknown cam
angle of the pitch-curve point the roller centre sits on (the contact point).  Two
constraints keep the roller centre on the pitch curve (equivalently, the roller in the
groove): ``Rot(-Omega t) E(q, t) - P(theta_c) = 0``.  The equations of motion are
Lagrange's, written out from the rod's energies integrated once over its length
(``RodIntegrals``); the tests check them against the Lagrangian and the constraint
differentiated automatically.  The index-3 system is reduced to acceleration level with
Baumgarte stabilisation, ``Phi'' + 2 beta Phi' + beta^2 Phi = 0``, and integrated with
diffrax.  The drift of the position constraint is reported on every saved sample.
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar, NamedTuple

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import checks, geometry
from ..checks import is_concrete, require
from ..errors import RESULTS, promote
from ..laws import AbstractMotionLaw, Cycloidal, RiseDwellFall, rest_to_rest
from ..solvers import solver
from ._base import AbstractMachineModel, Options, Response

_QUADRATURE_POINTS = 24


def _default_law():
    return Cycloidal()


class _TaylorJet(eqx.Module):
    """The motion program's cubic Taylor expansion about one cam angle ``centre``.

    Value and first three theta-derivatives are the program's own (the laws' closed-form
    derivatives); the equations of motion need no higher ones.  Automatic differentiation
    then runs through a cubic rather than through the laws' piecewise formulas."""

    centre: jax.Array
    coefficients: tuple

    @classmethod
    def about(cls, program: RiseDwellFall, theta) -> _TaylorJet:
        centre = jax.lax.stop_gradient(jnp.asarray(theta, dtype=float))
        return cls(centre, tuple(program.evaluate(centre)))

    def evaluate(self, theta):
        y0, y1, y2, y3 = self.coefficients
        e = theta - self.centre
        return y0 + e * (y1 + e * (y2 / 2 + e * y3 / 6)), y1 + e * (y2 + e * y3 / 2), y2 + e * y3, y3

    def displacement(self, theta):
        return self.evaluate(theta)[0]


class _ProgramJet(eqx.Module):
    """The motion program through its Taylor jet about each evaluation point itself.

    This keeps the traced graph short wherever the model is evaluated at arbitrary points.
    Gradients with respect to the laws', the program's and the model's leaves are unaffected
    (checked against differentiating through the program: 1e-14)."""

    program: RiseDwellFall

    def evaluate(self, theta):
        return _TaylorJet.about(self.program, theta).evaluate(theta)

    def displacement(self, theta):
        return self.evaluate(theta)[0]


class FollowerResponse(Response):
    """Samples over the simulated turns (SI units).  ``payload_acceleration`` and
    ``metrics`` are ``None``: the rod's output end is held in the groove, so there is no
    single payload lagging a command; the follower's answers are its deflections and
    their spectra (``spectrum``).  ``tau`` is time in rise periods.

    Attributes:
        t: time, s.
        cam_angle: rad.
        axial_end: u(l), axial deflection at the rod's output (roller) end, m.
        transverse: v at the observation point (default mid-rod), m.
        transverse_end: v(l), m: small, because the groove holds the end in its normal direction.
        constraint_error: |Phi| at each sample, m.
        coordinates: q at each sample, ``(samples, size)``.
        velocities: dq/dt at each sample.
        max_constraint_error: the largest |Phi|, m (checked against the option of that name).
    """

    t: jax.Array
    cam_angle: jax.Array
    axial_end: jax.Array
    transverse: jax.Array
    transverse_end: jax.Array
    constraint_error: jax.Array
    coordinates: jax.Array
    velocities: jax.Array
    max_constraint_error: jax.Array


@dataclasses.dataclass(frozen=True)
class FollowerOptions(Options):
    """Static settings of a swinging-follower solution.

    The step is limited by stability, not accuracy: the undamped axial modes (up to 3.5e5
    rad/s at N = 3) sit on the imaginary axis, where Tsit5 and Dopri5 amplify slightly
    beyond omega h of about 1 and Dopri8 stays stable to about 3.7.  Hence the default
    Dopri8 with a PI controller (``pcoeff = icoeff = 0.3``, fewer rejected steps): 4.8x
    fewer steps than Tsit5 and 25x more accurate.  ``model.axial_modes = 1`` removes
    those modes (quasi-static axial).

    Attributes:
        method: ``"dopri8"``, ``"tsit5"`` or ``"dopri5"``.
        dwell: unused (the program sets the dwells); kept for the common signature.
        turns: cam turns simulated from rest (a whole number for spectra).
        samples_per_turn: samples per turn.
        rtol, atol, max_steps, pcoeff, icoeff: diffrax settings.
        max_constraint_error: largest accepted drift |Phi| of the groove constraint, m.
    """

    method: str = "dopri8"
    turns: float = 3
    samples_per_turn: int = 512
    rtol: float = 1e-6
    atol: float = 1e-11
    max_steps: int = 400_000
    pcoeff: float = 0.3
    icoeff: float = 0.3
    max_constraint_error: float = 1e-6

    def checked(self, max_period_ratio: float) -> FollowerOptions:
        base = super().checked(max_period_ratio)
        require(isinstance(self.turns, int | float) and self.turns > 0, f"turns must be a positive number, got {self.turns}")
        require(isinstance(self.samples_per_turn, int) and self.samples_per_turn >= 16, "samples_per_turn must be an integer >= 16")
        require(self.max_constraint_error > 0, "max_constraint_error must be positive")
        return base


class RodIntegrals(eqx.Module):
    """The rod's kinetic, strain and gravity energies integrated over its length: with
    ``u = phi_a . a`` (axial) and ``v = phi . b`` (transverse), each energy is a quadratic
    form in ``a``, ``b`` and their rates with these coefficients (``rho A`` per length,
    rotary inertia ``rho I``, axial stiffness ``E A``, bending stiffness ``E I``)."""

    axial_mass: jax.Array
    """``rho A int phi_a phi_a^T``."""
    coupling: jax.Array
    """``rho A int phi_a phi^T``: axial rates against transverse deflections (the swing's Coriolis terms)."""
    transverse_mass: jax.Array
    """``rho A int phi phi^T``."""
    bending_mass: jax.Array
    """``rho A int phi phi^T + rho I int phi' phi'^T``: translation and rotary inertia of the bending rates."""
    axial_moment: jax.Array
    """``rho A int x phi_a``."""
    transverse_moment: jax.Array
    """``rho A int x phi + rho I int phi'``: the bending rates against the swing rate."""
    swing_inertia: jax.Array
    """``rho A int x^2 + rho I l``: the undeflected rod's inertia about the pivot."""
    axial_stiffness: jax.Array
    """``E A int phi_a' phi_a'^T``."""
    bending_stiffness: jax.Array
    """``E I int phi'' phi''^T``."""
    first_moment: jax.Array
    """``rho A int x``."""
    axial_weight: jax.Array
    """``rho A int phi_a``."""
    transverse_weight: jax.Array
    """``rho A int phi``."""


class SwingingFollower(AbstractMachineModel):
    """The cam - flexible rod - roller system.  SI units; every default is written here once.

    Defaults (the paper gives omega, l, rod radius, phi_T; the rest are chosen here):
    steel rod ``E = 210 GPa``, ``rho = 7800 kg/m^3`` (its first pinned-pinned bending
    frequency, 13 240 rad/s = 41.4 Omega, matches the paper's 41.5 Omega peak);
    base circle 40 mm, roller radius 10 mm, roller mass 25 g (steel disc 10 mm thick),
    roller polar inertia ``m_r r_r^2 / 2``; pivot distance ``sqrt(l^2 + (r_b + r_r)^2)`` so that
    the rod is perpendicular to the cam radius at the low dwell; gravity off (cam in a
    horizontal plane; set ``gravity=9.81`` to act along -Y).
    """

    rise: AbstractMotionLaw = eqx.field(default_factory=_default_law)
    fall: AbstractMotionLaw = eqx.field(default_factory=_default_law)
    omega: jax.Array | float = 320.0
    """Cam speed, rad/s."""
    total_swing: jax.Array | float = math.pi / 18
    """Total rise phi_T of the rod, rad."""
    length: jax.Array | float = 0.098
    """Rod length l (pivot to roller centre), m."""
    rod_radius: jax.Array | float = 0.005
    """Radius of the rod's circular section, m."""
    youngs_modulus: jax.Array | float = 210e9
    density: jax.Array | float = 7800.0
    roller_radius: jax.Array | float = 0.010
    roller_mass: jax.Array | float = 0.025
    base_radius: jax.Array | float = 0.040
    gravity: jax.Array | float = 0.0
    observation_point: jax.Array | float = 0.5
    """Where the transverse deflection is read, as a fraction of l (the end is held by the groove)."""
    baumgarte: jax.Array | float = 1e4
    """Constraint stabilisation rate beta, 1/s."""
    modes: int = eqx.field(static=True, default=3)
    """N: assumed modes per direction (axial and transverse)."""
    axial_modes: int | None = eqx.field(static=True, default=None)
    """Axial assumed modes (default ``modes``).  ``1`` keeps only the end mode ``x/l``: the
    quasi-static treatment of the stiff axial sin modes (see ``docs/swinging-follower.md``)."""

    methods: ClassVar[tuple[str, ...]] = ("dopri8", "tsit5", "dopri5")
    options_type: ClassVar[type[Options]] = FollowerOptions
    cpu_compiler_options: ClassVar[tuple[tuple[str, object], ...]] = (
        ("xla_cpu_use_fusion_emitters", False),)
    """XLA's classic CPU fusion emitters: they compile the solve (a large vector field inside
    diffrax's loop) in 3.4-3.9 s instead of 4.9-5.4 s, and run it as fast."""

    @property
    def period_ratio(self):
        """Rise duration over the rod's fundamental period (the SDOF view of the rise)."""
        return self.program.rise_angle / self.omega * self.fundamental_frequency() / (2 * math.pi)

    def _option_scale(self) -> float:
        return 1.0  # the follower's options do not depend on a period ratio

    def checked_parameters(self) -> dict:
        names = ("omega", "length", "rod_radius", "youngs_modulus", "density", "roller_radius", "roller_mass", "base_radius")
        return {name: checks.positive(getattr(self, name), name) for name in names}

    def response(self, law, options: FollowerOptions) -> FollowerResponse:
        model = self.validated()
        if law is not None:
            model = dataclasses.replace(model, rise=law, fall=law)
        response = _simulate(model, options)
        failed = response.result != RESULTS.successful
        drift = response.max_constraint_error > options.max_constraint_error  # NaN: not caught here
        finite = jnp.all(jnp.isfinite(response.transverse)) & jnp.all(jnp.isfinite(response.axial_end))
        result = RESULTS.where(failed, response.result, RESULTS.where(
            ~finite, RESULTS.nonfinite, RESULTS.where(drift, RESULTS.invariant_violated, RESULTS.successful)))
        return dataclasses.replace(response, result=result)

    def __check_init__(self):
        require(isinstance(self.modes, int) and 1 <= self.modes <= 12, f"modes must be an integer 1..12, got {self.modes}")
        axial = self.axial_modes
        require(
            axial is None or (isinstance(axial, int) and 1 <= axial <= 12), f"axial_modes must be None or an integer 1..12, got {axial}"
        )
        for which in ("rise", "fall"):  # rise-dwell-fall-dwell: each law runs from rest to rest
            rest_to_rest(getattr(self, which), "SwingingFollower", which)
        if is_concrete(self.total_swing, self.observation_point):
            require(0 < float(self.total_swing) < math.pi / 2, f"total_swing must be in (0, pi/2) rad, got {self.total_swing}")
            require(0 < float(self.observation_point) <= 1, "observation_point must be in (0, 1]")
        if is_concrete(self.rod_radius, self.length):
            require(self.rod_radius < self.length / 2, "rod_radius must be well below the rod length")

    # ---- derived quantities -------------------------------------------------------------
    @property
    def area(self):
        return math.pi * self.rod_radius**2

    @property
    def second_moment(self):
        return math.pi * self.rod_radius**4 / 4

    @property
    def roller_inertia(self):
        return self.roller_mass * self.roller_radius**2 / 2

    @property
    def pivot_distance(self):
        return jnp.sqrt(self.length**2 + (self.base_radius + self.roller_radius) ** 2)

    @property
    def follower(self) -> geometry.SwingingRollerFollower:
        return geometry.SwingingRollerFollower(
            pivot_distance=self.pivot_distance,
            arm_length=self.length,
            roller_radius=self.roller_radius,
            base_radius=self.base_radius,
        )

    @property
    def program(self) -> RiseDwellFall:
        return RiseDwellFall(self.rise, self.fall, self.total_swing)

    @property
    def _jet(self) -> _ProgramJet:
        return _ProgramJet(self.program)

    @property
    def n_axial(self) -> int:
        """Number of axial assumed modes."""
        return self.modes if self.axial_modes is None else self.axial_modes

    @property
    def size(self) -> int:
        return self.n_axial + self.modes + 1

    def shapes(self, x, count: int | None = None):
        """Assumed modes and their first two x-derivatives at ``x`` (m): each ``(len(x), count)``.

        ``count`` defaults to ``modes``."""
        count = self.modes if count is None else count
        x = jnp.asarray(x)[:, None]
        l = self.length
        k = jnp.arange(1, count)[None, :] * math.pi / l
        one = jnp.ones_like(x)
        phi = jnp.concatenate([x / l, jnp.sin(k * x)], axis=1)
        dphi = jnp.concatenate([one / l, k * jnp.cos(k * x)], axis=1)
        ddphi = jnp.concatenate([0 * one, -(k**2) * jnp.sin(k * x)], axis=1)
        return phi, dphi, ddphi

    def _quadrature(self):
        nodes, weights = np.polynomial.legendre.leggauss(_QUADRATURE_POINTS)
        return (nodes + 1) * self.length / 2, weights * self.length / 2

    def expansions(self, q, t) -> tuple[_TaylorJet, _TaylorJet]:
        """The program's jets about the rod frame's cam angle and the contact point's, at ``(q, t)``.

        ``accelerations`` evaluates the program once for both (one evaluation at the two
        angles) and hands the jets to the equations of motion and the constraint, so that
        the laws' formulas are traced once per vector field rather than once per nested
        derivative."""
        theta = self.omega * t
        centres = jax.lax.stop_gradient(jnp.stack([theta, theta + self._split(q)[2]]).astype(float))
        values = self.program.evaluate(centres)
        return tuple(_TaylorJet(centres[i], tuple(v[i] for v in values)) for i in range(2))

    def _jets(self, jets):
        return (self._jet, self._jet) if jets is None else jets

    def _swing(self, t, jet=None):
        """Rod frame angle psi(t) and its rate, from the rigid follower motion."""
        return self._swing_motion(t, jet)[:2]

    def _swing_motion(self, t, jet=None):
        """Rod frame angle psi(t), its rate and its acceleration (psi = arm_angle(y) falls
        as the lift y rises: d psi = -dy)."""
        y, dy, d2y, _ = (self._jet if jet is None else jet).evaluate(self.omega * t)
        return self.follower.arm_angle(y), -self.omega * dy, -self.omega**2 * d2y

    def _split(self, q):
        na, n = self.n_axial, self.modes
        return q[:na], q[na : na + n], q[-1]

    def roller_centre(self, q, t, jet=None):
        """Roller centre in the fixed frame for coordinates ``q`` at time ``t``.

        ``jet``: the rod frame's jet from ``expansions`` at the primal ``(q, t)``, or ``None``."""
        a, b, _ = self._split(q)
        psi, _ = self._swing(t, jet)
        axis, across = jnp.stack([jnp.cos(psi), jnp.sin(psi)]), jnp.stack([-jnp.sin(psi), jnp.cos(psi)])
        pivot = jnp.stack([self.pivot_distance, 0.0 * psi])
        return pivot + (self.length + a[0]) * axis + b[0] * across

    def constraint(self, q, t, jets=None):
        """Roller centre minus its pitch-curve point, in the cam frame (m); zero in the groove.

        ``jets``: the program's ``expansions`` at the primal ``(q, t)``, or ``None``."""
        swing, contact = self._jets(jets)
        theta_c = self.omega * t + self._split(q)[2]
        return self._centre_in_cam(q, t, swing) - geometry.pitch_point(self.follower, contact, theta_c)

    def _centre_in_cam(self, q, t, swing):
        """The roller centre in the cam frame (m), ``F(q, t)`` of the constraint."""
        return geometry._rot(-self.omega * t, self.roller_centre(q, t, swing))

    # ---- energies -----------------------------------------------------------------------
    def rod_integrals(self) -> RodIntegrals:
        """The rod's energies, and the roller's translation, as quadratic forms in the modal
        coordinates: the quadrature over the assumed modes, done once (per solve) rather
        than in every evaluation of the equations of motion.  The roller is a point mass at
        ``x = l``, where every mode but the first vanishes (``u(l) = a_1``, ``v(l) = b_1``)."""
        x, w = self._quadrature()
        phi, dphi, ddphi = self.shapes(x)
        phi_a, dphi_a, _ = self.shapes(x, self.n_axial)
        rho, area, inertia, modulus = self.density, self.area, self.second_moment, self.youngs_modulus
        m, l = self.roller_mass, self.length
        line = rho * area * w  # mass per length times the quadrature weights
        end_a = jnp.zeros(self.n_axial).at[0].set(1.0)
        end_b = jnp.zeros(self.modes).at[0].set(1.0)
        return RodIntegrals(
            axial_mass=(phi_a.T * line) @ phi_a + m * jnp.outer(end_a, end_a),
            coupling=(phi_a.T * line) @ phi + m * jnp.outer(end_a, end_b),
            transverse_mass=(phi.T * line) @ phi + m * jnp.outer(end_b, end_b),
            bending_mass=(phi.T * line) @ phi + rho * inertia * (dphi.T * w) @ dphi + m * jnp.outer(end_b, end_b),
            axial_moment=phi_a.T @ (line * x) + m * l * end_a,
            transverse_moment=phi.T @ (line * x) + rho * inertia * dphi.T @ w + m * l * end_b,
            swing_inertia=jnp.sum(line * x**2) + rho * inertia * jnp.sum(w) + m * l**2,
            axial_stiffness=modulus * area * (dphi_a.T * w) @ dphi_a,
            bending_stiffness=modulus * inertia * (ddphi.T * w) @ ddphi,
            first_moment=jnp.sum(line * x) + m * l,
            axial_weight=phi_a.T @ line + m * end_a,
            transverse_weight=phi.T @ line + m * end_b,
        )

    def lagrangian(self, q, qdot, t, jets=None, rod=None):
        """``T - V`` (J); ``jets``: the program's ``expansions`` at the primal ``(q, t)``, or
        ``None``; ``rod``: the model's ``rod_integrals()`` (computed here if ``None``)."""
        swing, contact = self._jets(jets)
        rod = self.rod_integrals() if rod is None else rod
        return self._frame_lagrangian(q, qdot, t, swing, rod) + self._spin_energy(q, qdot, t, contact)

    def _frame_lagrangian(self, q, qdot, t, swing, rod: RodIntegrals):
        """``T - V`` less the roller's spin: the rod and the roller's translation, with the
        rod frame's jet ``swing``.

        In the rod frame the neutral axis moves at ``(u' - v psi', v' + (x + u) psi')``
        (``' = d/dt``) and the section turns at ``psi' + dv'/dx`` (rotary inertia,
        Rayleigh); integrated over ``x`` (``rod_integrals``), T is a quadratic form in
        ``a``, ``b`` and their rates."""
        a, b, _ = self._split(q)
        adot, bdot, _ = self._split(qdot)
        psi, psidot = self._swing(t, swing)
        kinetic = (0.5 * adot @ rod.axial_mass @ adot - psidot * adot @ rod.coupling @ b
                   + 0.5 * psidot**2 * b @ rod.transverse_mass @ b + 0.5 * bdot @ rod.bending_mass @ bdot
                   + psidot * bdot @ (rod.transverse_moment + rod.coupling.T @ a)
                   + 0.5 * psidot**2 * (rod.swing_inertia + 2 * rod.axial_moment @ a + a @ rod.axial_mass @ a))
        strain = 0.5 * a @ rod.axial_stiffness @ a + 0.5 * b @ rod.bending_stiffness @ b
        height = (rod.first_moment + rod.axial_weight @ a) * jnp.sin(psi) + rod.transverse_weight @ b * jnp.cos(psi)
        return kinetic - strain - self.gravity * height

    def _frame_equations(self, q, qdot, t, swing, rod: RodIntegrals):
        """``M`` and ``dL/dq - d/dt(dL/dqdot)|_{qddot=0}`` of ``_frame_lagrangian``, written
        out: with ``A, C, B, D`` the axial, coupling, transverse and bending masses, ``g, h``
        the axial and transverse moments and ``K_a, K_b`` the stiffnesses,
        ``f_a = 2 psi' C b' + psi'' C b + psi'^2 (g + A a) - K_a a - gravity sin(psi) w_a`` and
        ``f_b = -2 psi' C^T a' - psi'' (h + C^T a) + psi'^2 B b - K_b b - gravity cos(psi) w_b``;
        ``M = diag(A, D, 0)`` (the spin adds the last entry)."""
        a, b, _ = self._split(q)
        adot, bdot, _ = self._split(qdot)
        psi, psidot, psiddot = self._swing_motion(t, swing)
        force_a = (2 * psidot * rod.coupling @ bdot + psiddot * rod.coupling @ b
                   + psidot**2 * (rod.axial_moment + rod.axial_mass @ a) - rod.axial_stiffness @ a
                   - self.gravity * jnp.sin(psi) * rod.axial_weight)
        force_b = (-2 * psidot * rod.coupling.T @ adot - psiddot * (rod.transverse_moment + rod.coupling.T @ a)
                   + psidot**2 * rod.transverse_mass @ b - rod.bending_stiffness @ b
                   - self.gravity * jnp.cos(psi) * rod.transverse_weight)
        mass = jax.scipy.linalg.block_diag(rod.axial_mass, rod.bending_mass, jnp.zeros((1, 1)))
        return mass, jnp.concatenate([force_a, force_b, jnp.zeros(1)])

    def _spin_energy(self, q, qdot, t, contact):
        """The roller's spin energy (J): it rolls without slip on the cam, so it spins at
        ``omega - s (omega + delta') / r_r``, ``s`` the pitch curve's speed ``|dP/dtheta|`` at
        the contact point."""
        theta_c = self.omega * t + self._split(q)[2]
        pitch_speed = jnp.linalg.norm(
            jax.jvp(lambda s: geometry.pitch_point(self.follower, contact, s), (theta_c,), (jnp.ones_like(theta_c),))[1]
        )
        spin = self.omega - pitch_speed * (self.omega + self._split(qdot)[2]) / self.roller_radius
        return 0.5 * self.roller_inertia * spin**2

    def _pitch_jet(self, contact, theta, order: int = 2) -> tuple:
        """The pitch point ``P`` at cam angle ``theta`` and its derivatives in it up to
        ``order``: ``(P, P', ..)``."""
        def deeper(derivatives):
            def next_order(s):
                values, rates = jax.jvp(derivatives, (s,), (jnp.ones_like(s),))
                return (*values, rates[-1])
            return next_order

        derivatives = lambda s: (geometry.pitch_point(self.follower, contact, s),)  # noqa: E731
        for _ in range(order):
            derivatives = deeper(derivatives)
        return derivatives(theta)

    def _constraint_jacobian(self, q, t, swing, tangent):
        """``dPhi/dq``: the roller centre's in the cam frame, less ``P'`` for ``delta``."""
        return jax.jacfwd(self._centre_in_cam)(q, t, swing).at[:, -1].add(-tangent)

    def accelerations(self, q, qdot, t, jets=None, rod=None):
        """``(qddot, lambda)`` from the stabilised augmented system.

        ``jets``: what the motion program is evaluated through (default: its ``expansions``
        at ``(q, t)``; ``(program, program)`` differentiates the laws' formulas directly);
        ``rod``: the ``rod_integrals()`` (computed here if ``None``).

        The rod and the roller's translation are Lagrange's equations written out from
        ``rod_integrals`` (``_frame_equations``).  The contact point enters only through the
        pitch curve at ``theta_c = omega t + delta``, whose terms are written out from its
        jet ``(P, P', P'')`` (evaluated once): the spin ``J (s/r)^2 delta'' + J s s' (omega + delta')^2 / r^2``
        (``s = |P'|``, ``s' = P'.P''/s``) and, in the constraint ``Phi = F(q, t) - P(theta_c)``,
        ``-P' delta''`` with the free term ``-P'' (omega + delta')^2``.  This equals
        differentiating the whole Lagrangian and constraint (tests/test_swinging_follower.py)
        at 1,178 traced operations instead of 3,096."""
        swing, contact = self.expansions(q, t) if jets is None else jets
        rod = self.rod_integrals() if rod is None else rod
        mass, force = self._frame_equations(q, qdot, t, swing, rod)
        rate = self.omega + self._split(qdot)[2]  # d theta_c / dt
        pitch, tangent, curvature = self._pitch_jet(contact, self.omega * t + self._split(q)[2])
        speed = jnp.linalg.norm(tangent)
        spin_mass = self.roller_inertia / self.roller_radius**2
        mass = mass.at[-1, -1].add(spin_mass * speed**2)
        force = force.at[-1].add(-spin_mass * (tangent @ curvature) * rate**2)
        # The roller centre in the cam frame, F(q, t), and its rates along the motion.
        centre = lambda q_, t_: self._centre_in_cam(q_, t_, swing)  # noqa: E731
        jac = self._constraint_jacobian(q, t, swing, tangent)
        velocity = lambda q_, t_: jax.jvp(centre, (q_, t_), (qdot, jnp.ones_like(t_)))  # noqa: E731
        (position, centre_rate), (_, centre_free) = jax.jvp(velocity, (q, t), (qdot, jnp.ones_like(t)))
        phi = position - pitch
        phi_dot = centre_rate - tangent * rate
        phi_ddot_free = centre_free - curvature * rate**2
        beta = self.baumgarte
        rhs_c = -phi_ddot_free - 2 * beta * phi_dot - beta**2 * phi
        n = self.size
        system = jnp.block([[mass, jac.T], [jac, jnp.zeros((2, 2))]])
        solution = jnp.linalg.solve(system, jnp.concatenate([force, rhs_c]))
        return solution[:n], solution[n:]

    def energy_function(self, q, qdot, t):
        """Jacobi's energy function ``h = qdot . dL/dqdot - L`` (J).

        With the prescribed swing and cam speed the mechanical energy is not conserved, but
        ``dh/dt = energy_supply(q, qdot, t)`` holds along every motion of the model; in a dwell
        the groove is a circle about the cam centre, the supply vanishes and ``h`` is conserved.
        """
        jets = self.expansions(q, t)
        lagrangian = lambda q_, qd_, t_: self.lagrangian(q_, qd_, t_, jets)  # noqa: E731
        return qdot @ jax.grad(lagrangian, argnums=1)(q, qdot, t) - lagrangian(q, qdot, t)

    def energy_supply(self, q, qdot, t):
        """``dh/dt = -dL/dt|_(q, qdot) - lambda . (dPhi/dq qdot)`` (W): the power that the prescribed
        swing of the rod frame and the turning groove feed into the energy function."""
        jets = self.expansions(q, t)
        explicit = jax.grad(lambda t_: self.lagrangian(q, qdot, t_, jets))(t)
        _, multipliers = self.accelerations(q, qdot, t, jets)
        return -explicit - multipliers @ (jax.jacfwd(self.constraint)(q, t, jets) @ qdot)

    def natural_frequencies(self, cam_angle=1.75 * math.pi):
        """Frequencies (rad/s, ascending) of the constrained rod linearised at rest at ``cam_angle``.

        The default angle lies in the low dwell, where the rigid swing is at rest.
        """
        return _natural_frequencies(self, jnp.asarray(cam_angle, dtype=float))

    def fundamental_frequency(self):
        """Lowest natural frequency of the rod in the groove, rad/s."""
        return self.natural_frequencies()[0]


@eqx.filter_jit
def _natural_frequencies(model, cam_angle):
    """The constrained rod's frequencies linearised at rest (``q = qdot = 0``) at
    ``cam_angle``: the written-out mass, the stiffness ``-d2L/dq2`` (strain less the swing's
    centrifugal softening ``psi'^2``, and the spin's ``J omega^2 ((s'/r)^2 - (1 - s/r) s''/r)``
    for ``delta``, ``s = |P'|``), on the motions that keep the roller in the groove."""
    t = cam_angle / model.omega
    zero = jnp.zeros(model.size)
    swing, contact = model.expansions(zero, t)
    rod = model.rod_integrals()
    mass, _ = model._frame_equations(zero, zero, t, swing, rod)
    _, psidot, _ = model._swing_motion(t, swing)
    _, tangent, curvature, third = model._pitch_jet(contact, model.omega * t, order=3)
    speed = jnp.linalg.norm(tangent)
    speed_rate = tangent @ curvature / speed
    speed_curvature = (curvature @ curvature + tangent @ third) / speed - speed_rate**2 / speed
    radius, spin = model.roller_radius, model.roller_inertia
    mass = mass.at[-1, -1].add(spin * (speed / radius) ** 2)
    spin_stiffness = -spin * model.omega**2 * ((speed_rate / radius) ** 2 - (1 - speed / radius) * speed_curvature / radius)
    stiffness = jax.scipy.linalg.block_diag(rod.axial_stiffness - psidot**2 * rod.axial_mass,
                                            rod.bending_stiffness - psidot**2 * rod.transverse_mass,
                                            spin_stiffness[None, None])
    # Motions that keep the roller in the groove: the null space of the constraint Jacobian.
    _, _, vt = jnp.linalg.svd(model._constraint_jacobian(zero, t, swing, tangent))
    basis = vt[2:].T
    chol = jnp.linalg.cholesky(basis.T @ mass @ basis)
    reduced = jax.scipy.linalg.solve_triangular(chol, basis.T @ stiffness @ basis, lower=True)
    reduced = jax.scipy.linalg.solve_triangular(chol, reduced.T, lower=True)
    return jnp.sqrt(jnp.clip(jnp.linalg.eigvalsh(0.5 * (reduced + reduced.T)), 0.0))


# Velocities are integrated as ``qdot / _RATE_SCALE`` so that one absolute tolerance suits
# deflections (m) and their rates (m/s, about 1e4 times larger at the rod's frequencies).
_RATE_SCALE = 1e4


@jax.jit  # traced once: diffrax evaluates the vector field in several places
def _vector_field(t, state, args):
    model, rod = args
    q, rate = state
    qdot = rate * _RATE_SCALE
    return qdot, model.accelerations(q, qdot, t, rod=rod)[0] / _RATE_SCALE


def _simulate(model, options: FollowerOptions) -> FollowerResponse:
    turns, samples_per_turn = options.turns, options.samples_per_turn
    period = 2 * math.pi / model.omega
    ts = jnp.arange(int(round(turns * samples_per_turn))) * (period / samples_per_turn)
    whole = math.ceil(turns)
    jumps = jnp.concatenate([jnp.asarray(model.program.jump_angles()) / model.omega + k * period for k in range(whole + 1)])
    zero = jnp.zeros(model.size)
    solution = diffrax.diffeqsolve(
        diffrax.ODETerm(_vector_field),
        solver(options.method),
        t0=0.0,
        t1=turns * period,
        dt0=period * 1e-4,
        y0=(zero, zero),
        args=(model, model.rod_integrals()),
        saveat=diffrax.SaveAt(ts=ts),
        stepsize_controller=diffrax.PIDController(
            rtol=options.rtol, atol=options.atol, pcoeff=options.pcoeff, icoeff=options.icoeff, jump_ts=jumps
        ),
        max_steps=options.max_steps,
        throw=False,
    )
    q, qdot = solution.ys[0], solution.ys[1] * _RATE_SCALE
    x_obs = jnp.atleast_1d(model.observation_point * model.length)
    phi_obs = model.shapes(x_obs)[0][0]
    na, n = model.n_axial, model.modes
    error = jnp.linalg.norm(jax.vmap(lambda q_, t_: model.constraint(q_, t_, model.expansions(q_, t_)))(q, ts), axis=1)
    return FollowerResponse(
        tau=ts * model.omega / model.program.rise_angle,
        payload_acceleration=None,
        metrics=None,
        result=promote(solution.result),
        stats={"steps": solution.stats["num_steps"]},
        t=ts,
        cam_angle=model.omega * ts,
        axial_end=q[:, 0],
        transverse=q[:, na : na + n] @ phi_obs,
        transverse_end=q[:, na],
        constraint_error=error,
        coordinates=q,
        velocities=qdot,
        max_constraint_error=jnp.max(error),
    )


class Spectrum(NamedTuple):
    order: np.ndarray
    """Frequency in multiples of the cam speed Omega."""
    amplitude: np.ndarray
    """Single-sided amplitude, same unit as the signal."""


def spectrum(signal, turns: int) -> Spectrum:
    """FFT amplitude spectrum of a signal sampled uniformly over ``turns`` whole cam turns."""
    signal = np.asarray(signal, dtype=float)
    count = signal.shape[-1]
    coefficients = np.fft.rfft(signal, axis=-1)
    amplitude = np.abs(coefficients) * 2 / count
    amplitude[..., 0] /= 2
    return Spectrum(np.arange(coefficients.shape[-1]) / turns, amplitude)


def spectral_peaks(spec: Spectrum, natural_order: float, odd_orders=(1, 3, 5, 7, 9), window: float = 3.0):
    """Amplitudes at the odd harmonics and the largest peak within ``window`` of ``natural_order``.

    Returns ``(list of (order, amplitude), (order, amplitude) near the natural frequency)``.
    """
    order, amplitude = np.asarray(spec.order), np.asarray(spec.amplitude)
    harmonics = [(float(k), float(amplitude[np.argmin(np.abs(order - k))])) for k in odd_orders]
    near = np.flatnonzero(np.abs(order - natural_order) <= window)
    if near.size == 0:
        raise ValueError(f"natural order {natural_order:.3g} lies outside the spectrum (max {order[-1]:.3g})")
    best = near[np.argmax(amplitude[near])]
    return harmonics, (float(order[best]), float(amplitude[best]))
