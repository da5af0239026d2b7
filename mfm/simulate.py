"""Time-domain simulation: a pure jax rollout, compiled once, and its labelled dataset.

``rollout`` is the pure core (``lax.scan`` over steps; vmap- and grad-friendly); ``simulate`` is the
front door: it checks the inputs, runs the compiled rollout, stops with a clear error if the state
went non-finite, and returns an :class:`xarray.Dataset`.
"""
from __future__ import annotations

import collections
import datetime
import math
import warnings
from typing import Sequence

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from . import integrators as _integrators
from . import se3
from .dynamics import energies, evaluate, mass_matrix, reaction_loads
from .kinematics import kinematics
from .loads import Load
from .model import Model

# How many times each compiled function was traced (a retrace means a recompilation); tests use it.
TRACES: collections.Counter = collections.Counter()


class StabilityWarning(UserWarning):
    """dt is beyond the integrator's stability limit for the model's shortest natural period."""


class SimulationError(RuntimeError):
    """The simulation went non-finite; the message gives the time, the state and the likely cause."""


def model_loads(model: Model, sea=None, *, dt, duration, t0=0.0, ramp=0.0,
                radiation="convolution", memory=None, state_space_options=None,
                added_mass="lhs") -> tuple[Load, ...]:
    """The loads a model carries itself: its moorings and, with a [hydro] config, its water for
    this sea and time grid (see :func:`mfm.water.build_water`). Pass them to :func:`rollout`."""
    out = []
    if model.hydro is not None:
        from .water import build_water

        out.append(build_water(model, model.hydro, sea, dt=dt, duration=duration, t0=t0, ramp=ramp,
                               radiation=radiation, memory=memory,
                               state_space_options=state_space_options, added_mass=added_mass))
    if model.moorings is not None:
        out.append(model.moorings)
    if model.ptos is not None:
        out.append(model.ptos)
    return tuple(out)


def _as_loads(loads) -> tuple[Load, ...]:
    if loads is None:
        return ()
    if isinstance(loads, Load):
        return (loads,)
    loads = tuple(loads)
    for ld in loads:
        if not isinstance(ld, Load):
            raise TypeError(f"loads: {ld!r} is not an mfm.loads.Load")
    return loads


def _state_offsets(loads: Sequence[Load]) -> np.ndarray:
    """Where each load's states start in z (they are concatenated in ``loads`` order)."""
    return np.concatenate([[0], np.cumsum([ld.n_states for ld in loads])]).astype(int)


def applied_loads(model: Model, loads: Sequence[Load], t, q, qd, z, kin, memories=None,
                  with_outputs=False, qdd_guess=None):
    """Sum the external loads at one state: (body (n, 6) | None, tau (n_q,) | None,
    mass (n_q, n_q) | None, zd (n_states,)), plus the per-load outputs if ``with_outputs``.
    Load states are concatenated in z in ``loads`` order."""
    offsets = _state_offsets(loads)
    memories = memories if memories is not None else tuple(() for _ in loads)
    body = tau = mass = None
    zds, outs = [], []
    for k, ld in enumerate(loads):
        out = ld(model, t, q, qd, z[offsets[k]:offsets[k + 1]], kin, memories[k], qdd_guess=qdd_guess)
        outs.append(out)
        if out.body is not None:
            body = out.body if body is None else body + out.body
        if out.tau is not None:
            tau = out.tau if tau is None else tau + out.tau
        if out.mass is not None:
            mass = out.mass if mass is None else mass + out.mass
        zds.append(jnp.zeros(ld.n_states) if out.zd is None else out.zd)
    zd = jnp.concatenate(zds) if zds else jnp.zeros(0)
    if with_outputs:
        return body, tau, mass, zd, outs
    return body, tau, mass, zd


def dynamics_function(model: Model, loads: Sequence[Load] = (), memories=None):
    """The system ``f(t, q, q̇, z) -> (q̈, ż)`` of the integrators: MFM equations of motion plus the
    external loads (with their memories of the current step)."""

    def f(t, q, qd, z, qdd_guess=None):
        kin = kinematics(model, q, qd)
        body, tau, mass, zd = applied_loads(model, loads, t, q, qd, z, kin, memories,
                                            qdd_guess=qdd_guess)
        return evaluate(model, q, qd, tau=tau, body_loads=body, extra_mass=mass, kin=kin).qdd, zd

    return f


