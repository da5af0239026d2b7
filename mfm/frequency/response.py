"""Frequency domain: static equilibrium, linearisation of the same model, RAOs, natural frequencies.

The model of :func:`mfm.simulate`, with exactly the loads it carries (its water, its config's
loads, and any ``loads=``), is linearised about its static equilibrium q₀ (DESIGN §4). With Q(q, q̇)
the generalised loads other than inertia (gravity, the loads at rest in still water —
:meth:`~mfm.loads.base.Load.static_load` — and the joint spring–dampers), jax gives

    K = −∂Q/∂q,   C = −∂Q/∂q̇   at (q₀, 0),   M = M*(q₀) + Σ (acceleration-proportional loads),

and each load adds what has memory or comes from the waves (:meth:`Load.frequency_terms`): the
water its radiation impedance −ω² Hᵀ(A(ω) − A∞)H − iω HᵀB(ω)H and its wave force Hᵀ X(ω, β).
With x(t) = Re[x̂ e^{−iωt}] (the hydro databases' convention):

    Z(ω) x̂ = F(ω),   Z(ω) = −ω² M − iω C + K + Σ Z_load(ω).

x̂ per metre of wave amplitude is the RAO of every coordinate; bodies, hydro dofs, PTOs and named
points follow from the same Jacobians. Quadratic drag has zero slope at rest (it drops out here;
:func:`mfm.spectral_response` linearises drag on the relative flow stochastically over a sea,
:mod:`mfm.frequency.drag`).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .. import host
from ..radiation import label as radiation_label
from ..loads.assembly import applied_loads, compile_view, state_offsets
from ..loads.base import Context
from ..mechanics.dynamics import Evaluation, gravity_loads, reaction_loads
from ..mechanics.kinematics import kinematics
from ..mechanics.model import Model
from .rest import _static_functions, linear_system
from ..validation import check_model


def _terms(model, sys, omega, heading, options):
    """Σ of the loads' impedances (n_ω, n_q, n_q) and wave forces (n_ω, n_q)."""
    n = model.n_coordinates
    Z = np.zeros((len(omega), n, n), dtype=complex)
    F = np.zeros((len(omega), n), dtype=complex)
    for ld in sys.loads:
        t = ld.frequency_terms(model, sys.q0, sys.kin0, omega, heading, options)
        if t.impedance is not None:
            Z = Z + t.impedance
        if t.force is not None:
            F = F + t.force
    return Z, F


def _system(model, sys, omega, heading, options):
    """Z(ω) = −ω² M − iω C + K + Σ Z_load(ω) (n_ω, n_q, n_q) and F(ω, β) (n_ω, n_q)."""
    Zl, F = _terms(model, sys, omega, heading, options)
    w = omega[:, None, None]
    return -w**2 * sys.M[None] - 1j * w * sys.C[None] + sys.K[None] + Zl, F


def _amplitudes(model, sys, omega, heading, options):
    """x̂ (n_ω, n_q) per metre of wave amplitude: [−ω² M − iω C + K + Σ Z_load(ω)] x̂ = F(ω, β)."""
    Z, F = _system(model, sys, omega, heading, options)
    return np.linalg.solve(Z, F[..., None])[..., 0]


def _reaction_function(model, loads):
    """The joint reactions of :func:`mfm.simulate` (``_record``: every load's
    :meth:`~mfm.loads.base.Load.reaction_loads` on the bodies, gravity, then
    :func:`mfm.mechanics.dynamics.reaction_loads`) as a function R(q, q̇, q̈) → (n, 6) [force; moment about
    the joint point], inertial axes, with the loads at rest in still water (their static loads):
    the joint springs and dampers, and loads acting on the coordinates directly, reach the joints
    through each body's Newton–Euler residual, as in the time domain."""
    model, static, mems = _static_functions(model, loads)
    offs = state_offsets(static)
    z = jnp.zeros(int(offs[-1]))

    def R(q, qd, qdd):
        kin = kinematics(model, q, qd)
        _, _, _, _, outs = applied_loads(model, static, 0.0, q, qd, z, kin, mems, with_outputs=True)
        F = gravity_loads(model)
        for k, (ld, out) in enumerate(zip(static, outs)):
            ctx = Context(model, 0.0, q, qd, z[offs[k]:offs[k + 1]], kin, mems[k], None, qdd)
            Fk = ld.reaction_loads(ctx, out)
            if Fk is not None:
                F = F + Fk
        Xdot = jnp.einsum("nai,i->na", kin.B, qdd) + kin.bias
        f, m = reaction_loads(model, Evaluation(qdd=qdd, kin=kin, X=kin.X, Xdot=Xdot, F=F, Q=None))
        return jnp.concatenate([f, m], axis=1)

    return R


