"""Time-domain simulation: a pure jax rollout, compiled once, and its labelled dataset.

``rollout`` is the pure core (``lax.scan`` over steps; vmap- and grad-friendly); ``simulate`` is the
front door: it checks the inputs, runs the compiled rollout, stops with a clear error if the state
went non-finite, and returns an :class:`xarray.Dataset`.
"""
from __future__ import annotations

import collections
import concurrent.futures
import functools
import math
import numbers
import os
import sys
import warnings
from typing import Sequence

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from . import integrators as _integrators
from .. import results
from ..mechanics import se3
from ..mechanics.dynamics import energies, evaluate, reaction_loads
from ..mechanics.kinematics import kinematics
from ..loads.base import Context, Load
from ..mechanics.model import Model

# How many times each compiled function was traced (a retrace means a recompilation); tests use it.
TRACES: collections.Counter = collections.Counter()


class StabilityWarning(UserWarning):
    """dt is beyond the integrator's stability limit for the model's shortest natural period."""


class AccuracyWarning(UserWarning):
    """The run's accuracy is in doubt: dt too coarse for the periods the sea excites (the expected
    period error is given), or a coordinate without restoring integrated by Verlet (it drifts)."""


class SimulationError(RuntimeError):
    """The simulation went non-finite; the message gives the time, the state and the likely cause.
    ``dataset`` holds what was computed up to the last finite sample (attribute
    ``complete = "false"``), or None."""

    def __init__(self, message, dataset=None):
        super().__init__(message)
        self.dataset = dataset


def model_loads(model: Model, sea=None, *, dt, duration, t0=0.0, ramp=0.0,
                radiation="convolution", memory=None, state_space_options=None,
                added_mass="lhs", integrator="rk4") -> tuple[Load, ...]:
    """The loads a model carries itself, ready for :func:`rollout`: with a [hydro] config its water
    for this sea and time grid (:func:`mfm.loads.water.build_water`, prepared for the stage
    times of ``integrator``), then the config's loads (``model.loads``: moorings, PTOs, …)."""
    out = []
    if model.hydro is not None:
        from ..loads.water import build_water

        _check_sea(sea)
        out.append(build_water(model, model.hydro, sea, dt=dt, duration=duration, t0=t0, ramp=ramp,
                               radiation=radiation, memory=memory,
                               state_space_options=state_space_options, added_mass=added_mass,
                               stage_offsets=_stage_offsets(integrator)))
    return tuple(out) + tuple(model.loads)


# convolution work per run above which radiation="auto" takes the state space: ≈ 10 s of
# multiply–adds at the ~2e9/s one core does on these small matrix–vector products, the order of
# a state-space fit (benchmarks/fit_speed.py: 1–3 s for M4, Stansby & Li, Hallak; 22 s for Wu &
# Yuan's 90 dofs), so short runs keep the fit-free convolution
AUTO_CONVOLUTION_LIMIT = 2e10


def choose_radiation(model: Model, *, dt, n_steps, integrator="rk4", memory=None):
    """The radiation strategy ``radiation="auto"`` takes, and why: ``(name, reason)``.

    The convolution costs n_steps × S × n_lags × n² multiply–adds (S the stage offsets of the
    integrator, for each of which the history sum is formed once per step,
    :class:`mfm.loads.radiation.Convolution`; n the moved hydro dofs; n_lags = T_K/dt with T_K the
    memory from the decay of K, or ``memory``); the state space a fit once (seconds to a minute) and
    then O(n · poles) per evaluation. Above :data:`AUTO_CONVOLUTION_LIMIT` multiply–adds the state
    space is taken, its states advanced exactly (``"state_space_exact"``, stable with every
    integrator); below it the convolution, the direct evaluation of the Cummins integral with no
    fit. The reason is recorded in the result (``radiation_choice``)."""
    if model.hydro is None:
        return "none", "no water"
    integ = _integrators.get(integrator)
    spec = model.hydro
    T_K = spec.memory() if memory is None else float(memory)
    n = len(spec.moving)
    lags = int(math.ceil(T_K / dt))
    # an integrator of the user's that declares no offsets: its evaluations per step
    offsets = getattr(integ, "stage_offsets", None)
    S = len(offsets) if offsets else getattr(integ, "evaluations", 2)
    macs = float(n_steps) * S * lags * n * n
    what = (f"convolution {n_steps} steps × {S} stage offsets × {lags} lags (T_K {T_K:.3g} s / "
            f"dt {dt:.3g} s) × {n}² moved dofs = {macs:.2g} multiply–adds")
    if macs > AUTO_CONVOLUTION_LIMIT:
        return "state_space_exact", f"auto: {what} > {AUTO_CONVOLUTION_LIMIT:.0e}: state space"
    return "convolution", f"auto: {what} ≤ {AUTO_CONVOLUTION_LIMIT:.0e}: convolution"


def _stage_offsets(integrator):
    integ = _integrators.get(integrator)
    offs = getattr(integ, "stage_offsets", None)
    if offs is None:
        raise TypeError(f"integrator {integ!r} declares no stage_offsets (the fractions of dt at "
                        "which it evaluates the dynamics in a step, e.g. (0.0, 0.5, 1.0) for RK4); "
                        "loads with memory need them")
    return tuple(float(o) for o in offs)


def _check_sea(sea):
    if sea is not None and not hasattr(sea, "components"):
        raise TypeError(f"sea: {sea!r} is not a sea state; give one of hydro.Regular(height=, "
                        "period=), hydro.Jonswap(hs=, tp=), hydro.PiersonMoskowitz(hs=, tp=), "
                        "hydro.UserSpectrum, hydro.MeasuredElevation, or None for still water")


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
        out = ld.evaluate(Context(model, t, q, qd, z[offsets[k]:offsets[k + 1]], kin, memories[k],
                                  qdd_guess))
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
        ctx = Context(model, s.t, s.q, s.qd, s.z[offs[k]:offs[k + 1]], kin, mem[k], s.qdd, ev.qdd)
        Fk = ld.reaction_loads(ctx, out)
        if Fk is not None:
            F = Fk if F is None else F + Fk
        diag.update(ld.diagnostics(ctx, out))
    ev_r = ev._replace(F=ev.F - (0.0 if body is None else body) + (0.0 if F is None else F))
    f_j, m_j = reaction_loads(model, ev_r)
    T, V = energies(model, s.q, s.qd, kin)
    angles = jax.vmap(se3.euler_zyx)(kin.E[:, :3, :3])
    return dict(body_position=kin.E[:, :3, 3], body_rotation=angles, joint_force=f_j,
                joint_moment=m_j, kinetic_energy=T, potential_energy=V, qdd=ev.qdd, **diag)