def _init_memories(model, loads, t0, q0, qd0, dt):
    return tuple(ld.init_memory(model, t0, q0, qd0, dt) for ld in loads)


def _update_memories(model, loads, s, memories):
    if not loads:
        return memories
    kin = kinematics(model, s.q, s.qd)
    return tuple(ld.update_memory(model, s.t, s.q, s.qd, kin, mem) for ld, mem in zip(loads, memories))


def _record(model, loads, s, mem):
    """What the dataset keeps of one saved state: poses, reactions, energies, load diagnostics."""
    kin = kinematics(model, s.q, s.qd)
    body, tau, mass, _, outs = applied_loads(model, loads, s.t, s.q, s.qd, s.z, kin, mem,
                                             with_outputs=True, qdd_guess=s.qdd)
    ev = evaluate(model, s.q, s.qd, tau=tau, body_loads=body, extra_mass=mass, kin=kin)
    offs = _state_offsets(loads)
    # the joints carry every load on the bodies, acceleration-proportional ones included
    F = None
    diag = {}
    for k, (ld, out) in enumerate(zip(loads, outs)):
        zk = s.z[offs[k]:offs[k + 1]]
        Fk = ld.reaction_loads(model, s.t, s.q, s.qd, ev.qdd, zk, kin, mem[k], out)
        if Fk is not None:
            F = Fk if F is None else F + Fk
        diag.update(ld.diagnostics(model, s.t, s.q, s.qd, ev.qdd, zk, kin, mem[k], out))
    ev_r = ev._replace(F=ev.F - (0.0 if body is None else body) + (0.0 if F is None else F))
    f_j, m_j = reaction_loads(model, ev_r)
    T, V = energies(model, s.q, s.qd)
    angles = jax.vmap(se3.euler_zyx)(kin.E[:, :3, :3])
    return dict(body_position=kin.E[:, :3, 3], body_rotation=angles, joint_force=f_j,
                joint_moment=m_j, kinetic_energy=T, potential_energy=V, qdd=ev.qdd, **diag)


def _rollout_impl(model, loads, q0, qd0, z0, t0, dt, n_steps, integrator, save_every, record):
    TRACES["rollout"] += 1
    mem0 = _init_memories(model, loads, t0, q0, qd0, dt)
    state = integrator.init(dynamics_function(model, loads, mem0), t0, q0, qd0, z0)

    def one_step(carry, _):
        s, mem = carry
        s = integrator.step(dynamics_function(model, loads, mem), s, dt)
        return (s, _update_memories(model, loads, s, mem)), None

    def saved(s, mem):
        out = (s.t, s.q, s.qd, s.qdd, s.z, s.iterations)
        return out + ((_record(model, loads, s, mem),) if record else ())

    def block(carry, _):
        carry, _ = jax.lax.scan(one_step, carry, None, length=save_every)
        return carry, saved(*carry)

    _, traj = jax.lax.scan(block, (state, mem0), None, length=n_steps // save_every)
    first = saved(state, mem0)
    return jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a[None], b]), first, traj)


_rollout_jit = jax.jit(_rollout_impl,
                       static_argnames=("n_steps", "integrator", "save_every", "record"))


def rollout(model: Model, q0, qd0, *, dt, n_steps: int, integrator="rk4", loads=None,
            save_every: int = 1, t0=0.0, z0=None, record: bool = False):
    """Pure, jit-compiled rollout: returns ``(t, q, qd, qdd, z, iterations)`` arrays with a leading
    time axis of length ``n_steps // save_every + 1`` (the initial state first).

    Compiled once per (topology, n_steps, integrator, save_every, loads structure): changing any
    array parameter of ``model`` or ``loads``, ``dt``, ``q0``, ``qd0`` reuses the compiled code, and
    the function can be ``jax.vmap``-ed over a batched model or ``jax.grad``-ed (RK4, semi-implicit
    and Newmark; Beeman's while loop is forward-mode only). ``record=True`` appends a dict of
    per-sample outputs (poses, joint reactions, energies, load diagnostics) as a 7th item.
    """
    loads = _as_loads(loads)
    integ = _integrators.get(integrator)
    q0 = jnp.asarray(q0, jnp.float64)
    qd0 = jnp.asarray(qd0, jnp.float64)
    if z0 is None:
        parts = [ld.initial_state(model) for ld in loads]
        z0 = jnp.concatenate(parts) if parts else jnp.zeros(0)
    return _rollout_jit(model, loads, q0, qd0, jnp.asarray(z0, jnp.float64),
                        jnp.asarray(t0, jnp.float64), jnp.asarray(dt, jnp.float64),
                        n_steps=int(n_steps), integrator=integ, save_every=int(save_every),
                        record=record)


