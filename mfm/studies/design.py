"""The design parameters of a model and its spectral responses as one pure jax function of them:
what :func:`mfm.optimize` (:mod:`mfm.studies.optimize`) differentiates and searches.

For each sea s with components a_sj at (ω_j, β_j) (the union of every sea's pairs):

    q₀(θ):  Q(q₀, 0; θ) = 0                        (the static equilibrium; implicit derivative)
    M, K, C at q₀(θ)                               (the jet of :mod:`mfm.frequency.rest`;
                                                    K + diag(k_c): controllers about q₀)
    Z_j(θ) = −ω_j² M − iω_j (C + C_drag,s) + K + Hᵀ[−ω_j²(A(ω_j) − A∞) − iω_j B(ω_j)]H
    x̂_sj = Z_j⁻¹ Hᵀ X(ω_j, β_j)                    (RAO per metre, H = H(q₀(θ)))
    P_s = Σ_p Σ_j a_sj² ½ c_p ω_j² |G_p x̂_sj|²      (mean power of each PTO p, rate ẇ = G_p q̇)
    σ_{q,s}² = Σ_j ½ a_sj² |x̂_sj|²                  (variance of each coordinate; of a stroke with G)

the frequency domain's equations (:mod:`mfm.frequency.response`, :mod:`mfm.runner.spectral`),
written in jax so that θ — joint dampings and stiffnesses, controller stiffnesses about q₀, body masses, hydraulic μ, β, κ, linear
mooring stiffnesses, named as the config and the coordinates are (:func:`tunable_parameters`) —
are arguments of one compiled function (their structure, not their values, is its key).

Quadratic drag −D |v| v on a hydro dof (D = ½ ρ C_D A, :mod:`mfm.loads.water`) is linearised
stochastically (Borgman): for a Gaussian velocity of standard deviation σ_v, the linear damping
with the same mean power is c_eq = D √(8/π) σ_v; σ_v depends on c_eq, so the pair is iterated to a
fixed point for each sea. Catenary lines' fairlead tensions are linearised as the frequency
domain's ``fairlead_tension_rao``. Everything else is the frequency domain's: linear about q₀,
hydrodynamic coefficients of the mean wetted surface.
"""
from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..frequency.rest import _static_functions, _static_jet, _static_parts, system_loads
from ..loads.hydraulic_pto import HydraulicPTO
from ..loads.mooring import PointSprings
from ..mechanics.model import Model
from ..results import coordinate_units
from ..validation import check_model

# kinds of tunable parameter: (where, field, what it is, units, whether it moves the equilibrium)
_MODEL_KINDS = {"damping": ("joint damping (PTO)", "N m s/rad or N s/m", False),
                "stiffness": ("joint stiffness (negative: reactive control)", "N m/rad or N/m", True),
                "mass": ("body mass (ballast at the centre of mass; inertia kept)", "kg", True)}
_PTO_KINDS = {"mu": ("hydraulic piston inertia μ", "kg", False),
              "beta": ("hydraulic piston damping β", "N s/m", False),
              "kappa": ("hydraulic piston stiffness κ", "N/m", True)}
_SPRING_KINDS = {"kx": 0, "ky": 1, "kz": 2}
# a controller's spring about the operating point: −k_c (q − q₀(θ)), in K of the linearisation
# only (it exerts nothing at q₀, so it never moves the equilibrium); the config has none (0)
_CONTROL = ("control_stiffness", "controller stiffness about the equilibrium q0 (negative: "
            "reactive control)", "N m/rad or N/m")
# Borgman's factor: E[|v| v · v] / E[v²] = √(8/π) σ for a zero-mean Gaussian v
_BORGMAN = math.sqrt(8.0 / math.pi)


class Target(NamedTuple):
    """Where a tunable parameter lives: ``where`` "model" (a Model array ``field`` at ``index``),
    "control" (the controller stiffness of coordinate ``index``, :class:`Problem`'s ``control``)
    or "load" (the load at ``load`` in the loads at rest, array ``field`` at ``index``, and the
    column ``column`` of a 2-D array or -1); ``moves`` whether it moves the static equilibrium."""
    where: str
    field: str
    index: int
    load: int = -1
    column: int = -1
    moves: bool = False


