"""The pure core of the time domain: the system f(t, q, q̇, z) → (q̈, ż) of the integrators and
the rollout, ``lax.scan`` over steps, compiled once per (topology, n_steps, integrator,
save_every, loads structure); vmap- and grad-friendly."""
from __future__ import annotations

import collections
from typing import Sequence

import jax
import jax.numpy as jnp

from ..loads.assembly import applied_loads, as_loads, compile_view, initial_states
from ..loads.base import Load
from ..mechanics.dynamics import evaluate
from ..mechanics.kinematics import kinematics
from ..mechanics.model import Model
from ..validation import positive_seconds, whole_number
from . import integrators as _integrators
from .record import (EVERY, STATE, Recording, deferred,
                     outputs_after, saved)


# How many times each compiled function was traced (a retrace means a recompilation); tests use it.
TRACES: collections.Counter = collections.Counter()


def dynamics_function(model: Model, loads: Sequence[Load] = (), memories=None):
    """The system ``f(t, q, q̇, z) -> (q̈, ż)`` of the integrators: MFM equations of motion plus the
    external loads (with their memories of the current step)."""

    def f(t, q, qd, z, qdd_guess=None):
        kin = kinematics(model, q, qd)
        body, tau, mass, zd = applied_loads(model, loads, t, q, qd, z, kin, memories,
                                            qdd_guess=qdd_guess)
        return evaluate(model, q, qd, tau=tau, body_loads=body, extra_mass=mass, kin=kin).qdd, zd

    return f


def init_memories(model, loads, t0, q0, qd0, dt):
    return tuple(ld.init_memory(model, t0, q0, qd0, dt) for ld in loads)


def update_memories(model, loads, s, memories):
    if not loads:
        return memories
    kin = kinematics(model, s.q, s.qd)
    return tuple(ld.update_memory(model, s.t, s.q, s.qd, kin, mem) for ld, mem in zip(loads, memories))


def rollout_start(model, loads, q0, qd0, z0, t0, dt, integrator, recording: Recording):
    """The initial carry (integrator state, load memories) and its saved outputs (deferred ones
    by the same vmapped program as the later samples', :func:`outputs_after`)."""
    mem0 = init_memories(model, loads, t0, q0, qd0, dt)
    state = integrator.init(dynamics_function(model, loads, mem0), t0, q0, qd0, z0)
    carry = (state, mem0)
    if deferred(carry, recording):
        one = outputs_after(model, loads, jax.tree_util.tree_map(lambda a: a[None], carry),
                            recording)
        return carry, jax.tree_util.tree_map(lambda a: a[0], one)
    return carry, saved(model, loads, state, mem0, recording)


def rollout_blocks(model, loads, carry, dt, n_blocks, integrator, save_every,
                   recording: Recording, keep_carries: bool = False):
    """``n_blocks`` blocks of ``save_every`` steps from ``carry``: (carry, what ``recording``
    keeps of each block's last step, stacked). With every output recorded and a small memory (the
    state space's, not the convolution's history) the loop keeps only the state and memory of
    each saved step and the outputs are evaluated afterwards in one vmapped pass
    (:func:`outputs_after`): the serial loop carries the integration alone (RM3: recording every
    step cost 5× the integration inside it). ``keep_carries``: the saved carries themselves, for
    that pass to be made by the caller."""

    def one_step(carry, _):
        s, mem = carry
        s = integrator.step(dynamics_function(model, loads, mem), s, dt)
        return (s, update_memories(model, loads, s, mem)), None

    later = keep_carries or deferred(carry, recording)

    def block(carry, _):
        carry, _ = jax.lax.scan(one_step, carry, None, length=save_every)
        return carry, (carry if later else saved(model, loads, *carry, recording))

    carry, out = jax.lax.scan(block, carry, None, length=n_blocks)
    if later and not keep_carries:
        out = outputs_after(model, loads, out, recording)
    return carry, out


def rollout_impl(model, loads, q0, qd0, z0, t0, dt, n_steps, integrator, save_every, record):
    TRACES["rollout"] += 1
    recording = Recording.of(record)
    n_blocks = n_steps // save_every
    carry, _ = rollout_start(model, loads, q0, qd0, z0, t0, dt, integrator, STATE)
    if deferred(carry, recording):
        # the initial sample's outputs in the same pass as the others': one copy of the outputs'
        # program to compile, not two (M4 134: ~4 s of a first call)
        return _blocks_with_head(model, loads, carry, dt, n_blocks, integrator, save_every,
                                 recording)[1]
    first = saved(model, loads, *carry, recording)
    _, traj = rollout_blocks(model, loads, carry, dt, n_blocks, integrator, save_every, recording)
    return jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a[None], b]), first, traj)


rollout_jit = jax.jit(rollout_impl,
                       static_argnames=("n_steps", "integrator", "save_every", "record"))


# The chunked rollout the runner shows as it goes: the same start and blocks, compiled as two
# functions (the blocks one once for the chunk length), called from the host between chunks.
def _chunk_impl(model, loads, carry, dt, n_blocks, integrator, save_every, recording):
    TRACES["rollout_chunk"] += 1
    return rollout_blocks(model, loads, carry, dt, n_blocks, integrator, save_every, recording)