def _initial_vector(model: Model, value, what: str) -> np.ndarray:
    n = model.n_coordinates
    if value is None:
        return np.zeros(n)
    if isinstance(value, dict):
        out = np.zeros(n)
        for k, v in value.items():
            try:
                out[model.coordinate_index(k)] = float(v)
            except KeyError:
                raise ValueError(f"{what}: {k!r} is not a coordinate of {model.name!r}; "
                                 f"coordinates: {list(model.coordinates)}") from None
        return out
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n,):
        raise ValueError(f"{what}: shape {arr.shape} does not match the {n} coordinates "
                         f"{list(model.coordinates)}; give an array of shape ({n},) or a dict")
    return arr


@jax.jit
def _stiffness_jacobian(model, loads, q):
    """∂q̈/∂q at (q, q̇ = 0, z = 0, t = 0): compiled once per model and loads structure."""
    TRACES["stiffness"] += 1
    qd0 = jnp.zeros(model.n_coordinates)
    mems = _init_memories(model, loads, 0.0, q, qd0, 1.0)
    f = dynamics_function(model, loads, mems)
    z0 = jnp.zeros(sum(ld.n_states for ld in loads))
    return jax.jacfwd(lambda x: f(0.0, x, qd0, z0)[0])(q)


def shortest_natural_period(model: Model, q, loads=()) -> float:
    """Estimate of the shortest natural period (s) at configuration q (q̇ = 0): 2π/√λ_max with λ
    the eigenvalues of −∂q̈/∂q (jax Jacobian of the full dynamics: its mass matrix, added mass
    included, and every restoring load). Returns inf when nothing is restoring."""
    Jq = _stiffness_jacobian(model, _as_loads(loads), jnp.asarray(q, jnp.float64))
    lam = np.linalg.eigvals(-np.asarray(Jq)).real
    lam_max = lam.max() if lam.size else 0.0
    return math.inf if lam_max <= 0 else 2.0 * math.pi / math.sqrt(lam_max)


def _raise_nonfinite(model, integ, t, q, qd, dt, loads):
    bad = ~(np.isfinite(q).all(axis=1) & np.isfinite(qd).all(axis=1))
    k = int(np.argmax(bad))
    coords = [model.coordinates[j] for j in range(model.n_coordinates)
              if not (np.isfinite(q[k, j]) and np.isfinite(qd[k, j]))]
    k_ok = max(k - 1, 0)
    for ld in loads:
        if getattr(ld, "added_mass", "lhs") == "rhs":
            # the fixed-point iteration a ← M*⁻¹(F − Hᵀ A∞ H a) contracts only if the spectral
            # radius of M*⁻¹ Hᵀ A∞ H is below 1
            kin = kinematics(model, q[k_ok], qd[k_ok])
            H = np.asarray(ld.geometry.h_matrix(kin)[0])
            Ms = np.asarray(mass_matrix(model, q[k_ok]))
            r = float(np.abs(np.linalg.eigvals(np.linalg.solve(Ms, H.T @ np.asarray(ld.A_inf) @ H))).max())
            if r >= 1.0:
                raise SimulationError(
                    f"the state went non-finite at t = {t[k]:.6g} s in coordinate(s) {coords}. "
                    f"Likely cause: added_mass='rhs' (the seed 001 iteration of A∞ ξ̈ on the "
                    f"right-hand side) diverges here: the spectral radius of M*⁻¹ Hᵀ A∞ H is "
                    f"{r:.3g} ≥ 1 (added mass larger than the structural mass). Use "
                    "added_mass='lhs' (A∞ in M*, no iteration).")
    T_min = shortest_natural_period(model, q[k_ok], loads)
    lines = [f"the state went non-finite at t = {t[k]:.6g} s (first saved sample; last finite at "
             f"t = {t[k_ok]:.6g} s) in coordinate(s) {coords}."]
    if math.isfinite(T_min):
        ratio = 2 * math.pi * dt / T_min
        lines.append(f"Likely cause: dt = {dt:.4g} s against the shortest natural period "
                     f"{T_min:.4g} s (ω dt = {ratio:.3g}; {integ.name} is stable for ω dt < "
                     f"{integ.stability_limit:.3g}).")
        if ratio >= 0.5 * integ.stability_limit:
            lines.append(f"Reduce dt below {T_min * integ.stability_limit / (4 * math.pi):.3g} s or "
                         "use integrator='newmark'.")
        else:
            lines.append("dt is inside the stability limit, so look at the loads or the model: "
                         "large rotations of a free root near pitch = ±90° (Euler angle "
                         "singularity), a load that grows without bound, or a bad parameter.")
    else:
        lines.append("No restoring stiffness at the last finite state: look at the loads, a "
                     "parameter, or a free root near pitch = ±90° (Euler angle singularity).")
    raise SimulationError(" ".join(lines))