def tunable_parameters(model: Model, loads=None) -> dict[str, str]:
    """Every parameter :func:`optimize` can tune, spelled as the config and the coordinates are:
    ``"<coordinate>.damping"``, ``"<coordinate>.stiffness"`` (the joint spring–damper of that
    coordinate: −k (q − rest), about the config's rest, so it moves the equilibrium),
    ``"<coordinate>.control_stiffness"`` (a controller's spring −k_c (q − q₀) about the
    equilibrium: it adds k_c to K of the linearisation and leaves q₀ where it is), ``"<body>.mass"``, ``"<hydraulic pto>.mu"``, ``".beta"``, ``".kappa"``,
    ``"<mooring>.kx"``, ``".ky"``, ``".kz"`` (a ``[[moorings]]`` spring's stiffness per inertial axis).
    Returns name → "what it is (units) = its value now"."""
    model = check_model(model)
    targets, static = _targets(model, system_loads(model, loads))
    return {name: f"{what} ({units}) = {_value_of(model, static, t):.6g}"
            for name, (t, what, units) in targets.items()}


def _static(model, loads):
    return _static_functions(model, system_loads(model, loads))[1]


def _targets(model, lds):
    """name → (Target, description, units) over the model and its loads at rest (their order in
    :func:`mfm.frequency.rest._static_functions`), and that static tuple."""
    _, static, _ = _static_functions(model, lds)
    out = {}
    units_of = coordinate_units(model)
    for k, c in enumerate(model.coordinates):
        # the coordinate's own units: a hinge's N m s/rad, a slider's N s/m
        rotation = units_of[k] == "rad"
        for f in ("damping", "stiffness"):
            what, units, moves = _MODEL_KINDS[f]
            out[f"{c}.{f}"] = (Target("model", f, k, moves=moves), what,
                               units.split(" or ")[0 if rotation else 1])
        out[f"{c}.{_CONTROL[0]}"] = (Target("control", _CONTROL[0], k), _CONTROL[1],
                                     _CONTROL[2].split(" or ")[0 if rotation else 1])
    for i, b in enumerate(model.body_names):
        what, units, moves = _MODEL_KINDS["mass"]
        out[f"{b}.mass"] = (Target("model", "mass", i, moves=moves), what, units)
    for li, ld in enumerate(static):
        if isinstance(ld, HydraulicPTO):
            for j, n in enumerate(ld.names):
                for f, (what, units, moves) in _PTO_KINDS.items():
                    out[f"{n}.{f}"] = (Target("load", f, j, li, -1, moves), what, units)
        elif isinstance(ld, PointSprings):
            names = ld.names or tuple(f"mooring{j}" for j in range(ld.stiffness.shape[0]))
            for j, n in enumerate(names):
                for f, col in _SPRING_KINDS.items():
                    out[f"{n}.{f}"] = (Target("load", "stiffness", j, li, col, True),
                                       f"linear mooring stiffness along {f[1]}", "N/m")
    return out, static


def _value_of(model, static, t: Target) -> float:
    if t.where == "control":
        return 0.0                  # a config has no controller spring: the model's own value is 0
    holder = model if t.where == "model" else static[t.load]
    arr = np.asarray(getattr(holder, t.field))
    return float(arr[t.index] if t.column < 0 else arr[t.index, t.column])


def _set(model, static, targets, values):
    """(model, static) with each group of targets set to its value (jax arrays: traced); the
    controller stiffnesses are :func:`_control`'s."""
    for group, v in zip(targets, values):
        for t in group:
            if t.where == "control":
                continue
            if t.where == "model":
                model = dataclasses.replace(
                    model, **{t.field: getattr(model, t.field).at[t.index].set(v)})
            else:
                ld = static[t.load]
                arr = getattr(ld, t.field)
                arr = arr.at[t.index].set(v) if t.column < 0 else arr.at[t.index, t.column].set(v)
                static = static[:t.load] + (dataclasses.replace(ld, **{t.field: arr}),) \
                    + static[t.load + 1:]
    return model, static


