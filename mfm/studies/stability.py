"""Stability where methods fail: of the engine's time step (the Floquet stability of a periodic
run is :mod:`mfm.studies.floquet`).

Answered by differentiating the engine's own code (``jax.jacfwd``), never by a
re-derivation of a scheme on paper:

1. **Step stability.** One step of an integrator (:mod:`mfm.integrators`) maps the carried state
   x = (q, q̇, q̈, z, ż) to the next, xₙ₊₁ = S(xₙ). On a linear system

       M q̈ + C q̇ + K q = −A∞ q̈        (A∞ the added mass at infinite frequency)

   S is linear, xₙ₊₁ = G xₙ, and G = ∂S/∂x is the *amplification matrix*; the step is stable when
   its spectral radius ρ(G) = max |λ(G)| ≤ 1. (q̈ and ż are carried because some schemes keep
   them: Verlet's q̈ₙ₊₁ is taken at a predicted velocity, Beeman's is the corrector's iterate. For
   a scheme whose q̈ is a function of (q, q̇) the extra eigenvalues are 0.) Two placements of A∞:

   - ``added_mass="lhs"`` (mfm's): (M + A∞) q̈ = −C q̇ − K q;
   - ``added_mass="rhs"`` (Lande-Sudall et al. §5): M q̈ = −C q̇ − K q − A∞ q̈_guess, q̈_guess the corrector's
     current iterate (:class:`~mfm.integrators.Beeman`; with ``max_iter=0`` no corrector at all:
     the lagged q̈ₙ, the classic added-mass instability).

   :func:`amplification_matrix`, :func:`spectral_radius`, :func:`largest_stable_dt` (bisection on
   ρ(G(dt)) ≤ 1). :func:`heave_model` and :func:`measured_stable_dt` measure the same boundary with
   runs of :func:`mfm.rollout` on a one-body heave model whose A∞/m is set.
"""
from __future__ import annotations

import functools
import math
import numbers
import tempfile
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from ..frequency.rest import linear_hydro_index
from ..io.build import load
from ..timedomain import integrators as _integrators
from ..timedomain.rollout import rollout
from ..timedomain.setup import model_loads
from ..validation import positive as _positive
from ..validation import square_matrix as _matrix

ADDED_MASS = ("lhs", "rhs")


# ---------------------------------------------------------------------------------------------
# argument checks

def _added_mass(value):
    if value not in ADDED_MASS:
        raise ValueError(f"added_mass={value!r}; accepted: 'lhs' (A∞ in M*, mfm's) or 'rhs' (A∞ q̈ "
                         "on the right-hand side with the corrector's iterate, Lande-Sudall et al. §5)")
    return value


def _integrator(integrator, added_mass):
    integ = _integrators.get(integrator)
    if added_mass == "rhs" and getattr(integ, "name", "") != "beeman":
        raise ValueError(f"added_mass='rhs' with integrator={integ.name!r}: the right-hand-side "
                         "added mass needs an acceleration iterate, which only Beeman's corrector "
                         "has; accepted: integrator='beeman' or mfm.integrators.Beeman(max_iter=0) "
                         "(no corrector)")
    return integ


# ---------------------------------------------------------------------------------------------
# 1. the amplification matrix of one step

def linear_dynamics(M, C, K, A_inf=None, added_mass="lhs"):
    """The system ``f(t, q, q̇, z, q̈_guess=None) -> (q̈, ż)`` of the integrators for

        lhs:  (M + A∞) q̈ = −C q̇ − K q
        rhs:  M q̈ = −C q̇ − K q − A∞ q̈_guess    (the lhs value where no guess is given, as
              :class:`mfm.loads.water.Water` does at the start of a run)

    M, C, K, A∞: (n, n) arrays (numbers for one coordinate); no auxiliary states (ż is empty)."""
    return _linear_f(*_system(M, C, K, A_inf), _added_mass(added_mass))