def simulate(model: Model, sea=None, *, duration: float, dt: float, integrator="rk4",
             q0=None, qd0=None, loads=None, save_every: int = 1, t0: float = 0.0,
             ramp: float = 0.0, radiation: str = "convolution", memory: float | None = None,
             state_space_options: dict | None = None, check_stability: bool = True,
             added_mass: str = "lhs") -> xr.Dataset:
    """Simulate a model in the time domain.

    Parameters
    ----------
    model: a compiled :class:`~mfm.model.Model` (with its water if the config has ``[hydro]``).
    sea: a sea state from :mod:`hydro.waves` (``Regular``, ``Jonswap``, …), or None (still water,
        or no water at all for a mechanics-only model).
    duration, dt: s. The run has ``round(duration / dt)`` steps.
    integrator: ``"rk4"`` (default), ``"beeman"`` (seed 001 eq. 52), ``"semi_implicit"``,
        ``"newmark"``, or an instance from :mod:`mfm.integrators`.
    q0, qd0: initial coordinates and rates, arrays (n_q,) or dicts by coordinate name (others 0).
    loads: an :class:`mfm.loads.Load` or a sequence of them (external loads).
    save_every: keep every k-th step in the output.
    ramp: s, the start-up ramp of the excitation (½(1 − cos πt/ramp)).
    radiation: ``"convolution"`` (direct, window T_K from the decay of K; ``memory`` overrides it,
        s), ``"state_space"`` (the passive fit of :mod:`hydro.statespace`, options in
        ``state_space_options``) or ``"none"`` (A∞ only).
    added_mass: ``"lhs"`` (A∞ in M*, the default) or ``"rhs"``: the scheme of seed 001 §5, A∞ ξ̈
        on the right-hand side with the acceleration iterated in Beeman's corrector (needs
        ``integrator="beeman"``; converges only where A∞ is smaller than the structural mass; the
        iteration counts are in ``iterations``).
    check_stability: warn (:class:`StabilityWarning`) before running when dt exceeds the
        integrator's stability limit at the shortest natural period of the model linearised at q0.

    Returns an :class:`xarray.Dataset` with ``q``, ``qd``, ``qdd`` (time, coordinate),
    ``body_position`` (time, body, axis) CoM in inertial axes, ``body_rotation`` (time, body, angle)
    roll/pitch/yaw (R = R_z(yaw) R_y(pitch) R_x(roll)), ``joint_force`` and ``joint_moment``
    (time, body, axis): the load each body's joint transmits from the parent (inertial axes, moment
    about the joint point), ``kinetic_energy`` and ``potential_energy`` (time), ``iterations``
    (corrector iterations of the step), ``pto_power`` and ``pto_displacement`` (time, pto) for each
    joint damper; with water also ``eta`` (time), ``xi`` (time, hydro_dof) and ``hydro_force``
    (time, component, hydro_dof). Units and provenance are in the attributes.

    Raises :class:`SimulationError` when the state goes non-finite.
    """
    if sea is not None and model.hydro is None:
        raise ValueError("sea: this model has no hydrodynamics (no [hydro] table in its config, or "
                         "mfm.load(..., hydro=False)); pass sea=None")
    if not (dt > 0 and math.isfinite(dt)):
        raise ValueError(f"dt: {dt!r} must be a positive number of seconds")
    if not (duration > 0 and math.isfinite(duration)):
        raise ValueError(f"duration: {duration!r} must be a positive number of seconds")
    n_steps = int(round(duration / dt))
    if n_steps < 1:
        raise ValueError(f"duration = {duration} s is shorter than one step dt = {dt} s")
    if save_every < 1 or n_steps % save_every:
        raise ValueError(f"save_every: {save_every} must be a positive divisor of the {n_steps} "
                         "steps")
    if ramp < 0:
        raise ValueError(f"ramp: {ramp!r} must be ≥ 0 s")
    integ = _integrators.get(integrator)
    if added_mass not in ("lhs", "rhs"):
        raise ValueError(f"added_mass={added_mass!r}; accepted: 'lhs' (A∞ in M*), 'rhs' (seed 001)")
    if added_mass == "rhs" and integ.name != "beeman":
        raise ValueError(f"added_mass='rhs' (the seed 001 scheme) iterates the acceleration in "
                         f"Beeman's corrector; integrator={integ.name!r} has none: use "
                         "integrator='beeman' or added_mass='lhs'")
    loads = model_loads(model, sea, dt=dt, duration=duration, t0=t0, ramp=ramp, radiation=radiation,
                        memory=memory, state_space_options=state_space_options,
                        added_mass=added_mass) + _as_loads(loads)
    q0 = _initial_vector(model, q0, "q0")
    qd0 = _initial_vector(model, qd0, "qd0")
    if check_stability and math.isfinite(integ.stability_limit):
        T_min = shortest_natural_period(model, q0, loads)
        if math.isfinite(T_min) and 2 * math.pi * dt / T_min > integ.stability_limit:
            warnings.warn(
                f"dt = {dt:.4g} s is beyond the stability limit of {integ.name}: the shortest natural "
                f"period of the model linearised at q0 is {T_min:.4g} s, ω dt = "
                f"{2 * math.pi * dt / T_min:.3g} > {integ.stability_limit:.3g}. Use dt < "
                f"{T_min * integ.stability_limit / (2 * math.pi):.3g} s or integrator='newmark'.",
                StabilityWarning, stacklevel=2)
    out = rollout(model, q0, qd0, dt=dt, n_steps=n_steps, integrator=integ, loads=loads,
                  save_every=save_every, t0=t0, record=True)
    t, q, qd, qdd, z, iters = (np.asarray(a) for a in out[:6])
    if not (np.isfinite(q).all() and np.isfinite(qd).all()):
        _raise_nonfinite(model, integ, t, q, qd, dt, loads)
    rec = {k: np.asarray(v) for k, v in out[6].items()}
    ds = _dataset(model, integ, dt, t, q, qd, rec["qdd"], iters, rec)
    for ld in loads:
        ds = ld.annotate(ds, rec)
    return ds