def _control(pb, values):
    """The controller stiffnesses k_c (n_q,) at ``values``: Problem's ``control`` with each
    "control" target set (traced)."""
    k = pb.control
    for group, v in zip(pb.targets, values):
        for t in group:
            if t.where == "control":
                k = k.at[t.index].set(v)
    return k


def apply(model: Model, values: dict) -> Model:
    """``model`` with the parameters ``values`` (name → number, names of
    :func:`tunable_parameters`) set in the model and in its config loads: what :func:`optimize`
    returns as the optimum, ready for :func:`mfm.simulate`.

    A controller stiffness k_c of coordinate i about the equilibrium q₀ (of the model with the
    other values set) joins the joint spring −k (q − r) as one spring of the same force,
    −k (q − r) − k_c (q − q₀) = −(k + k_c)(q − r'), r' = (k r + k_c q₀)/(k + k_c): the time
    domain steps exactly that force (its equilibrium stays q₀)."""
    model = check_model(model)
    table, _ = _targets(model, system_loads(model))
    for name in values:
        if name not in table:
            raise KeyError(_unknown(name, table))
    control = {table[n][0].index: (n, float(v)) for n, v in values.items()
               if table[n][0].where == "control"}
    model = _apply(model, {n: v for n, v in values.items() if table[n][0].where != "control"},
                   table)
    if not any(kc for _, kc in control.values()):
        return model
    from ..frequency.rest import equilibrium

    q0 = np.asarray(equilibrium(model)[0])
    k = np.array(model.stiffness, dtype=float)
    rest = np.array(model.rest, dtype=float)
    for i, (name, kc) in control.items():
        if kc == 0.0:
            continue
        if k[i] + kc == 0.0:
            raise ValueError(f"{name} = {kc!r} cancels the joint stiffness {k[i]!r} of "
                             f"{model.coordinates[i]!r}: the sum is a constant force, not a joint "
                             "spring the time domain can step; give a controller stiffness other "
                             f"than {-k[i]!r} (or tune '{model.coordinates[i]}.stiffness')")
        rest[i] = (k[i] * rest[i] + kc * q0[i]) / (k[i] + kc)
        k[i] += kc
    return model.replace(stiffness=jnp.asarray(k), rest=jnp.asarray(rest))


def _apply(model, values, table):
    """``model`` with model and load parameters set (numpy: no tracing), :func:`apply`'s part."""
    loads = list(model.loads)
    changes = {}
    for name, v in values.items():
        t = table[name][0]
        if t.where == "model":
            arr = changes.get(t.field, np.array(getattr(model, t.field), dtype=float))
            arr[t.index] = float(v)
            changes[t.field] = arr
            continue
        kind = HydraulicPTO if t.field in _PTO_KINDS else PointSprings
        # the config load of this kind with these names (the loads at rest are the same objects)
        held = [i for i, ld in enumerate(loads) if isinstance(ld, kind)]
        static_same = [i for i, ld in enumerate(_static(model, None)) if isinstance(ld, kind)]
        li = held[static_same.index(t.load)]
        arr = np.array(getattr(loads[li], t.field), dtype=float)
        if t.column < 0:
            arr[t.index] = float(v)
        else:
            arr[t.index, t.column] = float(v)
        loads[li] = dataclasses.replace(loads[li], **{t.field: jnp.asarray(arr)})
    return model.replace(loads=tuple(loads), **changes)


def _unknown(name, table):
    kinds = sorted({n.rsplit(".", 1)[1] for n in table})
    return (f"parameters: {name!r} is not a tunable parameter of this model; give "
            f"'<coordinate>.damping', '.stiffness' or '.control_stiffness', '<body>.mass', '<hydraulic pto>.mu', '.beta' "
            f"or '.kappa', '<mooring>.kx', '.ky' or '.kz' (kinds here: {kinds}). Tunable here: "
            f"{sorted(table)}")