def _blocks_with_head(model, loads, carry, dt, n_blocks, integrator, save_every,
                      recording: Recording = EVERY):
    """``n_blocks`` blocks of a recorded run whose outputs are deferred (:func:`deferred`): the
    last carry, and the outputs of the incoming carry (the head) and of the blocks' saved
    carries in one pass (:func:`outputs_after`: each sample by the same vmapped program, so a
    run in one call and in chunks give the same bits)."""
    carry_out, carries = rollout_blocks(model, loads, carry, dt, n_blocks, integrator, save_every,
                                        EVERY, keep_carries=True)
    stacked = jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a[None], b]), carry, carries)
    return carry_out, outputs_after(model, loads, stacked, recording)


def _headed_chunk_impl(model, loads, carry, dt, n_blocks, integrator, save_every,
                       recording: Recording = EVERY):
    """A chunk of a recorded run whose outputs are deferred (:func:`_blocks_with_head`), in one
    program with its steps (a run too short for the runner to pipeline, :mod:`mfm.runner.pipeline`).
    The host keeps the head of the first chunk only (the run's initial sample): the start then
    needs no outputs program of its own, and a first run compiles one copy of the outputs instead
    of two (RM3: the start's 4.7 of 14 s of compilation, cold)."""
    TRACES["rollout_chunk"] += 1
    return _blocks_with_head(model, loads, carry, dt, n_blocks, integrator, save_every,
                             recording)


def _steps_impl(model, loads, carry, dt, n_blocks, integrator, save_every):
    """A chunk of a pipelined run (:mod:`mfm.runner.pipeline`): ``n_blocks`` blocks from
    ``carry``, the carry after them and each block's saved carry, stacked; no outputs."""
    TRACES["rollout_chunk"] += 1
    return rollout_blocks(model, loads, carry, dt, n_blocks, integrator, save_every, EVERY,
                          keep_carries=True)


def _outputs_impl(model, loads, head, carries, recording: Recording = EVERY):
    """What ``recording`` keeps of a pipelined chunk's samples: the incoming carry (the head),
    then the chunk's saved carries, by :func:`outputs_after` (each sample the same vmapped
    computation as in a run made in one call)."""
    TRACES["rollout_outputs"] += 1
    stacked = jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a[None], b]), head, carries)
    return outputs_after(model, loads, stacked, recording)


# for the memories' shapes only: a jit keeps its trace, so a warm run does not trace them again
init_memories_jit = jax.jit(init_memories)
start_jit = jax.jit(rollout_start, static_argnames=("integrator", "recording"))


chunk_jit = jax.jit(_chunk_impl, static_argnames=("n_blocks", "integrator", "save_every",
                                                   "recording"))


headed_chunk_jit = jax.jit(_headed_chunk_impl, static_argnames=("n_blocks", "integrator",
                                                                 "save_every", "recording"))


steps_jit = jax.jit(_steps_impl, static_argnames=("n_blocks", "integrator", "save_every"))


outputs_jit = jax.jit(_outputs_impl, static_argnames=("recording",))


def rollout(model: Model, q0, qd0, *, dt, n_steps: int, integrator="rk4", loads=None,
            save_every: int = 1, t0=0.0, z0=None, record=False):
    """Pure, jit-compiled rollout: returns ``(t, q, qd, qdd, z, iterations)`` arrays with a leading
    time axis of length ``n_steps // save_every + 1`` (the initial state first).

    Compiled once per (topology, n_steps, integrator, save_every, loads structure): changing any
    array parameter of ``model`` or ``loads``, ``dt``, ``q0``, ``qd0`` reuses the compiled code, and
    the function can be ``jax.vmap``-ed over a batched model or ``jax.grad``-ed (RK4, semi-implicit
    and Newmark; Beeman's while loop is forward-mode only). ``record=True`` appends a dict of
    per-sample outputs (poses, joint reactions, energies, load diagnostics) as a 7th item; a tuple
    of output names (e.g. ``("point_acceleration",)``) records only those, and z comes back
    empty (the batch form: the loads' states are not kept per sample); or a
    :class:`~mfm.timedomain.record.Recording`, which these stand for.
    """
    args, options = rollout_call(model, q0, qd0, dt=dt, n_steps=n_steps, integrator=integrator,
                                  loads=loads, save_every=save_every, t0=t0, z0=z0, record=record)
    return rollout_jit(*args, **options)


def rollout_call(model, q0, qd0, *, dt, n_steps, integrator, loads, save_every, t0, z0, record):
    """The arguments and static options of :func:`rollout`'s compiled call, checked."""
    loads = as_loads(loads)
    integ = _integrators.get(integrator)
    if not whole_number(n_steps):
        raise ValueError(f"n_steps: {n_steps!r}; give a positive whole number of steps")
    if not whole_number(save_every):
        raise ValueError(f"save_every: {save_every!r}; give a positive whole number")
    positive_seconds(dt, "dt")
    q0 = jnp.asarray(q0, jnp.float64)
    qd0 = jnp.asarray(qd0, jnp.float64)
    if z0 is None:
        z0 = initial_states(model, loads)
    model, loads = compile_view(model, loads)       # numbers-only variants share the compile
    args = (model, loads, q0, qd0, jnp.asarray(z0, jnp.float64), jnp.asarray(t0, jnp.float64),
            jnp.asarray(dt, jnp.float64))
    return args, dict(n_steps=int(n_steps), integrator=integ, save_every=int(save_every),
                      record=Recording.of(record))