@jax.jit
def _reaction_derivatives(model, loads, q0):
    """R(q₀, 0, 0) and ∂R/∂q, ∂R/∂q̇, ∂R/∂q̈ there (compiled once per model structure)."""
    R = _reaction_function(model, loads)
    zero = jnp.zeros_like(q0)
    return R(q0, zero, zero), jax.jacfwd(R, argnums=(0, 1, 2))(q0, zero, zero)


def _joint_reactions(model, sys, omega, heading, options, x):
    """(static (n, 6), complex amplitudes (n_ω, n, 6)): see :func:`joint_reactions`."""
    args = (*compile_view(model, sys.loads), jnp.asarray(sys.q0, jnp.float64))
    # run once per call: the host may compile it for a fast compilation and keep it
    derivatives = host.current().program(_reaction_derivatives, "reaction_derivatives", args, once=True)
    static, (Jq, Jv, Ja) = jax.tree_util.tree_map(np.asarray, derivatives(*args))
    w = omega[:, None, None, None]
    D = Jq[None] - 1j * w * Jv[None] - w**2 * Ja[None]           # (n_ω, n, 6, n_q)
    out = np.einsum("wnai,wi->wna", D, x)
    L = None   # the linear map of _wrench_reactions as a matrix (n, 6, n, 6)
    for ld in sys.loads:
        W = ld.frequency_body_loads(model, sys.q0, sys.kin0, omega, heading, options, x)
        if W is None:
            continue
        if L is None:
            L = np.asarray(_wrench_reactions(model.keyed(), sys.kin0))
        out = out + np.einsum("naKb,wKb->wna", L, W)
    return static, out


@jax.jit
def _wrench_reactions(model, kin0):
    """The reactions (n, 6) that balance extra body loads W (n, 6) at q₀, the bodies at rest, as
    the matrix ∂R/∂W (n, 6, n, 6) of that linear map: one jacobian, not one call per ω, and
    compiled (op by op, Wu & Yuan's first frequency response spent 2.6 s compiling its
    primitives one by one)."""
    zeros6 = jnp.zeros((model.n_bodies, 6))

    def of_wrench(W):
        f, m = reaction_loads(model, Evaluation(qdd=None, kin=kin0, X=zeros6, Xdot=zeros6, F=W,
                                                Q=None))
        return jnp.concatenate([f, m], axis=1)

    return jax.jacfwd(of_wrench)(zeros6)


def joint_reactions(model: Model, omega, x, *, heading: float = 0.0, q0=None, loads=None,
                    radiation: str = "database", state_space_options: dict | None = None):
    """The loads each joint transmits (the time domain's ``joint_force`` and ``joint_moment``: from
    the parent, or the inertial frame, to the body; inertial axes; moment about the joint point),
    linearised about q₀ for the coordinate amplitudes x (n_ω, n_q) (x(t) = Re[x̂ e^{−iωt}]).

    With R(q, q̇, q̈) the reactions of the time domain (:func:`mfm.mechanics.dynamics.reaction_loads` of each
    body's Newton–Euler residual M_i Ẋ_i + ω × J ω − F_i, summed from the leaves) under the loads
    at rest (gravity, hydrostatics and buoyancy, A∞, PTO μ/β/κ, joint springs and dampers),

        R̂(ω) = (∂R/∂q − iω ∂R/∂q̇ − ω² ∂R/∂q̈) x̂ + L(Ŵ(ω)),

    all derivatives at (q₀, 0, 0) (jax), Ŵ(ω) the body loads of each load's frequency terms
    (:meth:`~mfm.loads.base.Load.frequency_body_loads`: the water's excitation X(ω, β) and its
    radiation memory −[−ω²(A(ω) − A∞) − iωB(ω)] H₀ x̂) and L the (linear) reaction that balances a
    body load on bodies at rest. Products of two first-order quantities (the rotation of a
    first-order load, Ḣq̇, gyroscopic terms) are second order and drop out; the static preload
    R(q₀, 0, 0) is returned separately.

    Along a joint's free directions the result is the joint's own generalised load (its spring and
    damper: −(k − iωc) x̂ for a hinge); across them, the constraint load.

    Returns (static (n_bodies, 6) N and N m, amplitudes (n_ω, n_bodies, 6) N/m and N m/m per metre of
    wave amplitude when x is a RAO); the last axis is (fx, fy, fz, mx, my, mz). Raises
    NotImplementedError naming a load whose frequency terms cannot be put on the bodies.
    """
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    x = np.asarray(x)
    if x.shape != (omega.size, model.n_coordinates):
        raise ValueError(f"x: shape {x.shape}; expected (n_omega, n_coordinates) = "
                         f"({omega.size}, {model.n_coordinates})")
    sys = linear_system(model, q0, loads=loads)
    options = {"radiation": radiation, "state_space_options": state_space_options}
    return _joint_reactions(model, sys, omega, float(heading), options, x)