# ------------------------------------------------------------------------------- the problem
class Problem(eqx.Module):
    """Everything the compiled objective reads: the model and its loads at rest as compiled
    (numbers only: :func:`mfm.loads.assembly.compile_view`), the baseline equilibrium, the union of
    the seas' components (ω (U,), a² (S, U)), the water's radiation impedance per hydro dof
    ``Zb`` (U, 6K, 6K) = −ω²(A − A∞) − iωB and excitation ``X`` (U, 6K) (per metre), the drag
    D (6K,) per hydro dof (0 on rotations), the seas' weights (S,), the controller stiffnesses
    ``control`` (n_q,) (0: none; the tuned ones are set by :func:`_control`); static: where each parameter
    lives, the joint PTO coordinates, the hydraulic PTO load, the water load, the catenary loads."""
    model: Model
    static: tuple
    mems: tuple
    q0: jnp.ndarray
    omega: jnp.ndarray
    a2: jnp.ndarray
    Zb: jnp.ndarray
    X: jnp.ndarray
    drag: jnp.ndarray
    weights: jnp.ndarray
    targets: tuple = eqx.field(static=True)
    joint_ptos: tuple = eqx.field(static=True)
    hydraulic: int = eqx.field(static=True)
    water: int = eqx.field(static=True)
    drag_iterations: int = eqx.field(static=True)
    lines: tuple = eqx.field(static=True, default=())
    control: jnp.ndarray | None = None


class Response(NamedTuple):
    """The spectral responses at θ (jax arrays), what a user's objective reads: ``power`` (S, P)
    W mean power of each PTO in each sea; ``q_rms`` (S, n_q) standard deviation of each coordinate
    about q₀ (m or rad); ``stroke_rms`` (S, P) of each PTO's displacement (m or rad);
    ``force_rms`` (S, P) of each PTO's damping force c ẇ (N or N m); ``weights`` (S,) the seas'
    weights normalised to sum 1; ``values`` (n_par,) the parameters; ``q0`` (n_q,) the
    equilibrium; ``drag_damping`` (S, 6K) the linearised drag c_eq = D √(8/π) σ_v of each
    hydro dof in each sea (N s/m; 0 on rotations and without drag); ``drag_change`` the last
    relative change of that fixed point (0 without drag); ``tension`` (L,) each catenary line's
    fairlead tension at q₀ and ``tension_rms`` (S, L) the standard deviation of its first-order
    change ∂T/∂r_F · r̂_F (N); ``equilibrium_residual`` max|Q(q₀)| over the force scale (the
    largest generalised or body weight): above EQUILIBRIUM_TOL no equilibrium was reached."""
    power: jnp.ndarray
    q_rms: jnp.ndarray
    stroke_rms: jnp.ndarray
    force_rms: jnp.ndarray
    weights: jnp.ndarray
    values: jnp.ndarray
    q0: jnp.ndarray
    drag_damping: jnp.ndarray
    drag_change: jnp.ndarray
    tension: jnp.ndarray
    tension_rms: jnp.ndarray
    equilibrium_residual: jnp.ndarray = 0.0


# the equilibrium Newton: at most this many steps, stopped once max|Q| < NEWTON_TOL × the force
# scale (round-off of Q is ~1e-16 of it; quadratic convergence reaches 1e-12 a step or two after
# 1e-6), each step halved up to NEWTON_HALVINGS times until ‖Q‖ decreases (Armijo, c = 1e-4)
NEWTON_STEPS, NEWTON_TOL, NEWTON_HALVINGS = 40, 1e-12, 12
# the equilibrium is accepted when max|Q(q₀)| ≤ EQUILIBRIUM_TOL × the force scale (the largest
# generalised weight or body weight): the acceptance of the engine's own equilibrium
# (:func:`mfm.frequency.rest.equilibrium`); a converged Newton leaves ~1e-12, one that found no
# equilibrium (a body that sinks or capsizes, a spring that leaves no balance) O(1e-2 … 1)
EQUILIBRIUM_TOL = 1e-6