def _system(M, C, K, A_inf):
    """The checked float64 matrices (M, C, K, A∞), each (n, n)."""
    M = _matrix(M, "M")
    n = M.shape[0]
    C, K = _matrix(C, "C", n), _matrix(K, "K", n)
    A = np.zeros((n, n)) if A_inf is None else _matrix(A_inf, "A_inf", n)
    return M, C, K, A


def _linear_f(M, C, K, A, added_mass):
    M, C, K, A = (jnp.asarray(x) for x in (M, C, K, A))
    Mt = M + A

    def f(t, q, qd, z, qdd_guess=None):
        rhs = -C @ qd - K @ q
        if added_mass == "rhs" and qdd_guess is not None:
            return jnp.linalg.solve(M, rhs - A @ qdd_guess), jnp.zeros(0)
        return jnp.linalg.solve(Mt, rhs), jnp.zeros(0)

    return f


def _pack(state):
    return jnp.concatenate([state.q, state.qd, state.qdd, state.z, state.zd])


def _unpack(x, like):
    n, m = like.q.shape[0], like.z.shape[0]
    q, qd, qdd = x[:n], x[n:2 * n], x[2 * n:3 * n]
    z, zd = x[3 * n:3 * n + m], x[3 * n + m:]
    return like._replace(q=q, qd=qd, qdd=qdd, z=z, zd=zd)


def step_jacobian(integrator, f, state, dt) -> np.ndarray:
    """∂xₙ₊₁/∂xₙ of one step ``integrator.step(f, state, dt)`` at ``state``, x = (q, q̇, q̈, z, ż)
    stacked (size 3 n_q + 2 n_z): the engine's own step, differentiated by ``jax.jacfwd``.

    For a linear f it is the amplification matrix G (independent of ``state``, except for a
    scheme whose work depends on the state: Beeman stops its corrector when the relative change of
    q̈ is below ``tol``, so G is that of the iteration count reached from ``state``)."""
    integ = _integrators.get(integrator)
    dt = _positive(dt, "dt")

    def S(x):
        return _pack(integ.step(f, _unpack(x, state), dt))

    return np.asarray(jax.jacfwd(S)(_pack(state)))


def _probe_state(integ, f, n, seed=0):
    """A fixed, generic starting state (q, q̇ random of a fixed seed, q̈ from f): the point at which
    a state-dependent step (Beeman's tolerance) is linearised."""
    rng = np.random.default_rng(seed)
    q0, qd0 = (jnp.asarray(rng.standard_normal(n)) for _ in range(2))
    return integ.init(f, 0.0, q0, qd0, jnp.zeros(0))


@functools.partial(jax.jit, static_argnames=("integ", "added_mass"))
def _linear_G(dt, M, C, K, A, integ, added_mass):
    """G of one step on the linear system: compiled once per (integrator, placement, n), reused
    for every dt and matrix (a bisection evaluates it a hundred times)."""
    f = _linear_f(M, C, K, A, added_mass)
    s0 = _probe_state(integ, f, M.shape[0])
    return jax.jacfwd(lambda x: _pack(integ.step(f, _unpack(x, s0), dt)))(_pack(s0))


def amplification_matrix(integrator, dt, M, C, K, A_inf=None, *, added_mass="lhs") -> np.ndarray:
    """The amplification matrix G (3n × 3n) of one step of ``integrator`` (a name or an instance of
    :mod:`mfm.integrators`) on (M + A∞) q̈ + C q̇ + K q = 0 with the added mass placed as
    ``added_mass`` says (:func:`linear_dynamics`); x = (q, q̇, q̈). See :func:`step_jacobian`."""
    added_mass = _added_mass(added_mass)
    integ = _integrator(integrator, added_mass)
    dt = _positive(dt, "dt")
    return np.asarray(_linear_G(jnp.asarray(dt), *map(jnp.asarray, _system(M, C, K, A_inf)),
                                integ=integ, added_mass=added_mass))


def spectral_radius(G) -> float:
    """ρ(G) = max |λ(G)|: the step is stable (no solution grows) for ρ ≤ 1."""
    return float(np.max(np.abs(np.linalg.eigvals(np.asarray(G))))) if np.size(G) else 0.0


