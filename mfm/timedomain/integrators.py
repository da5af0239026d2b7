"""Time integrators behind one small protocol.

The system is ``q̈, ż = f(t, q, q̇, z)``: second-order mechanical coordinates q plus first-order
auxiliary states z (e.g. radiation state-space states; an empty array when there are none). Every
integrator is an immutable, hashable object with

    init(f, t0, q0, qd0, z0) -> State
    step(f, state, dt)       -> State

so it can be a static argument of a jit-compiled simulation. ``evaluations``: the evaluations of
f per step (what a load's cost per step is multiplied by). ``stage_offsets`` declares when within a
step ``f`` is evaluated (fractions of dt from the step's start): loads with memory or tabulated
inputs (the radiation convolution, the excitation) prepare exactly those stages instead of
assuming them. ``State.qdd`` holds the acceleration at
``State.t`` where the scheme has it; ``State.iterations`` counts the corrector iterations of the last
step (implicit and predictor–corrector schemes; 0 otherwise).

Stability on an undamped oscillator of natural frequency ω (``stability_limit`` = max ω dt):
RK4 2√2, Beeman (Lande-Sudall et al. eq. 52 with its corrector) 2, semi-implicit Euler 2, Verlet (Beeman's
step without the corrector) 2, Newmark average acceleration ∞ (unconditionally stable).
"""
from __future__ import annotations

import abc
import dataclasses
import math
from typing import Callable, ClassVar, NamedTuple

import jax
import jax.numpy as jnp


class State(NamedTuple):
    t: jnp.ndarray
    q: jnp.ndarray
    qd: jnp.ndarray
    qdd: jnp.ndarray
    z: jnp.ndarray
    zd: jnp.ndarray
    iterations: jnp.ndarray


Dynamics = Callable[[jnp.ndarray, jnp.ndarray, jnp.ndarray, jnp.ndarray],
                    tuple[jnp.ndarray, jnp.ndarray]]


def phase_error(integrator, omega_dt: float) -> float:
    """Relative error of the period an integrator gives an undamped oscillator of ω at step dt
    (leading term of its modified frequency; Hairer, Lubich & Wanner, Geometric Numerical
    Integration, 2006, §IX): RK4 (ω dt)⁴/120, trapezoidal schemes (Newmark average acceleration,
    Beeman with its corrector) (ω dt)²/12, semi-implicit Euler and Verlet (ω dt)²/24."""
    x = float(omega_dt)
    order = getattr(integrator, "order", 2)
    if order >= 4:
        return x**4 / 120.0
    if getattr(integrator, "name", "") in ("semi_implicit", "verlet"):
        return x**2 / 24.0
    return x**2 / 12.0


class AbstractIntegrator(abc.ABC):
    """The base of the integrators (the protocol of the module docstring, declared): a frozen
    dataclass with ``name``, ``order`` (global error O(dtⁿ)), ``evaluations`` (of f per step),
    ``stability_limit`` (max ω dt on an undamped oscillator) and ``stage_offsets`` (the fractions
    of dt at which f is evaluated within a step), and :meth:`init`, :meth:`step`. An integrator
    of a user's own subclasses it (or follows the protocol: :func:`get` accepts that too, and
    asks for ``stage_offsets`` only where a load with memory needs them)."""
    name: ClassVar[str]

    @abc.abstractmethod
    def init(self, f, t0, q0, qd0, z0) -> State:
        """The state at t0: the acceleration and the auxiliary rates evaluated there."""

    @abc.abstractmethod
    def step(self, f, state: State, dt) -> State:
        """One step of length dt."""


def _init(f, t0, q0, qd0, z0):
    t0 = jnp.asarray(t0, jnp.float64)
    a, zd = f(t0, q0, qd0, z0)
    return State(t=t0, q=q0, qd=qd0, qdd=a, z=z0, zd=zd, iterations=jnp.asarray(0))