def _output_names(outputs) -> tuple:
    if isinstance(outputs, str):
        outputs = (outputs,)
    try:
        names = tuple(outputs)
    except TypeError:
        raise ValueError(f"outputs: {outputs!r}; give a sequence of output names") from None
    if not all(isinstance(n, str) for n in names):
        raise ValueError(f"outputs: {outputs!r}; give a sequence of output names (strings)")
    return tuple(dict.fromkeys(names))


def _saved(model, loads, s, mem, record):
    """The outputs kept of one saved state. ``record``: False (the state), True (the state and
    every per-sample output), or a tuple of output names: a batch's form, the state without the
    loads' own states z (a radiation fit has thousands per sample: a 36-case sweep of one hour
    would hold gigabytes of them) and a dict of the named outputs only (the compiler drops the
    work of the others)."""
    if isinstance(record, tuple):
        rec = _record(model, loads, s, mem) if record else {}
        return (s.t, s.q, s.qd, s.qdd, jnp.zeros(0), s.iterations, {k: rec[k] for k in record})
    out = (s.t, s.q, s.qd, s.qdd, s.z, s.iterations)
    return out + ((_record(model, loads, s, mem),) if record else ())


def _rollout_start(model, loads, q0, qd0, z0, t0, dt, integrator, record):
    """The initial carry (integrator state, load memories) and its saved outputs (deferred ones
    by the same vmapped program as the later samples', :func:`_record_deferred`)."""
    mem0 = _init_memories(model, loads, t0, q0, qd0, dt)
    state = integrator.init(dynamics_function(model, loads, mem0), t0, q0, qd0, z0)
    carry = (state, mem0)
    if _deferred(carry, record):
        one = _record_deferred(model, loads, jax.tree_util.tree_map(lambda a: a[None], carry))
        return carry, jax.tree_util.tree_map(lambda a: a[0], one)
    return carry, _saved(model, loads, state, mem0, record)


# per-sample memory (floats) up to which the outputs of a recorded run are computed after the
# time loop, vmapped over the saved samples (matrix–matrix work) instead of inside it
DEFERRED_RECORD_MEMORY = 10_000
DEFERRED_RECORD_WIDTH = 32


def _deferred(carry, record) -> bool:
    """Whether a recorded run evaluates its outputs after the time loop (:func:`_rollout_blocks`):
    ``record is True`` and a memory of at most :data:`DEFERRED_RECORD_MEMORY` floats."""
    mem_size = sum(int(np.prod(np.shape(a))) for a in jax.tree_util.tree_leaves(carry[1]))
    return record is True and mem_size <= DEFERRED_RECORD_MEMORY


def _rollout_blocks(model, loads, carry, dt, n_blocks, integrator, save_every, record):
    """``n_blocks`` blocks of ``save_every`` steps from ``carry``: (carry, the saved outputs of
    each block's last step, stacked). With ``record is True`` and a small memory (the state
    space's, not the convolution's history) the loop keeps only the state and memory of each
    saved step and the outputs are evaluated afterwards in one vmapped pass
    (:func:`_record_deferred`): the serial loop carries the integration alone (RM3: recording
    every step cost 5× the integration inside it). ``record="carry"``: the saved carries
    themselves, for that pass to be made by the caller."""

    def one_step(carry, _):
        s, mem = carry
        s = integrator.step(dynamics_function(model, loads, mem), s, dt)
        return (s, _update_memories(model, loads, s, mem)), None

    deferred = record == "carry" or _deferred(carry, record)

    def block(carry, _):
        carry, _ = jax.lax.scan(one_step, carry, None, length=save_every)
        return carry, (carry if deferred else _saved(model, loads, *carry, record))

    carry, saved = jax.lax.scan(block, carry, None, length=n_blocks)
    if deferred and record is True:
        saved = _record_deferred(model, loads, saved)
    return carry, saved


def _record_deferred(model, loads, carries):
    """The outputs (:func:`_saved`, ``record=True``) of stacked carries, in groups of a fixed
    width: every sample is computed by the same vmapped program whatever their number, so a run
    in chunks (progress bar) gives the same bits."""
    return _map_in_groups(lambda sm: _saved(model, loads, *sm, True), carries,
                          DEFERRED_RECORD_WIDTH)


def _map_in_groups(f, xs, width):
    """``f`` over the leading axis of the pytree ``xs``: ``jax.lax.map`` over groups of ``width``
    items that one ``jax.vmap`` evaluates together, the last group padded by repeating the last
    item (its results dropped). The shapes are written out, not inferred: items may be empty."""
    n = jax.tree_util.tree_leaves(xs)[0].shape[0]
    G = -(-n // width)
    pad = lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], G * width - n, 0)]).reshape(  # noqa: E731
        (G, width) + a.shape[1:])
    out = jax.lax.map(jax.vmap(f), jax.tree_util.tree_map(pad, xs))
    return jax.tree_util.tree_map(lambda a: a.reshape((G * width,) + a.shape[2:])[:n], out)


def _rollout_impl(model, loads, q0, qd0, z0, t0, dt, n_steps, integrator, save_every, record):
    TRACES["rollout"] += 1
    n_blocks = n_steps // save_every
    carry, _ = _rollout_start(model, loads, q0, qd0, z0, t0, dt, integrator, False)
    if _deferred(carry, record):
        # the initial sample's outputs in the same pass as the others': one copy of the outputs'
        # program to compile, not two (M4 134: ~4 s of a first call)
        _, carries = _rollout_blocks(model, loads, carry, dt, n_blocks, integrator, save_every,
                                     "carry")
        stacked = jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a[None], b]), carry, carries)
        return _record_deferred(model, loads, stacked)
    first = _saved(model, loads, *carry, record)
    _, traj = _rollout_blocks(model, loads, carry, dt, n_blocks, integrator, save_every, record)
    return jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a[None], b]), first, traj)


_rollout_jit = jax.jit(_rollout_impl,
                       static_argnames=("n_steps", "integrator", "save_every", "record"))


# The chunked rollout of a progress bar: the same start and blocks, compiled as two functions
# (the blocks one once for the chunk length), called from the host between bar updates.
def _chunk_impl(model, loads, carry, dt, n_blocks, integrator, save_every, record):
    TRACES["rollout_chunk"] += 1
    return _rollout_blocks(model, loads, carry, dt, n_blocks, integrator, save_every, record)


_start_jit = jax.jit(_rollout_start, static_argnames=("integrator", "record"))
_chunk_jit = jax.jit(_chunk_impl, static_argnames=("n_blocks", "integrator", "save_every", "record"))