class Raos(NamedTuple):
    """The numbers of :func:`solve_raos` (the dataset of :func:`mfm.frequency_response`)."""
    loads: tuple            # the loads of the linearisation
    omega: np.ndarray       # (n_ω,) rad/s
    x: np.ndarray           # (n_ω, n_coordinates) complex, per metre of wave amplitude
    q0: np.ndarray
    kin0: object            # the kinematics at q0
    heading: float
    settings: dict
    extra: list             # the loads' own outputs
    reactions: tuple | None


def solve_raos(model: Model, omega, heading: float = 0.0, *, q0=None,
               radiation: str = "database", state_space_options: dict | None = None,
               loads=None, joint_reactions: bool = True) -> Raos:
    """Complex RAOs (per metre of wave amplitude, x(t) = Re[x̂ e^{−iωt}]) of every coordinate,
    body (CoM displacement and small rotation, inertial axes), hydro dof and PTO, with the absorbed
    power per unit wave amplitude squared, from the model linearised about its equilibrium with
    every load it carries and ``loads``.

    omega: rad/s, inside the database's range. heading: rad (direction the waves travel to,
    from +x towards +y).
    radiation: which A(ω), B(ω): "database" (the BEM values), or exactly those of the time-domain
    models, "convolution" or "state_space" (:mod:`mfm.loads.radiation`); ``state_space_options``
    as given to :func:`mfm.simulate` (the same options give the same fit).

    Returns :class:`Raos`; :func:`mfm.frequency_response` returns it as an xarray.Dataset:
    ``rao`` (omega, coordinate), ``body_rao`` (omega, body, dof) with
    dof = x, y, z, rx, ry, rz, ``xi_rao`` (omega, hydro_dof), ``pto_rao`` and ``pto_power``
    (omega, pto) (W/m², mean power ½ c ω² |x̂|²), the loads' own outputs (``hydraulic_pto_power``,
    ``point_rao``, ``hydraulic_pto_force_rao``, …), ``equilibrium`` (coordinate); with
    ``joint_reactions`` (default) ``joint_force_rao`` and ``joint_moment_rao`` (omega, body, axis)
    per metre of wave amplitude and the static preload ``joint_force_static``,
    ``joint_moment_static`` (body, axis) (:func:`joint_reactions`).
    """
    model = check_model(model)
    if model.hydro is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: frequency_response needs a "
                         "config with a [hydro] table (and mfm.load(..., hydro=True))")
    try:
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"omega: {omega!r} is not an array of frequencies (rad/s)") from None
    if omega.ndim != 1 or omega.size == 0 or not np.all(np.isfinite(omega)) or np.any(omega <= 0):
        raise ValueError(f"omega: give positive, finite frequencies in rad/s (got {omega!r})")
    from hydro.waves import check_heading

    heading = check_heading(heading)     # radians: a heading in degrees warns with the fix
    options = {"radiation": radiation, "state_space_options": state_space_options}
    sys = linear_system(model, q0, loads=loads)
    x = _amplitudes(model, sys, omega, heading, options)
    extra = [ld.frequency_outputs(model, sys.kin0, x, omega) for ld in sys.loads]
    reactions = _joint_reactions(model, sys, omega, heading, options, x) if joint_reactions else None
    settings = {"radiation": radiation_label(radiation)}
    if state_space_options:
        settings["state_space_options"] = repr(state_space_options)
    return Raos(sys.loads, omega, x, sys.q0, sys.kin0, heading, settings,
                [e for e in extra if e], reactions)


def _frequency_range(loads):
    lo, hi = 0.0, math.inf
    for ld in loads:
        r = ld.frequency_range()
        if r is not None:
            lo, hi = max(lo, r[0]), min(hi, r[1])
    return lo, hi


def _mass_and_damping_at(model, sys, w, options):
    """M(ω) = M + Re Σ Z_load(ω)/(−ω²) and the loads' damping −Im Σ Z_load(ω)/ω at ω clipped to
    where every load is defined (A(ω) held at the ends of a database)."""
    lo, hi = _frequency_range(sys.loads)
    wc = np.clip(np.atleast_1d(w), lo, hi)
    Z, _ = _terms(model, sys, wc, 0.0, dict(options, excitation=False))
    return sys.M[None] + Z.real / (-wc[:, None, None] ** 2), -Z.imag / wc[:, None, None]