@dataclasses.dataclass(frozen=True)
class RK4(AbstractIntegrator):
    """Classical 4th-order Runge–Kutta on (q, q̇, z). Global error O(dt⁴)."""
    name: str = "rk4"
    order: int = 4
    evaluations: int = 4
    stability_limit: float = 2.0 * math.sqrt(2.0)
    stage_offsets: tuple = (0.0, 0.5, 1.0)

    def init(self, f, t0, q0, qd0, z0):
        return _init(f, t0, q0, qd0, z0)

    @staticmethod
    def amplification(z):
        """One step on the test equation ẏ = λy, z = λ dt (complex, any shape): y ← R(z) y with
        R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 (Hairer & Wanner, Solving ODEs II, §IV.2). What RK4
        does to a first-order state such as a radiation state-space mode; the exact factor is
        eᶻ (:func:`mfm.runner.choices.choose_radiation` compares the two)."""
        import numpy as np

        z = np.asarray(z, complex)
        return 1.0 + z * (1.0 + z * (0.5 + z * (1.0 / 6.0 + z / 24.0)))

    def step(self, f, s: State, dt):
        # The four evaluations as one rolled loop of one f (the compiled time loop holds one copy
        # of the dynamics instead of four). Evaluation j takes
        #   x_j = x + a_j h k_(j−1) + b_j (h/6) Σ w k,   (a, b) = (½,0), (½,0), (1,0), (0,1)
        # (k_0 = the step's start, x̃ = (q, q̇, z), k = (q̇, q̈, ż)): the stages k2, k3, k4 of
        # classical RK4, then the acceleration at the new state (the next step's k1).
        h = dt
        a_c = jnp.array([0.5, 0.5, 1.0, 0.0]) * h
        b_c = jnp.array([0.0, 0.0, 0.0, 1.0]) * (h / 6.0)
        t_c = jnp.array([0.5, 0.5, 1.0, 1.0]) * h
        w = jnp.array([2.0, 2.0, 1.0, 0.0])

        def stage(j, c):
            kq, kv, kz, sq, sv, sz = c
            qd = s.qd + a_c[j] * kv + b_c[j] * sv
            v, zd = f(s.t + t_c[j], s.q + a_c[j] * kq + b_c[j] * sq, qd,
                      s.z + a_c[j] * kz + b_c[j] * sz)
            return qd, v, zd, sq + w[j] * qd, sv + w[j] * v, sz + w[j] * zd

        c = (s.qd, s.qdd, s.zd, s.qd, s.qdd, s.zd)
        _, a, zd, sq, sv, sz = jax.lax.fori_loop(0, 4, stage, c)
        return State(t=s.t + h, q=s.q + h / 6.0 * sq, qd=s.qd + h / 6.0 * sv, qdd=a,
                      z=s.z + h / 6.0 * sz, zd=zd, iterations=jnp.asarray(0))


@dataclasses.dataclass(frozen=True)
class SemiImplicitEuler(AbstractIntegrator):
    """Semi-implicit (symplectic) Euler: q̇ₙ₊₁ = q̇ₙ + dt q̈(qₙ, q̇ₙ), qₙ₊₁ = qₙ + dt q̇ₙ₊₁.

    Symplectic for separable Hamiltonian systems with a constant mass matrix (bounded energy error
    rather than drift there); first order, one evaluation per step. z advances by explicit Euler.
    """
    name: str = "semi_implicit"
    order: int = 1
    evaluations: int = 1
    stability_limit: float = 2.0
    stage_offsets: tuple = (0.0, 1.0)

    def init(self, f, t0, q0, qd0, z0):
        return _init(f, t0, q0, qd0, z0)

    def step(self, f, s: State, dt):
        qd = s.qd + dt * s.qdd
        q = s.q + dt * qd
        z = s.z + dt * s.zd
        t = s.t + dt
        a, zd = f(t, q, qd, z)
        return State(t=t, q=q, qd=qd, qdd=a, z=z, zd=zd, iterations=jnp.asarray(0))


