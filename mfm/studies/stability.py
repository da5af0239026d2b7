"""Stability where methods fail: of the engine's time step, and of a periodic run.

Two questions, both answered by differentiating the engine's own code (``jax.jacfwd``), never by a
re-derivation of a scheme on paper:

1. **Step stability.** One step of an integrator (:mod:`mfm.integrators`) maps the carried state
   x = (q, q̇, q̈, z, ż) to the next, xₙ₊₁ = S(xₙ). On a linear system

       M q̈ + C q̇ + K q = −A∞ q̈        (A∞ the added mass at infinite frequency)

   S is linear, xₙ₊₁ = G xₙ, and G = ∂S/∂x is the *amplification matrix*; the step is stable when
   its spectral radius ρ(G) = max |λ(G)| ≤ 1. (q̈ and ż are carried because some schemes keep
   them: Verlet's q̈ₙ₊₁ is taken at a predicted velocity, Beeman's is the corrector's iterate. For
   a scheme whose q̈ is a function of (q, q̇) the extra eigenvalues are 0.) Two placements of A∞:

   - ``added_mass="lhs"`` (mfm's): (M + A∞) q̈ = −C q̇ − K q;
   - ``added_mass="rhs"`` (seed 001 §5): M q̈ = −C q̇ − K q − A∞ q̈_guess, q̈_guess the corrector's
     current iterate (:class:`~mfm.integrators.Beeman`; with ``max_iter=0`` no corrector at all:
     the lagged q̈ₙ, the classic added-mass instability).

   :func:`amplification_matrix`, :func:`spectral_radius`, :func:`largest_stable_dt` (bisection on
   ρ(G(dt)) ≤ 1). :func:`heave_model` and :func:`measured_stable_dt` measure the same boundary with
   runs of :func:`mfm.timedomain.simulation.rollout` on a one-body heave model whose A∞/m is set.

2. **Floquet stability of a periodic run.** A model forced with period T (a regular wave) settles
   on a T-periodic orbit x*(t). Small deviations obey δx(t + T) = Φ δx(t), Φ = ∂F/∂x the jacobian
   of the one-period flow map F (n = T/dt steps of the engine) at a point of the orbit: the
   monodromy matrix. Its eigenvalues μ are the Floquet multipliers; |μ| > 1 means the orbit is
   unstable and a deviation grows as |μ|^{t/T}, i.e. at the rate σ = ln|μ| / T (1/s). A real
   μ < −1 is a period-doubling (parametric, Mathieu-type) instability: the deviation changes sign
   every period, so it oscillates at 2T. :func:`floquet`.

   Whether such an instability is physics or numerics: a property of the equations converges as
   dt → 0 (the multipliers of the discrete flow map tend to those of the continuous one), while a
   numerical instability depends on dt and the scheme. Compute :func:`floquet` at two dt and with
   two integrators.
"""
from __future__ import annotations

import functools
import math
import numbers
import tempfile
from pathlib import Path
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..timedomain import integrators as _integrators

ADDED_MASS = ("lhs", "rhs")


# ---------------------------------------------------------------------------------------------
# argument checks

def _positive(value, what, *, allow_inf=False):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not value > 0 \
            or (not allow_inf and not math.isfinite(value)):
        raise ValueError(f"{what}: {value!r}; give a positive finite number"
                         + (" (or inf)" if allow_inf else ""))
    return float(value)


