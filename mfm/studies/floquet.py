"""**Floquet stability of a periodic run.** A model forced with period T (a regular wave) settles
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

Answered by differentiating the engine's own step (``jax.jacfwd``) over one period, never by a
re-derivation on paper; the step's own stability is :mod:`mfm.studies.stability`.
"""
from __future__ import annotations

import functools
import math
import numbers
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..loads.assembly import as_loads, compile_view, initial_states
from ..timedomain.rollout import dynamics_function, init_memories, update_memories
from ..timedomain.setup import model_loads
from ..validation import check_model, initial_vector
from ..validation import positive as _positive
from .stability import _added_mass, _integrator


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
    def one(carry, _):
        s, mem = carry
        s = integ.step(dynamics_function(model, lds, mem), s, dt)
        return (s, update_memories(model, lds, s, mem)), None

    return one


@functools.partial(jax.jit, static_argnames=("n0", "integ"))
def _floquet_start(model, lds, q0, qd0, z0, dt, n0, integ):
    """The rollout's carry after n0 steps from rest (the same step as :func:`mfm.simulate`)."""
    mem0 = init_memories(model, lds, 0.0, q0, qd0, dt)
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
    model = check_model(model)
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
                      added_mass=added_mass, integrator=integ) + as_loads(loads)
    q0 = jnp.asarray(initial_vector(model, q0, "q0"))
    qd0 = jnp.asarray(initial_vector(model, qd0, "qd0"))
    z0 = initial_states(model, lds)
    dt_ = jnp.asarray(dt, jnp.float64)

    km, kl = compile_view(model, lds)       # what the compiled calls see (numbers-only variants share)
    carry0 = _floquet_start(km, kl, q0, qd0, z0, dt_, n0, integ)
    _, _, idx = _carry_parts(carry0)
    idx = tuple(idx)
    x = _carry_to_x(carry0, idx)
    fj = lambda x: _flow_and_monodromy(x, km, kl, carry0, dt_, n, integ, idx)  # noqa: E731
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