@dataclasses.dataclass(frozen=True)
class Verlet(AbstractIntegrator):
    """Velocity Verlet with a predicted velocity: one evaluation of f per step, second order.

        qₙ₊₁ = qₙ + dt q̇ₙ + dt²/2 q̈ₙ,   q̇* = q̇ₙ + dt q̈ₙ,   z* = zₙ + dt żₙ      (predictor)
        q̈ₙ₊₁, ż* = f(tₙ₊₁, qₙ₊₁, q̇*, z*)
        q̇ₙ₊₁ = q̇ₙ + dt/2 (q̈ₙ + q̈ₙ₊₁),   zₙ₊₁ = zₙ + dt/2 (żₙ + ż*)

    Beeman's step (Lande-Sudall et al. eq. 52) with no corrector iteration. q̈ₙ₊₁ is taken at the predicted
    velocity q̇*, which is O(dt²) off q̇ₙ₊₁: with velocity-dependent loads (damping, drag, PTOs) that
    enters q̇ at O(dt³) per step, so the scheme stays second order. On an undamped oscillator it is
    Störmer–Verlet: period error (ω dt)²/24, half the trapezoid's. Stable for ω dt < 2
    (undamped). z advances by Heun's rule (explicit trapezoid), weakly unstable for undamped
    oscillatory states: use it with radiation='state_space_exact', whose states are advanced
    exactly outside the integrator. Reverse-mode differentiable. A coordinate with no restoring
    (free surge) integrates the O(dt²) error of its mean velocity: its drift is less accurate
    than RK4's (benchmarks/RESULTS.md).
    """
    name: str = "verlet"
    order: int = 2
    evaluations: int = 1
    stability_limit: float = 2.0
    stage_offsets: tuple = (0.0, 1.0)

    def init(self, f, t0, q0, qd0, z0):
        return _init(f, t0, q0, qd0, z0)

    def step(self, f, s: State, dt):
        t = s.t + dt
        q = s.q + dt * (s.qd + 0.5 * dt * s.qdd)
        a, zd = f(t, q, s.qd + dt * s.qdd, s.z + dt * s.zd)
        qd = s.qd + 0.5 * dt * (s.qdd + a)
        z = s.z + 0.5 * dt * (s.zd + zd)
        return State(t=t, q=q, qd=qd, qdd=a, z=z, zd=zd, iterations=jnp.asarray(0))


def _rel_change(new, old):
    scale = jnp.maximum(jnp.max(jnp.abs(new)), 1e-300)
    return jnp.max(jnp.abs(new - old)) / scale


@dataclasses.dataclass(frozen=True)
class Beeman(AbstractIntegrator):
    """The scheme of Lande-Sudall et al. eq. 52 (after [29]), a predictor–corrector:

        qₙ₊₁ = qₙ + dt (q̇ₙ + q̈ₙ dt/2)                      (52a)
        q̇ₙ₊₁ = q̇ₙ + dt/2 (q̈ₙ + q̈ₙ₊₁)                      (52b)

    q̈ₙ₊₁ depends on q̇ₙ₊₁, so (52b) is iterated from the predictor q̇ₙ + dt q̈ₙ until the relative
    change of q̈ₙ₊₁ is below ``tol`` (the seed uses 1 %) or ``max_iter`` is reached. z advances by
    the trapezoidal rule inside the same iteration; the current iterate of q̈ is passed to f, so
    acceleration terms on the right-hand side (the seed's added mass) are iterated with it.
    Second order. The iteration is a while loop:
    forward-mode differentiable, not reverse-mode (use RK4 or Newmark for gradients).
    """
    tol: float = 0.01
    max_iter: int = 50
    name: str = "beeman"
    order: int = 2
    evaluations: int = 3          # typical: the predictor and two corrector iterations
    stability_limit: float = 2.0
    stage_offsets: tuple = (0.0, 1.0)

    def init(self, f, t0, q0, qd0, z0):
        return _init(f, t0, q0, qd0, z0)

    def step(self, f, s: State, dt):
        t = s.t + dt
        q = s.q + dt * (s.qd + 0.5 * dt * s.qdd)
        qd0 = s.qd + dt * s.qdd
        z0 = s.z + dt * s.zd
        a0, zd0 = f(t, q, qd0, z0, s.qdd)

        def cond(c):
            k, a, _, _, _, change = c
            return (k < self.max_iter) & (change > self.tol)

        def body(c):
            k, a, zd, _, _, _ = c
            qd = s.qd + 0.5 * dt * (s.qdd + a)
            z = s.z + 0.5 * dt * (s.zd + zd)
            a_new, zd_new = f(t, q, qd, z, a)
            return k + 1, a_new, zd_new, qd, z, _rel_change(a_new, a)

        k, a, zd, qd, z, _ = jax.lax.while_loop(
            cond, body, (jnp.asarray(0), a0, zd0, qd0, z0, jnp.asarray(jnp.inf)))
        # velocity and z consistent with the last acceleration
        qd = s.qd + 0.5 * dt * (s.qdd + a)
        z = s.z + 0.5 * dt * (s.zd + zd)
        return State(t=t, q=q, qd=qd, qdd=a, z=z, zd=zd, iterations=k)