def _dataset(model, integ, dt, t, q, qd, qdd, iters, rec) -> xr.Dataset:
    pos, ang, f_j, m_j = (rec[k] for k in ("body_position", "body_rotation", "joint_force",
                                           "joint_moment"))
    T, V = rec["kinetic_energy"], rec["potential_energy"]
    coords = {"time": ("time", t, {"units": "s"}),
              "coordinate": list(model.coordinates),
              "body": list(model.body_names),
              "axis": ["x", "y", "z"],
              "angle": ["roll", "pitch", "yaw"]}
    units = [_coordinate_unit(model, c) for c in model.coordinates]
    ds = xr.Dataset(
        {
            "q": (("time", "coordinate"), q, {"long_name": "generalised coordinates",
                                              "units": "m or rad (see coordinate_unit)"}),
            "qd": (("time", "coordinate"), qd, {"long_name": "generalised velocities",
                                                "units": "m/s or rad/s"}),
            "qdd": (("time", "coordinate"), qdd, {"long_name": "generalised accelerations",
                                                  "units": "m/s2 or rad/s2"}),
            "coordinate_unit": (("coordinate",), units),
            "body_position": (("time", "body", "axis"), pos,
                              {"long_name": "centre of mass position, inertial axes", "units": "m"}),
            "body_rotation": (("time", "body", "angle"), ang,
                              {"long_name": "body orientation as roll, pitch, yaw with "
                               "R = Rz(yaw) Ry(pitch) Rx(roll)", "units": "rad"}),
            "joint_force": (("time", "body", "axis"), f_j,
                            {"long_name": "force the joint of each body transmits from its parent "
                             "(or the inertial frame) to the body, inertial axes", "units": "N"}),
            "joint_moment": (("time", "body", "axis"), m_j,
                             {"long_name": "moment the joint of each body transmits, about the joint "
                              "point, inertial axes", "units": "N m"}),
            "kinetic_energy": (("time",), T, {"units": "J"}),
            "potential_energy": (("time",), V, {"long_name": "gravity and joint springs",
                                                "units": "J"}),
            "iterations": (("time",), iters, {"long_name": "corrector iterations of the step"}),
        },
        coords=coords,
        attrs={
            "title": f"mfm simulation of {model.name}",
            "model": model.name,
            "integrator": integ.name,
            "integrator_settings": repr(integ),
            "dt": float(dt),
            "dt_units": "s",
            "mfm_version": _version(),
            "jax_version": jax.__version__,
            "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "conventions": "inertial frame: origin on the still-water line, z up; body frames at "
                           "the CoM, parallel to inertial at q = 0",
        },
    )
    damped, power = _damper_power(np.asarray(model.damping), qd)
    if damped:
        ds = ds.assign_coords(pto=[model.coordinates[k] for k in damped])
        ds["pto_power"] = (("time", "pto"), power, _PTO_POWER_ATTRS)
        ds["pto_displacement"] = (("time", "pto"), q[:, damped],
                                  {"long_name": "joint coordinate of each damper (relative angle or "
                                   "stroke)", "units": "rad or m"})
    return ds