def largest_stable_dt(integrator, M, C, K, A_inf=None, *, added_mass="lhs", dt_max=None,
                      tol=1e-9, grid=64, iterations=60) -> float:
    """The largest dt below which one step of ``integrator`` is stable on the linear system:
    the first dt at which ρ(G(dt)) exceeds 1 + ``tol``, found on a grid of ``grid`` steps from
    dt_max/grid to ``dt_max`` and refined by bisection (``iterations`` halvings).

    dt_max: default 2 T_min, T_min = 2π/√λ_max(K, M + A∞) the shortest undamped period. Returns
    ``inf`` when every dt up to dt_max is stable (Newmark: unconditionally stable) and 0.0 when
    even dt_max/grid·1e-3 is unstable (the seed's lagged added mass with A∞ > M: unstable at every
    dt). ``tol``: a neutral scheme (Verlet on an undamped oscillator) has ρ = 1 to round-off."""
    added_mass = _added_mass(added_mass)
    integ = _integrator(integrator, added_mass)
    Mm, Cm, Km, Am = _system(M, C, K, A_inf)
    if dt_max is None:
        lam = np.linalg.eigvals(np.linalg.solve(Mm + Am, Km)).real.max()
        if lam <= 0:
            raise ValueError("K: no positive stiffness, so no shortest period to scale dt by; give "
                             "dt_max (s)")
        dt_max = 2.0 * 2 * math.pi / math.sqrt(lam)
    dt_max = _positive(dt_max, "dt_max")
    mats = tuple(jnp.asarray(a) for a in (Mm, Cm, Km, Am))
    step = lambda dt: _linear_G(dt, *mats, integ=integ, added_mass=added_mass)  # noqa: E731

    def unstable(dt):
        return spectral_radius(step(jnp.asarray(dt))) > 1.0 + tol

    if unstable(dt_max / grid * 1e-3):
        return 0.0
    prev = dt_max / grid * 1e-3
    for k in range(1, grid + 1):
        dt = dt_max * k / grid
        if unstable(dt):
            lo, hi = prev, dt
            for _ in range(iterations):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
                if hi - lo < 1e-12 * hi:
                    break
            return lo
        prev = dt
    return math.inf


# ---------------------------------------------------------------------------------------------
# the one-body heave model of the map, and the boundary measured by runs

def heave_model(damping_ratio: float = 0.02, database=None):
    """A one-body heave-only model: the floating hemisphere of ``configs/sphere.toml`` (radius 1 m,
    capytaine data ``hydro/data/sphere.nc``, mass ρV) on a root with the heave coordinate alone and
    a linear damper of ``damping_ratio`` of critical on it (c = 2ζ √(K (m + A∞))), so that the
    stable side is strictly damped (ρ < 1). Returns ``(model, params)`` with params m (kg),
    A33∞ (kg, the water's), K = C33 (N/m), c (N s/m). Heave alone is linear: buoyancy ρgV is a
    constant force, the water plane a linear spring. Set A∞/m with :func:`heave_loads`."""
    if isinstance(damping_ratio, bool) or not isinstance(damping_ratio, numbers.Real) \
            or not 0 <= damping_ratio < 1:
        raise ValueError(f"damping_ratio: {damping_ratio!r}; give a fraction of critical in [0, 1)")
    root = Path(__file__).resolve().parents[2]
    db = Path(database) if database is not None else root / "hydro" / "data" / "sphere.nc"
    m = 2092.29322
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "heave.toml"
        p.write_text(_HEAVE_CONFIG.format(db=str(db), mass=m, c=0.0))
        model = load(p)
    water = model_loads(model, None, dt=0.1, duration=0.1, radiation="none")[0]
    A, K = float(water.A_inf[2, 2]), float(water.C_wp[2, 2])
    c = 2.0 * float(damping_ratio) * math.sqrt(K * (m + A))
    model = model.replace(damping=jnp.asarray([c]))
    return model, dict(m=m, A_inf=A, K=K, c=c)