@dataclasses.dataclass(frozen=True)
class Newmark(AbstractIntegrator):
    """Newmark average acceleration (β = 1/4, γ = 1/2), the trapezoidal rule on (q, q̇, z):

        qₙ₊₁ = qₙ + dt q̇ₙ + dt²/4 (q̈ₙ + q̈ₙ₊₁),   q̇ₙ₊₁ = q̇ₙ + dt/2 (q̈ₙ + q̈ₙ₊₁),
        zₙ₊₁ = zₙ + dt/2 (żₙ + żₙ₊₁),

    solved for (q̈ₙ₊₁, żₙ₊₁) by chord-Newton iterations: the exact jax Jacobian of the residual is
    formed once per step and reused for ``iterations`` fixed steps (a fixed count keeps the step
    reverse-mode differentiable). Second order,
    unconditionally stable, no numerical damping (energy-conserving on linear systems).
    """
    iterations: int = 4
    name: str = "newmark"
    order: int = 2
    evaluations: int = 6          # the Jacobian (forward mode), four iterations, the final one
    stability_limit: float = math.inf
    stage_offsets: tuple = (0.0, 1.0)

    def init(self, f, t0, q0, qd0, z0):
        return _init(f, t0, q0, qd0, z0)

    def step(self, f, s: State, dt):
        t = s.t + dt
        nq = s.q.shape[0]

        def unpack(u):
            a, zd = u[:nq], u[nq:]
            q = s.q + dt * s.qd + 0.25 * dt * dt * (s.qdd + a)
            qd = s.qd + 0.5 * dt * (s.qdd + a)
            z = s.z + 0.5 * dt * (s.zd + zd)
            return q, qd, z

        def residual(u):
            q, qd, z = unpack(u)
            a, zd = f(t, q, qd, z)
            return u - jnp.concatenate([a, zd])

        u0 = jnp.concatenate([s.qdd, s.zd])
        # chord (modified Newton) iterations: the exact Jacobian once per step, then reused
        lu = jax.scipy.linalg.lu_factor(jax.jacfwd(residual)(u0))

        def newton(u, _):
            return u - jax.scipy.linalg.lu_solve(lu, residual(u)), None

        u, _ = jax.lax.scan(newton, u0, None, length=self.iterations)
        q, qd, z = unpack(u)
        a, zd = f(t, q, qd, z)
        return State(t=t, q=q, qd=qd, qdd=a, z=z, zd=zd, iterations=jnp.asarray(self.iterations))


INTEGRATORS = {"rk4": RK4, "beeman": Beeman, "semi_implicit": SemiImplicitEuler,
               "newmark": Newmark, "verlet": Verlet}


def get(integrator) -> RK4 | Beeman | SemiImplicitEuler | Newmark | Verlet:
    """An integrator instance from a name (``rk4``, ``beeman``, ``semi_implicit``, ``newmark``,
    ``verlet``) or
    an instance (returned as is)."""
    if isinstance(integrator, str):
        try:
            return INTEGRATORS[integrator]()
        except KeyError:
            raise ValueError(f"integrator={integrator!r} is not known; accepted: "
                             f"{sorted(INTEGRATORS)} or an instance such as "
                             "mfm.integrators.Beeman(tol=0.01)") from None
    if not all(hasattr(integrator, a) for a in ("init", "step", "name")):
        raise TypeError(f"integrator={integrator!r} does not follow the protocol (init, step, name)")
    return integrator