_PTO_POWER_ATTRS = {"long_name": "power absorbed by each joint damper, c q̇²", "units": "W"}


def _damper_power(damping, qd):
    """The coordinates with a joint damper (c > 0 in any case) and the power c q̇² of each:
    damping (n_q,) or (case, n_q), qd (…, time, n_q) → (indices, (…, time, n_damped))."""
    damped = [int(k) for k in np.flatnonzero(np.any(np.atleast_2d(damping) > 0, axis=0))]
    c = damping[..., damped]
    return damped, (c[..., None, :] if c.ndim > 1 else c) * qd[..., damped] ** 2


def _coordinate_unit(model: Model, name: str) -> str:
    for i, motions in enumerate(model.motions):
        for kind, k in motions:
            if model.coordinates[k] == name:
                return "rad" if kind == "R" else "m"
    return ""


def _version() -> str:
    try:
        from importlib.metadata import version
        return version("mfm")
    except Exception:  # not installed (running from a source tree)
        return "unknown"


def simulate_batch(model, seas, *, dt, n_steps: int, integrator="rk4", ramp=0.0,
                   radiation: str = "state_space", state_space_options: dict | None = None,
                   memory: float | None = None, save_every: int = 1, t0: float = 0.0,
                   q0=None, qd0=None) -> xr.Dataset:
    """Many runs of one topology in one compiled, ``jax.vmap``-ed call: a sweep over sea states,
    time steps and model parameters (a power matrix, a T_p sweep at dt = T_p/200, a hinge-height
    study) without retracing.

    model: a :class:`Model`, or a sequence of Models of one topology (parameters differ, e.g.
        made with ``equinox.tree_at``; their ``hydro`` must be the same object).
    seas: a sea state or a sequence of them (``hydro.waves``; None for still water).
    dt, ramp: s, a number or one per case. Every case runs ``n_steps`` steps (so a sweep at
        dt = T_p/200 over 100 T_p is one shape: 20,000 steps).
    radiation: "state_space" (default; its arrays have one shape whatever dt), "none", or
        "convolution" (only when every case has the same number of lags, e.g. one dt).
    Sequences of length > 1 must agree in length B; length-1 arguments are broadcast.

    Returns an :class:`xarray.Dataset` with dimensions (case, step, coordinate): ``time``
    (case, step), ``q``, ``qd``, ``pto_power`` (case, step, pto) of the joint dampers, ``eta``
    (case, step) the undisturbed elevation at the origin, and ``dt`` (case).
    Raises :class:`SimulationError` naming the first case that goes non-finite.
    """
    models = list(model) if isinstance(model, (list, tuple)) else [model]
    seas = list(seas) if isinstance(seas, (list, tuple)) else [seas]
    dts = np.atleast_1d(np.asarray(dt, dtype=float))
    ramps = np.atleast_1d(np.asarray(ramp, dtype=float))
    sizes = {"model": len(models), "seas": len(seas), "dt": dts.size, "ramp": ramps.size}
    B = max(sizes.values())
    bad = {k: v for k, v in sizes.items() if v not in (1, B)}
    if bad:
        raise ValueError(f"simulate_batch: the batched arguments must have one length or 1; got "
                         f"{sizes}")
    if not (np.all(dts > 0) and np.all(np.isfinite(dts))):
        raise ValueError(f"dt: {dts} must be positive numbers of seconds")
    if n_steps < 1 or n_steps % save_every:
        raise ValueError(f"n_steps: {n_steps} must be ≥ 1 and a multiple of save_every={save_every}")
    pick = lambda seq, i: seq[i if len(seq) > 1 else 0]  # noqa: E731
    structure = {m_.coordinates for m_ in models}
    if len(structure) > 1 or len({id(m_.hydro) for m_ in models}) > 1:
        raise ValueError("model: the models of a batch must share one topology and one hydro "
                         "spec (make them from one Model with equinox.tree_at)")
    integ = _integrators.get(integrator)
    loads = [model_loads(pick(models, i), pick(seas, i), dt=float(pick(dts, i)),
                         duration=n_steps * float(pick(dts, i)), t0=t0, ramp=float(pick(ramps, i)),
                         radiation=radiation, memory=memory,
                         state_space_options=state_space_options) for i in range(B)]
    defs = {jax.tree_util.tree_structure(ld) for ld in loads}
    if len(defs) > 1:
        raise ValueError("simulate_batch: the cases' loads differ in structure (with "
                         "radiation='convolution' the number of lags follows dt: give every case "
                         "the same dt and memory, or use radiation='state_space')")
    stack = lambda items: jax.tree_util.tree_map(lambda *a: jnp.stack(a), *items)  # noqa: E731
    m0 = models[0]
    q0 = jnp.asarray(_initial_vector(m0, q0, "q0"))
    qd0 = jnp.asarray(_initial_vector(m0, qd0, "qd0"))
    parts = [ld.initial_state(m0) for ld in loads[0]]
    z0 = jnp.concatenate(parts) if parts else jnp.zeros(0)
    batched_model = stack([pick(models, i) for i in range(B)]) if len(models) > 1 else m0

    def one(m_, lds, d):
        return _rollout_jit(m_, lds, q0, qd0, z0, jnp.asarray(t0, jnp.float64), d, n_steps=int(n_steps),
                            integrator=integ, save_every=int(save_every), record=False)

    out = jax.vmap(one, in_axes=(0 if len(models) > 1 else None, 0, 0))(
        batched_model, stack(loads), jnp.asarray(np.broadcast_to(dts, (B,)).copy()))
    t, q, qd = (np.asarray(a) for a in out[:3])
    for i in range(B):
        if not (np.isfinite(q[i]).all() and np.isfinite(qd[i]).all()):
            k = int(np.argmax(~np.isfinite(q[i]).all(axis=1) | ~np.isfinite(qd[i]).all(axis=1)))
            raise SimulationError(f"simulate_batch: case {i} went non-finite at t = {t[i, k]:.6g} s "
                                  f"(dt = {pick(dts, i):.4g} s); run it alone with mfm.simulate "
                                  "for the diagnosis")
    coords = {"case": np.arange(B), "coordinate": list(m0.coordinates)}
    ds = xr.Dataset(
        {"time": (("case", "step"), t, {"units": "s"}),
         "q": (("case", "step", "coordinate"), q, {"long_name": "generalised coordinates",
                                                   "units": "m or rad"}),
         "qd": (("case", "step", "coordinate"), qd, {"long_name": "generalised velocities",
                                                     "units": "m/s or rad/s"}),
         "dt": (("case",), np.broadcast_to(dts, (B,)).copy(), {"units": "s"})},
        coords=coords,
        attrs={"title": f"mfm batch of {B} runs of {m0.name}", "model": m0.name,
               "integrator": integ.name, "radiation": radiation, "n_steps": int(n_steps),
               "save_every": int(save_every), "mfm_version": _version(),
               "jax_version": jax.__version__,
               "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")})
    damped, power = _damper_power(np.stack([np.asarray(pick(models, i).damping) for i in range(B)]), qd)
    if damped:
        ds = ds.assign_coords(pto=[m0.coordinates[k] for k in damped])
        ds["pto_power"] = (("case", "step", "pto"), power, _PTO_POWER_ATTRS)
    k = next((k for k, ld in enumerate(loads[0]) if hasattr(ld, "eta_values")), None)
    if k is not None:
        eta = np.stack([np.asarray(loads[i][k].eta_values)[::2 * save_every][:t.shape[1]]
                        for i in range(B)])
        ds["eta"] = (("case", "step"), eta, {"long_name": "wave elevation at the origin", "units": "m"})
    return ds