def _force_scale(model, weights):
    """The size of the loads that must balance (N or N m): the largest generalised weight
    |Bᵀ m g| or the largest body weight m g (as :func:`mfm.frequency.rest.equilibrium`)."""
    return jnp.maximum(jnp.max(jnp.abs(weights)), jnp.max(model.mass) * model.gravity)


def _newton(f, q, scale):
    """Damped Newton on Q(q) = 0 from the baseline q₀: the step d = −J⁺Q (least squares: a
    coordinate nothing restores keeps its value) times α = 1, ½, ¼, … (at most NEWTON_HALVINGS
    halvings), the first α with ‖Q(q + αd)‖ ≤ (1 − 10⁻⁴ α)‖Q(q)‖ (Armijo on ‖Q‖²'s descent
    direction; a non-finite Q counts as no decrease, the smallest α is taken if none decreases),
    until max|Q| < NEWTON_TOL · ``scale`` or NEWTON_STEPS steps. A full step from far away can
    overshoot into a region where Q is wild (a float flipped over, a catenary off its table) and
    diverge; the halving keeps each step a descent. Run by ``lax.custom_root``, which
    differentiates the root implicitly (q₀' = −J⁻¹ ∂Q/∂θ), never through these loops.
    :func:`responses` reports the residual and :func:`optimize` refuses one above
    EQUILIBRIUM_TOL."""
    def norm(g):
        n = jnp.sqrt(jnp.sum(g * g))
        return jnp.where(jnp.isfinite(n), n, jnp.inf)

    def step(carry):
        k, q, g = carry
        J = jax.jacfwd(f)(q)
        d = -jnp.linalg.lstsq(J, g, rcond=1e-10)[0]
        n0 = norm(g)

        def shorter(c):
            a, h, _ = c
            return a * 0.5, h + 1, norm(f(q + a * 0.5 * d))

        def worse(c):
            a, h, n = c
            return (n > (1.0 - 1e-4 * a) * n0) & (h < NEWTON_HALVINGS)

        a, _, _ = jax.lax.while_loop(worse, shorter, (jnp.ones(()), 0, norm(f(q + d))))
        q_new = q + a * d
        return k + 1, q_new, f(q_new)

    def going(carry):
        k, _, g = carry
        return (k < NEWTON_STEPS) & ~(jnp.max(jnp.abs(g)) < NEWTON_TOL * scale)

    return jax.lax.while_loop(going, step, (0, q, f(q)))[1]


def _tangent(g, y):
    J = jax.jacfwd(g)(y)
    return jnp.linalg.lstsq(J, y, rcond=1e-10)[0]