def _over_cases(f, model, model_axis, batched, lanes):
    """``f(model_k, *batched_k)`` for every case k (the leading axis of each leaf of ``batched``,
    and of ``model`` where ``model_axis`` is 0): ``jax.lax.map`` over groups of ``lanes`` cases
    advanced together by one vmapped loop (1: the cases one after another in one compiled call).

    Why not one ``jax.vmap`` over every case: on a CPU the vmapped time loop cost 1.6–2× a single
    run per case-step (M4 134, Verlet + exact radiation, 20,000 steps: 18 µs/step alone, 33–37 µs
    per case-step at 4–16 cases), so there the cases run one after another at a single run's
    speed; a GPU has the width to advance them together.
    """
    xs = tuple(batched) if model_axis is None else (model,) + tuple(batched)
    g = (lambda a: f(model, *a)) if model_axis is None else (lambda a: f(*a))
    if lanes <= 1:
        return jax.lax.map(g, xs)
    # not lax.map's own batch_size: it fails on the empty state of a model without load states
    # (its reshape divides by 0)
    return _map_in_groups(g, xs, lanes)


def default_lanes(n_cases: int) -> int:
    """The cases advanced together by default: 1 on a CPU (see :func:`_over_cases`), all of them
    on an accelerator."""
    return 1 if jax.default_backend() == "cpu" else max(1, int(n_cases))


def default_threads() -> int:
    """Host threads of a batch by default: one per core this process may use on a CPU (each
    compiled call runs on one core), 1 on an accelerator."""
    if jax.default_backend() != "cpu":
        return 1
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:      # not on Linux
        return max(1, os.cpu_count() or 1)


def _in_threads(n, call):
    """``[call(0), …, call(n − 1)]``, each made and waited for on its own host thread (XLA on a
    CPU executes a call on the thread that waits for it: measured, two parts of M4 134 cases in
    two threads took 0.76 s against 1.51 s one after the other on 2 cores)."""
    if n == 1:
        return [jax.block_until_ready(call(0))]
    with concurrent.futures.ThreadPoolExecutor(n) as pool:
        return list(pool.map(lambda k: jax.block_until_ready(call(k)), range(n)))


def _join_parts(outs, B):
    """The parts' outputs joined on the case axis, the padding cases dropped (numpy)."""
    return jax.tree_util.tree_map(lambda *a: np.concatenate([np.asarray(x) for x in a])[:B],
                                  *outs)


@functools.partial(jax.jit, static_argnames=("model_axis", "n_steps", "integrator", "save_every",
                                             "record", "lanes"))
def _batch_jit(model, loads, q0, qd0, z0, t0, dt, *, model_axis, n_steps, integrator, save_every,
               record, lanes):
    return _over_cases(lambda m, lds, d: _rollout_impl(m, lds, q0, qd0, z0, t0, d, n_steps,
                                                       integrator, save_every, record),
                       model, model_axis, (loads, dt), lanes)


@functools.partial(jax.jit, static_argnames=("model_axis", "integrator", "record", "lanes"))
def _start_batch_jit(model, loads, q0, qd0, z0, t0, dt, *, model_axis, integrator, record, lanes):
    return _over_cases(lambda m, lds, d: _rollout_start(m, lds, q0, qd0, z0, t0, d, integrator,
                                                        record),
                       model, model_axis, (loads, dt), lanes)


@functools.partial(jax.jit, static_argnames=("model_axis", "n_blocks", "integrator", "save_every",
                                             "record", "lanes"))
def _chunk_batch_jit(model, loads, carry, dt, *, model_axis, n_blocks, integrator, save_every,
                     record, lanes):
    TRACES["rollout_chunk"] += 1
    return _over_cases(lambda m, lds, c, d: _rollout_blocks(m, lds, c, d, n_blocks, integrator,
                                                            save_every, record),
                       model, model_axis, (loads, carry, dt), lanes)