_HEAVE_CONFIG = """
[model]
name = "heave"
gravity = 9.81
[hydro]
database = "{db}"
[[bodies]]
name = "sphere"
mass = {mass!r}
com = [0.0, 0.0, 0.0]
principal_inertia = [833.3, 833.3, 833.3]
[bodies.joint]
type = "free"
dofs = ["heave"]
damping = [{c!r}]
"""  # the damper is set after loading (model.replace), from the water's A∞ and C33


def heave_loads(model, mass_ratio, *, dt, n_steps, added_mass="lhs", integrator="rk4"):
    """The loads of :func:`heave_model` for a run of ``n_steps`` of ``dt`` in still water,
    radiation "none" (A∞ only), with A∞ scaled so that A∞₃₃/m = ``mass_ratio`` (the engine's own
    :class:`~mfm.loads.water.Water`, its ``A_inf`` array replaced)."""
    import equinox as eqx

    if isinstance(mass_ratio, bool) or not isinstance(mass_ratio, numbers.Real) or mass_ratio < 0 \
            or not math.isfinite(mass_ratio):
        raise ValueError(f"mass_ratio: {mass_ratio!r}; give A∞/m ≥ 0")
    loads = model_loads(model, None, dt=dt, duration=n_steps * dt, radiation="none",
                        added_mass=_added_mass(added_mass), integrator=integrator)
    k = linear_hydro_index(loads)
    m = float(np.asarray(model.mass)[0])
    A = jnp.zeros_like(loads[k].linear_hydro().A_inf).at[2, 2].set(mass_ratio * m)
    return loads[:k] + (eqx.tree_at(lambda x: x.A_inf, loads[k], A),) + loads[k + 1:]


def run_grows(model, mass_ratio, dt, *, integrator, added_mass="lhs", n_steps=2000,
              growth=1e3) -> bool:
    """Whether a run of ``n_steps`` of :func:`mfm.rollout` on :func:`heave_model`, from
    a heave of 1 cm off equilibrium at rest, grows: |q| somewhere in the last quarter above
    ``growth`` × 1 cm, or non-finite. (A stable run decays or stays at 1 cm; an unstable one grows
    as ρⁿ, so with ρ − 1 ≥ ln(growth)/n_steps = 0.35 % it is caught.)"""
    integ = _integrator(integrator, added_mass)
    loads = heave_loads(model, mass_ratio, dt=dt, n_steps=n_steps, added_mass=added_mass,
                        integrator=integ)
    out = rollout(model, jnp.asarray([0.01]), jnp.zeros(1), dt=dt, n_steps=n_steps,
                  integrator=integ, loads=loads, save_every=max(n_steps // 200, 1))
    q = np.asarray(out[1])[:, 0]
    tail = q[3 * len(q) // 4:]
    return bool(not np.all(np.isfinite(q)) or np.abs(tail).max() > growth * 0.01)


def measured_stable_dt(model, mass_ratio, *, integrator, added_mass="lhs", dt_lo, dt_hi,
                       n_steps=2000, iterations=10) -> float:
    """The largest stable dt measured by runs (:func:`run_grows`): bisection between ``dt_lo``
    (must stay bounded) and ``dt_hi`` (must grow), ``iterations`` halvings. Returns 0.0 if the run
    at dt_lo already grows and inf if the run at dt_hi does not."""
    kw = dict(integrator=integrator, added_mass=added_mass, n_steps=n_steps)
    if run_grows(model, mass_ratio, dt_lo, **kw):
        return 0.0
    if not run_grows(model, mass_ratio, dt_hi, **kw):
        return math.inf
    lo, hi = dt_lo, dt_hi
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if run_grows(model, mass_ratio, mid, **kw) else (mid, hi)
    return 0.5 * (lo + hi)


__all__ = ["amplification_matrix", "heave_loads", "heave_model", "largest_stable_dt",
           "linear_dynamics", "measured_stable_dt", "run_grows", "spectral_radius",
           "step_jacobian"]