def responses(pb: Problem, values) -> Response:
    """The spectral responses of the module docstring at parameters ``values`` (n_par,)."""
    model, static = _set(pb.model, pb.static, pb.targets, values)
    moves = any(t.moves for group in pb.targets for t in group)
    if moves:
        zero = jnp.zeros_like(pb.q0)
        scale = _force_scale(model, _static_jet(model, static, pb.mems, pb.q0).weights)
        q0 = jax.lax.custom_root(lambda q: _static_parts(model, static, pb.mems, q, zero)[0],
                                 pb.q0, lambda f, q: _newton(f, q, scale), _tangent)
    else:
        q0 = pb.q0
    jet = _static_jet(model, static, pb.mems, q0)
    residual = jnp.max(jnp.abs(jet.Q)) / _force_scale(model, jet.weights)
    # the controller −k_c (q − q₀) adds k_c on K's diagonal and nothing to Q(q₀)
    k_c = _control(pb, values) if pb.control is not None else 0.0
    M, K, C = jet.M, -jet.dQ_dq + jnp.diag(k_c * jnp.ones(model.n_coordinates)), -jet.dQ_dqd
    H = static[pb.water].linear_hydro().geometry.h_matrix(jet.kin)[0]                     # (6K, n)
    w = pb.omega[:, None, None]
    Z = (-w**2 * M[None] - 1j * w * C[None] + K[None]
         + jnp.einsum("ai,uab,bj->uij", H, pb.Zb, H))                      # (U, n, n)
    F = jnp.einsum("ai,ua->ui", H, pb.X)                                   # (U, n)

    def solve(c_eq):                                                       # c_eq (S, 6K)
        Cd = jnp.einsum("ai,sa,aj->sij", H, c_eq, H)
        Zs = Z[None] - 1j * w[None] * Cd[:, None]
        return jnp.linalg.solve(Zs, F[None, ..., None])[..., 0]           # (S, U, n)

    def sigma_v(x):                                                        # (S, 6K)
        v = jnp.einsum("ai,sui->sua", H, x) * pb.omega[None, :, None]
        return _safe_sqrt(jnp.sum(0.5 * pb.a2[..., None] * _abs2(v), axis=1))

    S = pb.a2.shape[0]
    c_eq = jnp.zeros((S, H.shape[0]))
    x = solve(c_eq)
    change = jnp.zeros(())
    if pb.drag_iterations:
        def fixed_point(_, carry):
            c, _ = carry
            c_new = pb.drag[None] * _BORGMAN * sigma_v(solve(c))
            return c_new, jnp.max(jnp.abs(c_new - c)) / jnp.maximum(jnp.max(jnp.abs(c_new)), 1e-300)
        c_eq, change = jax.lax.fori_loop(0, pb.drag_iterations, fixed_point, (c_eq, change))
        x = solve(c_eq)
    # PTO rates ẇ = G q̇: the joint dampers (coordinates), then the hydraulic pistons at q₀
    joint = np.asarray(pb.joint_ptos, dtype=int)
    rows = [jnp.asarray(np.eye(model.n_coordinates)[joint])] if joint.size else []
    c = [model.damping[joint]] if joint.size else []
    if pb.hydraulic >= 0:
        hyd = static[pb.hydraulic]
        rows.append(hyd._kinematics(jet.kin)[2])
        c.append(hyd.beta)
    G = jnp.concatenate(rows) if rows else jnp.zeros((0, model.n_coordinates))
    c = jnp.concatenate(c) if c else jnp.zeros((0,))
    stroke = jnp.einsum("pi,sui->sup", G, x)                               # per metre
    half_a2 = 0.5 * pb.a2[..., None]
    stroke_var = jnp.sum(half_a2 * _abs2(stroke), axis=1)                  # (S, P)
    rate_var = jnp.sum(half_a2 * pb.omega[None, :, None] ** 2 * _abs2(stroke), axis=1)
    power = c[None] * rate_var          # Σ_j a² ½ c ω² |G x̂|² (mean of c ẇ²)
    q_rms = _safe_sqrt(jnp.sum(half_a2 * _abs2(x), axis=1))
    weights = pb.weights / jnp.sum(pb.weights)
    tension, tension_rms = _tensions(static, pb.lines, jet.kin, x, half_a2)
    return Response(power, q_rms, _safe_sqrt(stroke_var), jnp.abs(c)[None] * _safe_sqrt(rate_var),
                    weights, values, q0, c_eq, change, tension, tension_rms, residual)


def _tensions(static, lines, kin, x, half_a2):
    """Fairlead tensions T = √(H² + V²) at q₀ (L,) and the standard deviation of their
    linearisation T̂ = ∂T/∂r_F · H_F x̂ (S, L), of the catenary loads at ``lines`` (the frequency
    domain's ``fairlead_tension_rao``)."""
    if not lines:
        return jnp.zeros((0,)), jnp.zeros((x.shape[0], 0))
    T0, var = [], []
    for li in lines:
        ld = static[li]

        def tension(p, ld=ld):
            H, V, _ = ld.tensions(p)
            return jnp.sqrt(H * H + V * V)

        p0 = ld.fairleads.positions(kin)
        n = p0.shape[0]
        dT = jnp.einsum("kka->ka", jax.jacfwd(tension)(p0))                  # (L, 3)
        Hp = ld.fairleads.h_matrix(kin)[0].reshape(n, 6, -1)[:, :3]          # (L, 3, n_q)
        rao = jnp.einsum("ka,kai,sui->suk", dT, Hp, x)
        T0.append(tension(p0))
        var.append(jnp.sum(half_a2 * _abs2(rao), axis=1))
    return jnp.concatenate(T0), _safe_sqrt(jnp.concatenate(var, axis=1))