def _matrix(a, what, n=None):
    """A square float64 matrix from a number or array (a number is a 1×1 matrix)."""
    try:
        m = np.atleast_2d(np.asarray(a, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"{what}: {a!r} is not a number or a square matrix of numbers") from None
    if m.ndim != 2 or m.shape[0] != m.shape[1] or (n is not None and m.shape[0] != n):
        raise ValueError(f"{what}: shape {m.shape}; give a square matrix"
                         + (f" of shape ({n}, {n}) like M" if n is not None else ""))
    if not np.all(np.isfinite(m)):
        raise ValueError(f"{what}: {a!r} has non-finite entries; give finite numbers")
    return m


def _added_mass(value):
    if value not in ADDED_MASS:
        raise ValueError(f"added_mass={value!r}; accepted: 'lhs' (A∞ in M*, mfm's) or 'rhs' (A∞ q̈ "
                         "on the right-hand side with the corrector's iterate, seed 001 §5)")
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
    import mfm

    from ..timedomain.simulation import model_loads

    if isinstance(damping_ratio, bool) or not isinstance(damping_ratio, numbers.Real) \
            or not 0 <= damping_ratio < 1:
        raise ValueError(f"damping_ratio: {damping_ratio!r}; give a fraction of critical in [0, 1)")
    root = Path(__file__).resolve().parents[1]
    db = Path(database) if database is not None else root / "hydro" / "data" / "sphere.nc"
    m = 2092.29322
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "heave.toml"
        p.write_text(_HEAVE_CONFIG.format(db=str(db), mass=m, c=0.0))
        model = mfm.load(p)
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

    from ..timedomain.simulation import model_loads

    if isinstance(mass_ratio, bool) or not isinstance(mass_ratio, numbers.Real) or mass_ratio < 0 \
            or not math.isfinite(mass_ratio):
        raise ValueError(f"mass_ratio: {mass_ratio!r}; give A∞/m ≥ 0")
    loads = model_loads(model, None, dt=dt, duration=n_steps * dt, radiation="none",
                        added_mass=_added_mass(added_mass), integrator=integrator)
    w = loads[0]
    m = float(np.asarray(model.mass)[0])
    A = jnp.zeros_like(w.A_inf).at[2, 2].set(mass_ratio * m)
    return (eqx.tree_at(lambda x: x.A_inf, w, A),) + tuple(loads[1:])


def run_grows(model, mass_ratio, dt, *, integrator, added_mass="lhs", n_steps=2000,
              growth=1e3) -> bool:
    """Whether a run of ``n_steps`` of :func:`mfm.timedomain.simulation.rollout` on :func:`heave_model`, from
    a heave of 1 cm off equilibrium at rest, grows: |q| somewhere in the last quarter above
    ``growth`` × 1 cm, or non-finite. (A stable run decays or stays at 1 cm; an unstable one grows
    as ρⁿ, so with ρ − 1 ≥ ln(growth)/n_steps = 0.35 % it is caught.)"""
    from ..timedomain.simulation import rollout

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


# ---------------------------------------------------------------------------------------------
# 2. Floquet multipliers of a periodic run

class FloquetResult(NamedTuple):
    """The Floquet analysis of a periodic run (:func:`floquet`).

    multipliers: μ (complex), sorted by |μ|, largest first. growth_rates: ln|μ|/T, 1/s (> 0:
    grows). period: T, s. monodromy: Φ (n_x, n_x), the jacobian of the one-period flow map.
    state_names: what each entry of x is (``q[spar.pitch]``, ``qd[...]``, ``qdd[...]``, then the
    loads' states and memories, e.g. ``memory0[1][k]``). x: the point of the orbit (at
    ``t_start``, refined). residual: |F(x) − x|_∞ before and after refinement (how periodic the
    point is). modes: the eigenvectors (columns, in the order of ``multipliers``)."""
    multipliers: np.ndarray
    growth_rates: np.ndarray
    period: float
    monodromy: np.ndarray
    state_names: list
    x: np.ndarray
    residual: tuple
    modes: np.ndarray
    t_start: float
    dt: float

    def leading(self, coordinate_prefix="q["):
        """(μ, σ, the state entry of the leading mode with the largest |component| among names
        starting with ``coordinate_prefix``)."""
        v = np.abs(self.modes[:, 0])
        idx = [i for i, nm in enumerate(self.state_names) if nm.startswith(coordinate_prefix)]
        k = max(idx, key=lambda i: v[i]) if idx else int(np.argmax(v))
        return self.multipliers[0], float(self.growth_rates[0]), self.state_names[k]


def _carry_parts(carry):
    """The leaves of a rollout carry that are states (float arrays with ≥ 1 dimension): q, q̇, q̈,
    z, ż and the loads' array memories. 0-d leaves (the clock t, a memory's time stamp) and
    integer leaves (iteration counts) are not states: they are held as they are."""
    leaves, tree = jax.tree_util.tree_flatten(carry)
    idx = [i for i, a in enumerate(leaves)
           if jnp.issubdtype(jnp.asarray(a).dtype, jnp.floating) and jnp.ndim(a) >= 1]
    return leaves, tree, idx


def _state_names(model, carry, idx):
    leaves, _, _ = _carry_parts(carry)
    state, mems = carry
    names = []
    fields = {id(getattr(state, k)): k for k in ("q", "qd", "qdd", "z", "zd")}
    coords = list(model.coordinates)
    mem_paths = {}
    for path, leaf in jax.tree_util.tree_flatten_with_path(mems)[0]:
        mem_paths[id(leaf)] = "memory" + "".join(str(p) for p in path)
    for i in idx:
        a = leaves[i]
        size = int(np.prod(np.shape(a)))
        f = fields.get(id(a))
        if f in ("q", "qd", "qdd"):
            names += [f"{f}[{c}]" for c in coords]
        else:
            base = f or mem_paths.get(id(a), f"leaf{i}")
            names += [f"{base}[{k}]" for k in range(size)]
    return names


def _one_step(model, lds, integ, dt):
    from ..timedomain.simulation import _update_memories, dynamics_function

    def one(carry, _):
        s, mem = carry
        s = integ.step(dynamics_function(model, lds, mem), s, dt)
        return (s, _update_memories(model, lds, s, mem)), None

    return one


@functools.partial(jax.jit, static_argnames=("n0", "integ"))
def _floquet_start(model, lds, q0, qd0, z0, dt, n0, integ):
    """The rollout's carry after n0 steps from rest (the same step as :func:`mfm.simulate`)."""
    from ..timedomain.simulation import _init_memories, dynamics_function

    mem0 = _init_memories(model, lds, 0.0, q0, qd0, dt)
    s = integ.init(dynamics_function(model, lds, mem0), 0.0, q0, qd0, z0)
    carry, _ = jax.lax.scan(_one_step(model, lds, integ, dt), (s, mem0), None, length=n0)
    return carry


def _carry_to_x(carry, idx):
    leaves = jax.tree_util.tree_leaves(carry)
    return jnp.concatenate([jnp.ravel(leaves[i]) for i in idx])


def _x_to_carry(x, like, idx):
    leaves, tree = jax.tree_util.tree_flatten(like)
    off = 0
    for i in idx:
        sz = int(np.prod(np.shape(leaves[i])))
        leaves[i] = x[off:off + sz].reshape(np.shape(leaves[i]))
        off += sz
    return jax.tree_util.tree_unflatten(tree, leaves)


def _flow(x, model, lds, like, dt, n, integ, idx):
    """F(x): the carried state after n steps from x (the clock and stamps of ``like``)."""
    carry, _ = jax.lax.scan(_one_step(model, lds, integ, dt), _x_to_carry(x, like, idx), None,
                            length=n)
    return _carry_to_x(carry, idx)


@functools.partial(jax.jit, static_argnames=("n", "integ", "idx"))
def _flow_and_monodromy(x, model, lds, like, dt, n, integ, idx):
    """(F(x), Φ = ∂F/∂x): forward mode, the tangents of every state entry pushed through the
    same n steps as the value, in one compiled function."""
    y, push = jax.linearize(lambda x_: _flow(x_, model, lds, like, dt, n, integ, idx), x)
    return y, jax.vmap(push, out_axes=1)(jnp.eye(x.shape[0], dtype=x.dtype))


def floquet(model, sea, *, period, dt, t_start, integrator="verlet",
            radiation="state_space_exact", loads=None, ramp=0.0, added_mass="lhs",
            state_space_options=None, q0=None, qd0=None, refine: int = 2) -> FloquetResult:
    """Floquet multipliers of ``model`` in the periodic sea ``sea`` (period ``period``, s), about
    the periodic orbit the run reaches at ``t_start``.

    The run (the engine's rollout: ``integrator``, ``radiation``, ``loads``, ``ramp``, ``q0``,
    ``qd0`` as in :func:`mfm.simulate`) goes from rest to ``t_start``; its carried state x there
    (q, q̇, q̈, z, ż and the loads' memories, e.g. the exactly advanced radiation states) is the
    start of the one-period flow map

        F(x) = the state after n = T/dt steps from x at t_start,   Φ = ∂F/∂x  (jax.jacfwd),

    and the multipliers are the eigenvalues of Φ; a deviation grows as |μ|^{t/T}, at
    σ = ln|μ|/T. The point is refined towards the periodic orbit by ``refine`` Newton steps
    x ← x − (Φ − I)⁺ (F(x) − x) (least squares: a free coordinate, an unmoored surge, gives
    μ = 1 and a singular Φ − I), so an orbit that is unstable, and that the run is already
    leaving at t_start, is still found.

    period must be a whole number of steps; ``t_start`` a whole number of steps. radiation must
    have finitely many states: "state_space", "state_space_exact" or "none" (the convolution's
    memory is its whole velocity history: allowed, but Φ is then as large as that history)."""
    from ..timedomain.simulation import _as_loads, _initial_vector, model_loads

    period = _positive(period, "period")
    dt = _positive(dt, "dt")
    ok = isinstance(t_start, numbers.Real) and not isinstance(t_start, bool) \
        and math.isfinite(t_start) and t_start >= 0
    if not ok:
        raise ValueError(f"t_start: {t_start!r}; give a time ≥ 0 (s) at which the run has reached "
                         "its periodic steady state")
    t_start = float(t_start)
    n = int(round(period / dt))
    if n < 1 or abs(n * dt - period) > 1e-9 * period:
        raise ValueError(f"period: {period!r} s is not a whole number of steps of dt = {dt!r} s "
                         f"({period / dt:.6g}); choose dt = period / k")
    n0 = int(round(t_start / dt))
    if abs(n0 * dt - t_start) > 1e-9 * max(t_start, dt):
        raise ValueError(f"t_start: {t_start!r} s is not a whole number of steps of dt = {dt!r} s")
    if isinstance(refine, bool) or not isinstance(refine, numbers.Integral) or refine < 0:
        raise ValueError(f"refine: {refine!r}; give a whole number ≥ 0 of Newton steps")
    accepted = ("state_space", "state_space_exact", "none", "convolution")
    if radiation not in accepted:
        raise ValueError(f"radiation={radiation!r}; accepted: {accepted} (a finite state: "
                         "'state_space_exact' or 'state_space' recommended)")
    integ = _integrator(integrator, _added_mass(added_mass))
    lds = model_loads(model, sea, dt=dt, duration=t_start + period + dt, ramp=ramp,
                      radiation=radiation, state_space_options=state_space_options,
                      added_mass=added_mass, integrator=integ) + _as_loads(loads)
    q0 = jnp.asarray(_initial_vector(model, q0, "q0"))
    qd0 = jnp.asarray(_initial_vector(model, qd0, "qd0"))
    parts = [ld.initial_state(model) for ld in lds]
    z0 = jnp.concatenate(parts) if parts else jnp.zeros(0)
    dt_ = jnp.asarray(dt, jnp.float64)

    carry0 = _floquet_start(model, lds, q0, qd0, z0, dt_, n0, integ)
    _, _, idx = _carry_parts(carry0)
    idx = tuple(idx)
    x = _carry_to_x(carry0, idx)
    fj = lambda x: _flow_and_monodromy(x, model, lds, carry0, dt_, n, integ, idx)  # noqa: E731
    y, J = fj(x)
    res0 = res = float(jnp.max(jnp.abs(y - x)))
    for _ in range(int(refine)):
        dx, *_ = np.linalg.lstsq(np.asarray(J) - np.eye(J.shape[0]), -np.asarray(y - x),
                                 rcond=1e-10)
        x_new = x + jnp.asarray(dx)
        y_new, J_new = fj(x_new)
        r_new = float(jnp.max(jnp.abs(y_new - x_new)))
        if not np.isfinite(r_new) or r_new > res:
            break
        x, y, J, res = x_new, y_new, J_new, r_new
    Phi = np.asarray(J)
    mu, vec = np.linalg.eig(Phi)
    order = np.argsort(-np.abs(mu), kind="stable")
    mu, vec = mu[order], vec[:, order]
    with np.errstate(divide="ignore"):
        sigma = np.log(np.abs(mu)) / period
    return FloquetResult(multipliers=mu, growth_rates=sigma, period=period, monodromy=Phi,
                         state_names=_state_names(model, carry0, idx), x=np.asarray(x),
                         residual=(res0, res), modes=vec, t_start=t_start, dt=dt)


def envelope_growth_rate(t, y, period, t_from, t_to):
    """The measured growth rate σ (1/s) of the deviation of a signal from T-periodicity,
    d(t) = y(t + T) − y(t): for a run near an unstable periodic orbit, d grows as e^{σ t} (the
    periodic forced part cancels). Fit: least squares of ln max|d| over each period against its
    time, for periods within [t_from, t_to]. ``t`` uniform. Returns (σ, period midpoints,
    per-period peaks)."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    h = t[1] - t[0]
    k = int(round(period / h))
    if k < 1 or abs(k * h - period) > 1e-6 * period:
        raise ValueError(f"period: {period!r} s is not a whole number of samples of {h:g} s")
    d = y[k:] - y[:-k]
    td = t[:-k]
    mids, peaks = [], []
    a = t_from
    while a + period <= t_to + 1e-9:
        s = (td >= a - 1e-9) & (td < a + period - 1e-9)
        if s.any():
            mids.append(a + 0.5 * period)
            peaks.append(np.abs(d[s]).max())
        a += period
    mids, peaks = np.asarray(mids), np.asarray(peaks)
    if len(mids) < 3:
        raise ValueError(f"t_from, t_to: [{t_from}, {t_to}] s holds fewer than 3 periods of the "
                         "run; give a longer window")
    sigma = np.polyfit(mids, np.log(peaks), 1)[0]
    return float(sigma), mids, peaks


__all__ = ["FloquetResult", "amplification_matrix", "envelope_growth_rate", "floquet",
           "heave_loads", "heave_model", "largest_stable_dt", "linear_dynamics",
           "measured_stable_dt", "run_grows", "spectral_radius", "step_jacobian"]