def chunk_plan(n_blocks: int, fewest: int = 20, most: int = 100) -> tuple[int, int]:
    """(chunk length in saved blocks, number of chunks) for a progress bar: between ``fewest``
    and ``most`` updates, the length that wastes the fewest blocks past the end (the last chunk
    has the same length, so one compilation serves every chunk; its extra blocks are dropped)."""
    if n_blocks <= fewest:
        return 1, n_blocks
    lengths = range(-(-n_blocks // most), -(-n_blocks // fewest) + 1)
    c = min(lengths, key=lambda c: (-(-n_blocks // c) * c - n_blocks, c))
    return c, -(-n_blocks // c)


def _progress_options(progress):
    """The tqdm options of ``progress`` (True, or a dict of tqdm options), or None for no bar."""
    if progress is None or progress is False:
        return None
    if progress is True:
        return {}
    if isinstance(progress, dict):
        return dict(progress)
    raise ValueError(f"progress: {progress!r}; give False (no bar, the default), True (a bar on "
                     "stderr) or a dict of tqdm options, e.g. {'delay': 5}")


def _progress_bar(options, total, desc):
    """A tqdm bar on stderr with ``options`` (from :func:`_progress_options`), or None."""
    if options is None:
        return None
    from tqdm.auto import tqdm

    try:
        return tqdm(**{"total": total, "unit": "step", "desc": desc, "file": sys.stderr, **options})
    except (TypeError, KeyError) as e:     # tqdm's TqdmKeyError for an unknown option
        raise ValueError(f"progress: {options!r} is not a set of tqdm options ({e})") from None


def _run_chunked(start, chunk, n_blocks, save_every, bar, time_axis):
    """Run ``start()`` then ``chunk(carry, c)`` (``c`` blocks, from :func:`chunk_plan`) until
    ``n_blocks`` are done,
    updating ``bar`` between chunks; stops early once a chunk has a non-finite q or q̇ (the caller
    finds where). Returns the saved outputs as numpy, the initial state first, as the unchunked
    rollout does: the same compiled steps in the same order, so the same numbers."""
    c, n_chunks = chunk_plan(n_blocks)
    bar.set_postfix_str("compiling")
    carry, first = start()
    pieces = [jax.tree_util.tree_map(lambda a: np.expand_dims(np.asarray(a), time_axis), first)]
    done = 0
    try:
        for _ in range(n_chunks):
            carry, traj = chunk(carry, c)
            take = min(c, n_blocks - done)
            cut = (slice(None),) * time_axis + (slice(0, take),)
            traj = jax.tree_util.tree_map(lambda a: np.asarray(a)[cut], traj)
            pieces.append(traj)
            done += take
            if done == take:
                # the first chunk compiled: rate, elapsed and ETA count from here, else the
                # compilation (seconds to a minute) shows as slow steps and a far-off ETA
                compiled = bar.format_dict["elapsed"]
                bar.reset(total=bar.total)
                bar.initial = bar.n = bar.last_print_n = take * save_every
                bar.set_postfix_str(f"compiled in {compiled:.0f} s")
            else:
                bar.update(take * save_every)
            if not (np.isfinite(traj[1]).all() and np.isfinite(traj[2]).all()):
                break
    finally:
        bar.close()
    return jax.tree_util.tree_map(lambda *a: np.concatenate(a, axis=time_axis), *pieces)


def rollout(model: Model, q0, qd0, *, dt, n_steps: int, integrator="rk4", loads=None,
            save_every: int = 1, t0=0.0, z0=None, record: bool = False):
    """Pure, jit-compiled rollout: returns ``(t, q, qd, qdd, z, iterations)`` arrays with a leading
    time axis of length ``n_steps // save_every + 1`` (the initial state first).

    Compiled once per (topology, n_steps, integrator, save_every, loads structure): changing any
    array parameter of ``model`` or ``loads``, ``dt``, ``q0``, ``qd0`` reuses the compiled code, and
    the function can be ``jax.vmap``-ed over a batched model or ``jax.grad``-ed (RK4, semi-implicit
    and Newmark; Beeman's while loop is forward-mode only). ``record=True`` appends a dict of
    per-sample outputs (poses, joint reactions, energies, load diagnostics) as a 7th item; a tuple
    of output names (e.g. ``("point_acceleration",)``) records only those, and z comes back
    empty (the batch form: the loads' states are not kept per sample).
    """
    args, options = _rollout_call(model, q0, qd0, dt=dt, n_steps=n_steps, integrator=integrator,
                                  loads=loads, save_every=save_every, t0=t0, z0=z0, record=record)
    return _rollout_jit(*args, **options)


def _rollout_call(model, q0, qd0, *, dt, n_steps, integrator, loads, save_every, t0, z0, record):
    """The arguments and static options of :func:`rollout`'s compiled call, checked."""
    loads = _as_loads(loads)
    integ = _integrators.get(integrator)
    if isinstance(n_steps, bool) or not isinstance(n_steps, numbers.Integral) or n_steps < 1:
        raise ValueError(f"n_steps: {n_steps!r}; give a positive whole number of steps")
    if isinstance(save_every, bool) or not isinstance(save_every, numbers.Integral) or save_every < 1:
        raise ValueError(f"save_every: {save_every!r}; give a positive whole number")
    _check_concrete_positive(dt, "dt")
    q0 = jnp.asarray(q0, jnp.float64)
    qd0 = jnp.asarray(qd0, jnp.float64)
    if z0 is None:
        parts = [ld.initial_state(model) for ld in loads]
        z0 = jnp.concatenate(parts) if parts else jnp.zeros(0)
    args = (model, loads, q0, qd0, jnp.asarray(z0, jnp.float64), jnp.asarray(t0, jnp.float64),
            jnp.asarray(dt, jnp.float64))
    return args, dict(n_steps=int(n_steps), integrator=integ, save_every=int(save_every),
                      record=record)


def _rollout_progress(model, q0, qd0, *, dt, n_steps, integrator, loads, save_every, t0, bar):
    """:func:`rollout` (``record=True``) in chunks with a progress bar: numpy outputs, the same
    values; it stops early once the state is non-finite."""
    parts = [ld.initial_state(model) for ld in loads]
    z0 = jnp.concatenate(parts) if parts else jnp.zeros(0)
    q0, qd0 = jnp.asarray(q0, jnp.float64), jnp.asarray(qd0, jnp.float64)
    t0, dt = jnp.asarray(t0, jnp.float64), jnp.asarray(dt, jnp.float64)
    return _run_chunked(
        lambda: _start_jit(model, loads, q0, qd0, z0, t0, dt, integrator=integrator, record=True),
        lambda carry, c: _chunk_jit(model, loads, carry, dt, n_blocks=c, integrator=integrator,
                                    save_every=save_every, record=True),
        n_steps // save_every, save_every, bar, time_axis=0)


def _check_concrete_positive(value, what):
    """A positive finite number of seconds, where the value is known (not a jax tracer)."""
    if isinstance(value, jax.core.Tracer):
        return
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: {value!r} is not a number; give a positive number of seconds") from None
    if v.size == 0 or not (np.all(np.isfinite(v)) and np.all(v > 0)):
        raise ValueError(f"{what}: {value!r}; give a positive, finite number of seconds")


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
            except (TypeError, ValueError):
                raise ValueError(f"{what}[{k!r}]: {v!r} is not a number") from None
    else:
        try:
            out = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{what}: {value!r} is not an array of numbers") from None
        if out.shape != (n,):
            raise ValueError(f"{what}: shape {out.shape} does not match the {n} coordinates "
                             f"{list(model.coordinates)}; give an array of shape ({n},) or a dict")
    bad = [model.coordinates[k] for k in np.flatnonzero(~np.isfinite(out))]
    if bad:
        raise ValueError(f"{what}: not finite for {bad}; give finite numbers (m, rad; m/s, rad/s)")
    return out


def _number(value, what, *, positive=False, nonnegative=False, allow_none=False):
    """A finite float, with a message naming the argument when it is not."""
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"{what}: {value!r} is not a finite number")
    if positive and not value > 0:
        raise ValueError(f"{what}: {value!r} must be > 0")
    if nonnegative and not value >= 0:
        raise ValueError(f"{what}: {value!r} must be ≥ 0")
    return float(value)


@jax.jit
def _stiffness_jacobian(model, loads, q):
    """(∂q̈/∂q, −∂Q/∂q) at (q, q̇ = 0, z = 0, t = 0), Q = Bᵀ F + τ the generalised loads
    (M* q̈ = Q at rest): compiled once per model and loads structure."""
    TRACES["stiffness"] += 1
    qd0 = jnp.zeros(model.n_coordinates)
    mems = _init_memories(model, loads, 0.0, q, qd0, 1.0)
    z0 = jnp.zeros(sum(ld.n_states for ld in loads))

    def qdd_and_Q(x):
        kin = kinematics(model, x, qd0)
        body, tau, mass, _ = applied_loads(model, loads, 0.0, x, qd0, z0, kin, mems)
        ev = evaluate(model, x, qd0, tau=tau, body_loads=body, extra_mass=mass, kin=kin)
        return ev.qdd, jnp.einsum("nai,na->i", kin.B, ev.F) + ev.Q

    J, dQ = jax.jacfwd(qdd_and_Q)(q)
    return J, -dQ


def _at_rest(loads) -> tuple[Load, ...]:
    """The loads as the linearisation at rest sees them: each load's still-water part
    (:meth:`Load.static_load`: the water without its waves and radiation memory), a load without
    one (a user's function of t, q, q̇; a probe) as it is. The sea and the ramp of a run do not
    change what restores a coordinate."""
    return tuple(ld if (s := ld.static_load()) is None else s for ld in _as_loads(loads))


def linearised_at_rest(model: Model, q, loads=()) -> tuple[np.ndarray, np.ndarray]:
    """(J, K), each (n_q, n_q), at configuration q, q̇ = 0, t = 0 with the loads at rest
    (:func:`_at_rest`): J = ∂q̈/∂q (q̈ ≈ J δq for a small displacement δq; its eigenvalues give
    the stability check's periods) and the static stiffness K = −∂Q/∂q of the generalised loads
    Q (gravity, buoyancy, water plane, moorings, joint springs; K = −M* J at an equilibrium)."""
    J, K = _stiffness_jacobian(model, _at_rest(loads), jnp.asarray(q, jnp.float64))
    return np.asarray(J), np.asarray(K)


def free_coordinates(model: Model, K) -> list[str]:
    """The coordinates nothing pulls back: K_kk ≤ 1e-9 of the largest |K| for the static
    stiffness K (:func:`linearised_at_rest`), i.e. displaced alone, q_k feels no load back towards
    where it was. An unmoored body's surge (RM3's spar, the M4's bow float: a column of exact
    zeros) drifts after the start-up transient under wave drift and any mean load; K_kk < 0 (a
    slider on a hanging arm) is unstable alone. Where K is positive semi-definite, K_kk = 0 means
    the whole column is zero. 1e-9: far below any restoring entry of the shipped configs (the
    smallest is ≥ 1e-5 of their largest) and far above the round-off of a zero one."""
    K = np.asarray(K)
    scale = max(float(np.abs(K).max()), 1e-300)
    return [c for k, c in enumerate(model.coordinates) if float(K[k, k]) <= 1e-9 * scale]


def _still_water_loads(model: Model, loads=None, *, added_mass="lhs", integrator="rk4"):
    """``model``'s own loads in still water (no radiation memory) and the extra ``loads``: what the
    checks linearise at rest (:func:`_at_rest`). At rest they have the structure of every run's
    loads at rest, whatever its sea, radiation and length (:meth:`Water.static_load` holds no
    table of the run's length), so one compiled linearisation serves them all."""
    return model_loads(model, None, dt=1.0, duration=1.0, radiation="none", added_mass=added_mass,
                       integrator=integrator) + _as_loads(loads)


def no_restoring(model: Model, q0=None, *, loads=None) -> list[str]:
    """The coordinates of ``model`` nothing pulls back at q0 (default 0, the start of
    :func:`simulate` and ``mfm simulate`` without ``--initial``), under its own loads in still
    water and ``loads`` (:func:`free_coordinates`): what ``mfm info`` reports, and what
    :func:`simulate` records in its ``no_restoring`` attribute for a run from the same q0 with
    the same extra loads, whatever its sea."""
    _, K = linearised_at_rest(model, _initial_vector(model, q0, "q0"),
                              _still_water_loads(model, loads))
    return free_coordinates(model, K)


def shortest_natural_period(model: Model, q, loads=()) -> float:
    """Estimate of the shortest natural period (s) at configuration q (q̇ = 0): 2π/√λ_max with λ
    the eigenvalues of −∂q̈/∂q (:func:`linearised_at_rest`: the mass matrix, added mass included,
    and every restoring load). Returns inf when nothing is restoring."""
    return _period_from_jacobian(linearised_at_rest(model, q, loads)[0])


def _period_from_jacobian(Jq) -> float:
    lam = np.linalg.eigvals(-np.asarray(Jq)).real
    lam_max = lam.max() if lam.size else 0.0
    return math.inf if lam_max <= 0 else 2.0 * math.pi / math.sqrt(lam_max)


def _nonfinite_message(model, integ, t, q, qd, dt, loads, k):
    coords = [model.coordinates[j] for j in range(model.n_coordinates)
              if not (np.isfinite(q[k, j]) and np.isfinite(qd[k, j]))]
    k_ok = max(k - 1, 0)
    head = (f"the state went non-finite at t = {t[k]:.6g} s (first saved sample; last finite at "
            f"t = {t[k_ok]:.6g} s) in coordinate(s) {coords}.")
    for ld in loads:
        cause = ld.describe_nonfinite(model, q[k_ok], qd[k_ok])
        if cause:
            return f"{head} {cause}"
    # linearised at the start, as the stability warning is: the last finite state of a diverging
    # run is itself far from any equilibrium
    T_min = shortest_natural_period(model, q[0], loads)
    lines = [head]
    if math.isfinite(T_min):
        ratio = 2 * math.pi * dt / T_min
        lines.append(f"Likely cause: dt = {dt:.4g} s against the shortest natural period "
                     f"{T_min:.4g} s (ω dt = {ratio:.3g}; {integ.name} is stable for ω dt < "
                     f"{integ.stability_limit:.3g}).")
        if ratio >= 0.5 * integ.stability_limit:
            lines.append(f"Reduce dt below {stable_dt(T_min, integ):.3g} s or use integrator='newmark'.")
        else:
            lines.append("dt is inside the stability limit, so look at the loads or the model: "
                         "large rotations of a free root near pitch = ±90° (Euler angle "
                         "singularity), a load that grows without bound, or a bad parameter.")
    else:
        lines.append("No restoring stiffness at the last finite state: look at the loads, a "
                     "parameter, or a free root near pitch = ±90° (Euler angle singularity).")
    return " ".join(lines)


def _warn_accuracy(model, sea, dt, integ, tol=0.01):
    """Warn when the shortest wave period with energy (amplitude ≥ 5 % of the largest component)
    is resolved with a period error above ``tol`` by the integrator (its leading error term,
    :func:`mfm.integrators.phase_error`)."""
    comps = sea.components(water_depth=model.hydro.water_depth, g=model.hydro.g)
    amp = np.abs(np.asarray(comps.amplitude, dtype=float))
    if not amp.size or amp.max() <= 0:
        return
    w_hi = float(np.max(np.asarray(comps.omega)[amp >= 0.05 * amp.max()]))
    err = _integrators.phase_error(integ, w_hi * dt)
    if err > tol:
        # the dt that brings the error to tol (phase_error is a power of ω dt)
        p = 4 if getattr(integ, "order", 2) >= 4 else 2
        dt_ok = dt * (tol / err) ** (1.0 / p)
        warnings.warn(
            f"dt = {dt:.4g} s is coarse for the sea: its shortest period with energy is "
            f"{2 * math.pi / w_hi:.4g} s (ω dt = {w_hi * dt:.3g}), where {integ.name} makes a "
            f"period (phase) error of about {100 * err:.2g} % per wave period, which accumulates "
            f"into amplitudes and power. Use dt ≤ {dt_ok:.3g} s for {100 * tol:g} %.",
            AccuracyWarning, stacklevel=3)


def stable_dt(T_min: float, integ) -> float:
    """The largest stable dt at the shortest natural period T_min: ω dt < the integrator's limit."""
    return T_min * integ.stability_limit / (2 * math.pi)


def _compile_ahead(jitted, *args, **static):
    """Compile ``jitted`` for these arguments (jit's lower/compile): a later call with arguments
    of the same structure and shapes finds it compiled, traced once."""
    return jitted.lower(*args, **static).compile()


def simulate(model: Model, sea=None, *, duration: float, dt: float, integrator="rk4",
             q0=None, qd0=None, loads=None, save_every: int = 1, t0: float = 0.0,
             ramp: float = 0.0, radiation: str = "auto", memory: float | None = None,
             state_space_options: dict | None = None, check_stability: bool = True,
             added_mass: str = "lhs", progress: bool | dict = False) -> xr.Dataset:
    """Simulate a model in the time domain.

    Parameters
    ----------
    model: a compiled :class:`~mfm.mechanics.model.Model` (with its water if the config has ``[hydro]``).
    sea: a sea state from :mod:`hydro.waves` (``Regular``, ``Jonswap``, …), or None (still water,
        or no water at all for a mechanics-only model).
    duration, dt: s. The run has ``round(duration / dt)`` steps.
    integrator: ``"rk4"`` (default), ``"beeman"`` (seed 001 eq. 52), ``"semi_implicit"``,
        ``"newmark"``, ``"verlet"`` (one evaluation per step, second order: the fast one, with
        ``radiation="state_space_exact"``), or an instance from :mod:`mfm.integrators`.
    q0, qd0: initial coordinates and rates, arrays (n_q,) or dicts by coordinate name (others 0).
    loads: an :class:`mfm.loads.Load` or a sequence of them (external loads), added to the
        model's own (its water and its config's loads).
    save_every: keep every k-th step in the output.
    ramp: s, the start-up ramp of the excitation (½(1 − cos πt/ramp)).
    radiation: ``"auto"`` (default: the cheaper of the next two for this run,
        :func:`choose_radiation`; the choice and why are in the attribute ``radiation_choice``),
        ``"convolution"`` (direct, window T_K from the decay of K; ``memory`` overrides it,
        s), ``"state_space"`` (the passive fit of :mod:`hydro.statespace`, options in
        ``state_space_options``, its states integrated by the integrator),
        ``"state_space_exact"`` (the same fit, its states advanced exactly over each step: stable
        at any dt, what ``integrator="verlet"`` needs) or ``"none"`` (A∞ only).
    added_mass: ``"lhs"`` (A∞ in M*, the default) or ``"rhs"``: the scheme of seed 001 §5, A∞ ξ̈
        on the right-hand side with the acceleration iterated in Beeman's corrector (needs
        ``integrator="beeman"``; converges only where A∞ is smaller than the structural mass; the
        iteration counts are in ``iterations``).
    check_stability: warn (:class:`StabilityWarning`) before running when dt exceeds the
        integrator's stability limit at the shortest natural period of the model linearised at q0,
        and (:class:`AccuracyWarning`) when Verlet integrates coordinates without restoring.
    progress: False (default), True for a progress bar (tqdm, on stderr), or a dict of tqdm
        options (e.g. ``{"delay": 5}``: shown only once the run has taken 5 s). The run is then
        made in 20 to 100 chunks of one compiled function, with the bar updated between them;
        the results are the same to the last bit.

    Returns an :class:`xarray.Dataset` with ``q``, ``qd``, ``qdd`` (time, coordinate),
    ``body_position`` (time, body, axis) CoM in inertial axes, ``body_rotation`` (time, body, angle)
    roll/pitch/yaw (R = R_z(yaw) R_y(pitch) R_x(roll)), ``joint_force`` and ``joint_moment``
    (time, body, axis): the load each body's joint transmits from the parent (inertial axes, moment
    about the joint point), ``kinetic_energy`` and ``potential_energy`` (time), ``iterations``
    (corrector iterations of the step), ``pto_power`` and ``pto_displacement`` (time, pto) for each
    joint damper and hydraulic PTO; with water also ``eta`` (time), ``xi`` (time, hydro_dof) and
    ``hydro_force`` (time, component, hydro_dof); each load's own outputs (e.g. ``point_position``
    of named body points). Units and provenance (config, database, sea state, settings, versions)
    are in the attributes (:mod:`mfm.results`).

    Raises :class:`SimulationError` when the state goes non-finite; its ``dataset`` holds the run
    up to the last finite sample.
    """
    if sea is not None and model.hydro is None:
        raise ValueError("sea: this model has no hydrodynamics (no [hydro] table in its config, or "
                         "mfm.load(..., hydro=False)); pass sea=None")
    dt = _number(dt, "dt", positive=True)
    duration = _number(duration, "duration", positive=True)
    t0 = _number(t0, "t0")
    ramp = _number(ramp, "ramp", nonnegative=True)
    memory = _number(memory, "memory", positive=True, allow_none=True)
    progress = _progress_options(progress)
    n_steps = int(round(duration / dt))
    if n_steps < 1:
        raise ValueError(f"duration = {duration} s is shorter than one step dt = {dt} s")
    if isinstance(save_every, bool) or not isinstance(save_every, numbers.Integral) \
            or save_every < 1 or n_steps % save_every:
        raise ValueError(f"save_every: {save_every!r} must be a positive divisor of the {n_steps} "
                         "steps")
    integ = _integrators.get(integrator)
    if added_mass not in ("lhs", "rhs"):
        raise ValueError(f"added_mass={added_mass!r}; accepted: 'lhs' (A∞ in M*), 'rhs' (seed 001)")
    if added_mass == "rhs" and integ.name != "beeman":
        raise ValueError(f"added_mass='rhs' (the seed 001 scheme) iterates the acceleration in "
                         f"Beeman's corrector; integrator={integ.name!r} has none: use "
                         "integrator='beeman' or added_mass='lhs'")
    choice = "given"
    if radiation == "auto":
        radiation, choice = choose_radiation(model, dt=dt, n_steps=n_steps, integrator=integ,
                                             memory=memory)
        if model.hydro is None:
            radiation = "convolution"          # no water: nothing to choose
    q0 = _initial_vector(model, q0, "q0")
    qd0 = _initial_vector(model, qd0, "qd0")
    extra = _as_loads(loads)
    free = []
    # The checks' linearisation at q0 (a Jacobian of the dynamics, ~6 s to compile for M4 134)
    # compiles on a second thread while this one builds the run's water (its radiation fit, in
    # numpy) and compiles the run. An error here returns at once: that compilation finishes on
    # its own.
    pool = concurrent.futures.ThreadPoolExecutor(1)
    try:
        if check_stability:
            # still water's loads at rest have the structure of the run's, so the Jacobian
            # compiles while this thread builds the run's water (its radiation fit) and is then
            # evaluated with the run's own loads
            rest = _at_rest(_still_water_loads(model, extra, added_mass=added_mass,
                                               integrator=integ))
            ahead = pool.submit(_compile_ahead, _stiffness_jacobian, model, rest,
                                jnp.asarray(q0, jnp.float64))
        loads = model_loads(model, sea, dt=dt, duration=duration, t0=t0, ramp=ramp,
                            radiation=radiation, memory=memory,
                            state_space_options=state_space_options, added_mass=added_mass,
                            integrator=integ) + extra
        # the recorded run, compiled here: beside the Jacobian's compile where the water builds
        # faster than that (no fit), and before the checks' warnings
        run = None if progress is not None else _rollout_call(
            model, q0, qd0, dt=dt, n_steps=n_steps, integrator=integ, loads=loads,
            save_every=save_every, t0=t0, z0=None, record=True)
        if run is not None:
            _compile_ahead(_rollout_jit, *run[0], **run[1])
        if check_stability:
            ahead.result()
            # one linearisation at q0 gives the shortest period and the coordinates that nothing
            # pulls back (those of no_restoring(model, q0, loads=<the extra loads>), `mfm info`'s)
            Jq, K = linearised_at_rest(model, q0, loads)
            free = free_coordinates(model, K)
    finally:
        pool.shutdown(wait=False)
    if check_stability and math.isfinite(integ.stability_limit):
        T_min = _period_from_jacobian(Jq)
        if math.isfinite(T_min) and 2 * math.pi * dt / T_min > integ.stability_limit:
            warnings.warn(
                f"dt = {dt:.4g} s is beyond the stability limit of {integ.name}: the shortest natural "
                f"period of the model linearised at q0 is {T_min:.4g} s, ω dt = "
                f"{2 * math.pi * dt / T_min:.3g} > {integ.stability_limit:.3g}. Use dt < "
                f"{stable_dt(T_min, integ):.3g} s or integrator='newmark'.",
                StabilityWarning, stacklevel=2)
    if sea is not None:
        _warn_accuracy(model, sea, dt, integ)
    if free and integ.name == "verlet":
        warnings.warn(
            f"{free} have no restoring (nothing pulls them back) and integrator='verlet' takes the "
            "velocity-dependent loads at a lagged velocity: a small steady force on them, so their "
            "velocity drifts without bound in a long run (M4 134, 10⁶ steps: surge 147 m against "
            "RK4's 0.32 m; docs/stability.md §3). The other coordinates' statistics are not "
            "affected. Use integrator='rk4' where their position matters, or moor the body.",
            AccuracyWarning, stacklevel=2)
    bar = _progress_bar(progress, n_steps, model.name)
    if bar is None:
        out = _rollout_jit(*run[0], **run[1])
    else:
        out = _rollout_progress(model, q0, qd0, dt=dt, n_steps=n_steps, integrator=integ,
                                loads=loads, save_every=save_every, t0=t0, bar=bar)
    t, q, qd, qdd, z, iters = (np.asarray(a) for a in out[:6])
    rec = {k: np.asarray(v) for k, v in out[6].items()}
    settings = dict(duration=duration, n_steps=n_steps, save_every=int(save_every), t0=t0,
                    complete="true", ramp_s=ramp, memory_s=memory,
                    sea="still water" if sea is None else repr(sea), radiation_choice=choice,
                    no_restoring=", ".join(free) if check_stability else "not checked")
    finite = np.isfinite(q).all(axis=1) & np.isfinite(qd).all(axis=1)
    if not finite.all():
        k = int(np.argmax(~finite))
        message = _nonfinite_message(model, integ, t, q, qd, dt, loads, k)
        partial = None
        if k > 0:
            keep = slice(0, k)
            settings.update(complete="false", stopped=message)
            partial = results.time_series(model, loads, integ, dt, t[keep], q[keep], qd[keep],
                                          rec["qdd"][keep], iters[keep],
                                          {n: v[keep] for n, v in rec.items()}, settings)
        raise SimulationError(message + (f" The run up to t = {t[k - 1]:.6g} s is in this error's "
                                         "`dataset`." if partial is not None else ""), partial)
    return results.time_series(model, loads, integ, dt, t, q, qd, rec["qdd"], iters, rec, settings)


def _sea_labels(seas):
    """Per-case labels of a batch's sea states (Hs, Tp, H, T, gamma, heading) where every sea has
    the attribute."""
    units = {"hs": "m", "tp": "s", "height": "m", "period": "s", "gamma": "1", "heading": "rad"}
    out = {}
    for name, u in units.items():
        vals = [getattr(s, name, None) for s in seas]
        if all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in vals):
            out[f"sea_{name}"] = (np.asarray(vals, dtype=float), {"units": u})
    return out


def simulate_batch(model, seas, *, dt, n_steps: int, integrator="rk4", ramp=0.0,
                   radiation: str = "state_space", state_space_options: dict | None = None,
                   memory: float | None = None, save_every: int = 1, t0: float = 0.0,
                   q0=None, qd0=None, loads=None, outputs=(), vary_loads=None,
                   progress: bool | dict = False, lanes: int | None = None,
                   threads: int | None = None) -> xr.Dataset:
    """Many runs of one topology in one compiled call: a sweep over sea states,
    time steps and model parameters (a power matrix, a T_p sweep at dt = T_p/200, a hinge-height
    study) without retracing.

    model: a :class:`Model`, or a sequence of Models of one topology (parameters differ, e.g.
        made with ``equinox.tree_at``; their ``hydro`` must be the same object).
    seas: a sea state or a sequence of them (``hydro.waves``; None for still water).
    dt, ramp: s, a number or one per case. Every case runs ``n_steps`` steps (so a sweep at
        dt = T_p/200 over 100 T_p is one shape: 20,000 steps).
    radiation: "state_space" (default; its arrays have one shape whatever dt), "none", or
        "convolution" (only when every case has the same number of lags, e.g. one dt).
    loads: extra loads for every case (as in :func:`simulate`).
    vary_loads: a function ``(case_index, loads) -> loads`` that changes load parameters per case
        (arrays only, e.g. ``equinox.tree_at`` on the water's ``drag`` for a drag-coefficient sweep,
        or on a wind load's speed): the cases stay one compiled, vmapped call. ``loads`` is the
        case's tuple (its water first, then the model's and the extra loads); the structure must
        not change.
    outputs: names of per-sample outputs to record as well (a load's diagnostics such as
        ``point_acceleration`` of the ``[[points]]``, or ``body_rotation``, ``joint_force``, ...:
        the names :func:`simulate` records); only what is named is computed and kept, as
        (case, step, ...) arrays.
    progress: False (default), True or a dict of tqdm options: a bar over the steps (every case
        advances together), as in :func:`simulate`; the same results.
    lanes: cases advanced together by one ``jax.vmap``-ed time loop; the groups run one after
        another (``jax.lax.map``) in the same compiled call. None (default): 1 on a CPU, where a
        vmapped loop cost 1.6–2× a single run per case-step, every case on a GPU
        (:func:`default_lanes`). The results are the same to round-off whatever the width.
    threads: host threads, each running its part of the cases at once with the others (XLA on a
        CPU runs a compiled call on the thread that made it, one core each). None (default): one
        per core this process may use on a CPU (:func:`default_threads`), 1 on a GPU. The
        results are the same numbers whatever the count.
    Sequences of length > 1 must agree in length B; length-1 arguments are broadcast.

    Returns an :class:`xarray.Dataset` with dimensions (case, step, coordinate): ``time``
    (case, step), ``q``, ``qd``, ``pto_power`` (case, step, pto) of the joint dampers, ``eta``
    (case, step) the undisturbed elevation at the origin, ``dt`` (case), and the sea states'
    parameters as coordinates on ``case`` (``sea_hs``, ``sea_tp``, …).
    Raises :class:`SimulationError` naming the first case that goes non-finite.
    """
    models = list(model) if isinstance(model, (list, tuple)) else [model]
    seas = list(seas) if isinstance(seas, (list, tuple)) else [seas]
    try:
        dts = np.atleast_1d(np.asarray(dt, dtype=float))
        ramps = np.atleast_1d(np.asarray(ramp, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"dt, ramp: {dt!r}, {ramp!r}; give numbers of seconds (one, or one per "
                         "case)") from None
    sizes = {"model": len(models), "seas": len(seas), "dt": dts.size, "ramp": ramps.size}
    B = max(sizes.values())
    bad = {k: v for k, v in sizes.items() if v not in (1, B)}
    if bad:
        raise ValueError(f"simulate_batch: the batched arguments must have one length or 1; got "
                         f"{sizes}")
    if not (np.all(dts > 0) and np.all(np.isfinite(dts))):
        raise ValueError(f"dt: {dts} must be positive numbers of seconds")
    if not (np.all(ramps >= 0) and np.all(np.isfinite(ramps))):
        raise ValueError(f"ramp: {ramps} must be numbers of seconds ≥ 0")
    if isinstance(n_steps, bool) or not isinstance(n_steps, numbers.Integral) or n_steps < 1 \
            or n_steps % save_every:
        raise ValueError(f"n_steps: {n_steps!r} must be a whole number ≥ 1 and a multiple of "
                         f"save_every={save_every}")
    t0 = _number(t0, "t0")
    memory = _number(memory, "memory", positive=True, allow_none=True)
    progress = _progress_options(progress)
    if lanes is None:
        lanes = default_lanes(B)
    elif isinstance(lanes, bool) or not isinstance(lanes, numbers.Integral) or lanes < 1:
        raise ValueError(f"lanes: {lanes!r}; give a whole number ≥ 1 of cases to advance "
                         "together in one vmapped loop, or None (1 on a CPU, all on a GPU)")
    lanes = int(lanes)
    if threads is None:
        threads = default_threads()
    elif isinstance(threads, bool) or not isinstance(threads, numbers.Integral) or threads < 1:
        raise ValueError(f"threads: {threads!r}; give a whole number ≥ 1 of host threads, or None "
                         "(one per core on a CPU)")
    threads = min(int(threads), B)
    pick = lambda seq, i: seq[i if len(seq) > 1 else 0]  # noqa: E731
    structure = {m_.coordinates for m_ in models}
    if len(structure) > 1 or len({id(m_.hydro) for m_ in models}) > 1:
        raise ValueError("model: the models of a batch must share one topology and one hydro "
                         "spec (make them from one Model with equinox.tree_at)")
    integ = _integrators.get(integrator)
    outputs = _output_names(outputs)
    extra = _as_loads(loads)
    loads = [model_loads(pick(models, i), pick(seas, i), dt=float(pick(dts, i)),
                         duration=n_steps * float(pick(dts, i)), t0=t0, ramp=float(pick(ramps, i)),
                         radiation=radiation, memory=memory,
                         state_space_options=state_space_options, integrator=integ) + extra
             for i in range(B)]
    if vary_loads is not None:
        if not callable(vary_loads):
            raise ValueError(f"vary_loads: {vary_loads!r}; give a function (case_index, loads) -> "
                             "loads")
        loads = [tuple(vary_loads(i, ld)) for i, ld in enumerate(loads)]
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

    known = set(results.record_specs(m0, loads[0])[0])
    bad = [n for n in outputs if n not in known]
    if bad:
        raise ValueError(f"outputs: {bad} are not outputs of this model and its loads; accepted: "
                         f"{sorted(known)}")

    model_axis = 0 if len(models) > 1 else None
    dts_all = np.broadcast_to(dts, (B,))
    # the cases in `threads` parts of one size (the last padded by repeating its last case): one
    # compiled program serves every part, each run from its own host thread
    size = -(-B // threads)
    lanes = min(lanes, size)
    groups = [np.minimum(np.arange(k, k + size), B - 1) for k in range(0, B, size)]
    args = [(stack([pick(models, i) for i in g]) if model_axis == 0 else m0,
             stack([loads[i] for i in g]), jnp.asarray(dts_all[g])) for g in groups]
    t0_ = jnp.asarray(t0, jnp.float64)
    bar = _progress_bar(progress, int(n_steps), f"{m0.name} × {B}")
    if bar is None:
        out = _join_parts(_in_threads(len(groups), lambda k: _batch_jit(
            args[k][0], args[k][1], q0, qd0, z0, t0_, args[k][2], model_axis=model_axis,
            n_steps=int(n_steps), integrator=integ, save_every=int(save_every), record=outputs,
            lanes=lanes)), B)
    else:
        def start():
            res = _in_threads(len(groups), lambda k: _start_batch_jit(
                args[k][0], args[k][1], q0, qd0, z0, t0_, args[k][2], model_axis=model_axis,
                integrator=integ, record=outputs, lanes=lanes))
            return [r[0] for r in res], _join_parts([r[1] for r in res], B)

        def chunk(carries, c):
            res = _in_threads(len(groups), lambda k: _chunk_batch_jit(
                args[k][0], args[k][1], carries[k], args[k][2], model_axis=model_axis,
                n_blocks=c, integrator=integ, save_every=int(save_every), record=outputs,
                lanes=lanes))
            return [r[0] for r in res], _join_parts([r[1] for r in res], B)

        out = _run_chunked(start, chunk, int(n_steps) // int(save_every), int(save_every), bar,
                           time_axis=1)
    t, q, qd = (np.asarray(a) for a in out[:3])
    for i in range(B):
        if not (np.isfinite(q[i]).all() and np.isfinite(qd[i]).all()):
            k = int(np.argmax(~np.isfinite(q[i]).all(axis=1) | ~np.isfinite(qd[i]).all(axis=1)))
            raise SimulationError(f"simulate_batch: case {i} went non-finite at t = {t[i, k]:.6g} s "
                                  f"(dt = {pick(dts, i):.4g} s); run it alone with mfm.simulate "
                                  "for the diagnosis")
    settings = dict(radiation=radiation, n_steps=int(n_steps), t0=t0, lanes=lanes,
                    ramp_s=repr(ramps.tolist()), seas=repr(seas))
    labels = _sea_labels(seas) if len(seas) == B else {}
    recorded = {k: np.asarray(v) for k, v in out[6].items()} if outputs else {}
    return results.batch(m0, [pick(models, i) for i in range(B)], loads, integ, t, q, qd, dts,
                         settings, save_every, labels, recorded)