def _abs2(z):
    # |z|² as z z̄: smooth at z = 0, where |z| has no derivative (a coordinate a sea does not move)
    return jnp.real(z * jnp.conj(z))


def _safe_sqrt(v):
    # √ with a finite derivative at 0 (a PTO that does not move in a sea); a NaN stays NaN (0 × v),
    # not 0: a response gone non-finite must not read as a met rms limit
    ok = v > 0
    return jnp.where(ok, jnp.sqrt(jnp.where(ok, v, 1.0)), 0.0 * v)


def mean_power(r: Response):
    """The default objective: Σ_s w_s Σ_p P_sp, the weighted mean absorbed power (W)."""
    return jnp.sum(r.weights * jnp.sum(r.power, axis=1))


# ------------------------------------------------------------------------------- constraints
class Limit(NamedTuple):
    """One constraint: ``quantity`` (a coordinate, a PTO of the model, or ``"<line>.tension"``
    of a catenary mooring line) ``kind`` "rms" (standard deviation) or "significant" (the
    significant amplitude 2σ: the mean of the highest third of a narrow-band Gaussian response's
    amplitudes, as H_s = 4σ is of crest-to-trough heights), or for a tension also "peak" (the
    tension at rest plus the significant amplitude, T₀ + 2σ_T), must stay ≤ ``limit`` (m, rad or
    N) in every sea."""
    quantity: str
    kind: str
    limit: float


KINDS = {"rms": 1.0, "significant": 2.0, "peak": 2.0}


def _limits(constraints, coordinates, ptos, lines=()) -> list[Limit]:
    if constraints is None:
        return []
    if not isinstance(constraints, dict):
        raise TypeError(f"constraints: {constraints!r}; give a dict quantity → {{'rms' or "
                        "'significant': limit}, e.g. {'platform.pitch': {'rms': 0.035}}")
    out = []
    for q, spec in constraints.items():
        tensions = [f"{n}.tension" for n in lines]
        if q not in coordinates and q not in ptos and q not in tensions:
            raise KeyError(f"constraints: {q!r} is neither a coordinate, a PTO nor a catenary "
                           f"line's tension of the model; coordinates: {list(coordinates)}, PTOs: "
                           f"{list(ptos)}, tensions: {tensions}")
        if not isinstance(spec, dict) or not spec:
            raise TypeError(f"constraints[{q!r}]: {spec!r}; give {{'rms': limit}} or "
                            "{'significant': limit} (m or rad)")
        for kind, lim in spec.items():
            kinds = list(KINDS) if q in tensions else ["rms", "significant"]
            if kind not in kinds:
                raise KeyError(f"constraints[{q!r}]: {kind!r} is not a kind of limit here; give one "
                               f"of {kinds}")
            if not isinstance(lim, (int, float)) or not math.isfinite(lim) or lim <= 0:
                raise ValueError(f"constraints[{q!r}][{kind!r}]: {lim!r}; give a positive, finite "
                                 "limit (m or rad)")
            out.append(Limit(q, kind, float(lim)))
    return out


def _constraint_values(r: Response, spec):
    """Each limit's value in each sea (n_limits, S): KINDS[kind] × σ of a coordinate, a PTO or a
    tension, plus the tension at rest for a "peak"."""
    rows = []
    for source, index, factor, static in spec:
        arr = {"q": r.q_rms, "pto": r.stroke_rms, "tension": r.tension_rms}[source]
        rows.append(factor * arr[:, index] + (r.tension[index] if static else 0.0))
    return jnp.stack(rows) if rows else jnp.zeros((0, r.power.shape[0]))

