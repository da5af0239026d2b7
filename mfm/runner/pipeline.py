"""A recorded run of the pure rollout (:mod:`mfm.timedomain.rollout`), compiled and run by the
host: its programs from disk where an earlier process traced them (:mod:`.programs`), compiled on
other threads while the start runs, and long runs in chunks whose outputs are made on another
thread as the next chunk steps (:mod:`.progress`)."""
from __future__ import annotations

import time

import jax
import jax.numpy as jnp
import numpy as np

from ..loads.assembly import compile_view, initial_states
from ..timedomain.record import DEFERRED_RECORD_WIDTH, EVERY, STATE, Recording, deferred
from ..timedomain.rollout import (chunk_jit, headed_chunk_jit, init_memories_jit, outputs_jit,
                                  start_jit, steps_jit, rollout_jit)
from . import programs as _programs
from . import progress
from .progress import chunk_plan, run_chunked, run_pipelined
from .threads import background, result, wait


def _strong(tree):
    """``tree``'s arrays, strongly typed (the same dtypes and values)."""
    def strong(a):
        if isinstance(a, jax.Array) and not a.weak_type:
            return a
        if isinstance(a, jax.Array):
            # through the host: jnp's conversion of a weakly typed array is a program of its own,
            # compiled in a first run beside the run's (Wu & Yuan: 1.2 s on 2 busy cores)
            return jax.device_put(np.asarray(a))
        return jnp.asarray(a, a.dtype)
    return jax.tree_util.tree_map(strong, tree)


def prepare_run(model, q0, qd0, *, dt, n_steps, integrator, loads, save_every, t0,
                recording: Recording = EVERY, chunked: bool = False, fast: bool = False):
    """Start a recorded run and compile its programs, here and now; returns ``run(bar)``, which
    makes the run and gives what ``recording`` keeps of each saved step (numpy or jax arrays,
    the initial state first). Compiling before ``run`` lets :func:`~.simulation.simulate` do it
    while its checks' linearisation compiles on another thread (XLA compiles without the GIL): a
    first run waits for the longer of the two, not their sum.

    ``recording``: :data:`~.record.EVERY` (``rollout``'s ``record=True``) or
    :data:`~.record.OUTPUTS` (``simulate``'s: no loads' states per sample). Where its outputs
    are made after the time loop (:func:`~.record.deferred`: a small load memory) and the run
    saves at least :data:`~.progress.PIPELINE_MIN_SAMPLES` samples, it is pipelined
    (:func:`~.progress.run_pipelined`): chunks of steps on this thread, each chunk's outputs on
    another as the next one steps; ``chunked`` (a progress bar) in 20 to 100 chunks
    (:func:`~.progress.chunk_plan`), else in up to 8 (:func:`~.progress.pipeline_plan`).
    Other runs make their outputs after the loop in the same program (one program to compile
    instead of two), and a large memory (a convolution's history) makes them inside the loop: the
    whole run in one program, or with ``chunked`` in chunks of one
    (:func:`~.progress.run_chunked`). The same numbers every way.

    ``fast``: every program of the run compiled as a program run once is
    (:func:`mfm.runner.xla.once_options`: XLA's lowest optimisation level), for ``simulate``'s
    ``compile="fast"``: other last bits than the default's (no fused multiply–adds)."""
    began = time.perf_counter()
    z0 = initial_states(model, loads)
    q0, qd0 = jnp.asarray(q0, jnp.float64), jnp.asarray(qd0, jnp.float64)
    t0, dt = jnp.asarray(t0, jnp.float64), jnp.asarray(dt, jnp.float64)
    model, loads = compile_view(model, loads)
    n_blocks = n_steps // save_every
    memories = _programs.eval_shape(init_memories_jit, model, loads, t0, q0, qd0, dt)
    headed = deferred((None, memories), recording)
    pipelined = headed and n_blocks >= progress.PIPELINE_MIN_SAMPLES
    start_args = (model, loads, q0, qd0, z0, t0, dt)
    if not (pipelined or chunked):
        # the whole run, one program (from disk where an earlier process traced it); its outputs
        # after the loop (rollout_impl), or inside it for a large memory
        opts = dict(n_steps=n_steps, integrator=integrator, save_every=save_every,
                    record=recording)
        whole = _programs.program(rollout_jit, "rollout", start_args, opts, once=fast)
        # compiled on a daemon thread while this one waits: a Ctrl-C ends the process at once
        # (mfm.runner.threads)
        wait(whole.compile, *start_args)
        return lambda bar: whole(*start_args)
    if pipelined and not chunked:
        c, _ = progress.pipeline_plan(n_blocks, multiple=DEFERRED_RECORD_WIDTH)
    else:
        # where the outputs are made after the steps (pipelined, or in each headed chunk), a
        # multiple of their group width: each sample in the place of its group it has in the run
        # made in one program (the same bits; progress.run_pipelined). A headed chunk of 20
        # blocks put RM3's samples elsewhere in their groups: q̈, the joint and hydro forces
        # 1e-9 to 2e-7 relative off the run without a bar (issue 54, item 18)
        c, n = chunk_plan(n_blocks, multiple=DEFERRED_RECORD_WIDTH if headed else 1)
        if n * c - n_blocks > n_blocks // 4:
            # a short run (under ~128 blocks) in one chunk, rather than stepping up to 31 blocks
            # more than it saves: its first sample starts a group as in the run in one program
            c = n_blocks
    # the outputs of the initial sample come with the first chunk's (its head) where they are
    # made after the steps; else the start makes them, in the loop's way
    start_kw = dict(integrator=integrator, recording=STATE if headed else recording)
    # the chunk's programs compile on other threads from the start's shapes while this one
    # compiles and runs the start: XLA compiles without the GIL, so on several cores they
    # overlap. All come from disk where an earlier process traced them (mfm.runner.programs)
    start = _programs.program(start_jit, "rollout_start", start_args, start_kw, once=fast)
    # the carry strongly typed, however the start was made (a saved program keeps no weak types),
    # so that the chunk is one program, one key (the same dtypes: the same numbers)
    shapes = jax.tree_util.tree_map(lambda a: jax.ShapeDtypeStruct(a.shape, a.dtype),
                                    start.shapes(*start_args)[0])

    def compiled(fn, name, args, kw):
        made = _programs.program(fn, name, args, kw, once=fast)
        made.compile(*args)
        return made

    steps_kw = dict(n_blocks=c, integrator=integrator, save_every=save_every)
    # on daemon threads (mfm.runner.threads): a Ctrl-C while they compile ends the process at
    # once instead of at the end of their compilations
    if pipelined:
        stacked = jax.tree_util.tree_map(
            lambda a: jax.ShapeDtypeStruct((c,) + a.shape, a.dtype), shapes)
        ahead = [background(compiled, steps_jit, "rollout_steps", (model, loads, shapes, dt),
                            steps_kw),
                 background(compiled, outputs_jit, "rollout_outputs",
                            (model, loads, shapes, stacked), dict(recording=recording))]
    else:
        fn, name = ((headed_chunk_jit, "rollout_chunk_headed") if headed
                    else (chunk_jit, "rollout_chunk"))
        ahead = [background(compiled, fn, name, (model, loads, shapes, dt),
                            dict(steps_kw, recording=recording))]
    # the start compiled on a third while this one waits, then run here
    wait(start.compile, *start_args)
    carry, first = start(*start_args)
    carry = _strong(carry)
    # a pipelined run steps once its steps' program is ready: the outputs' program (the
    # larger: M4 134 3.5 s, Wu & Yuan 4–9 s of compilation on 2 cores) goes on compiling
    # beside the first chunks, whose outputs wait for it on the outputs' thread
    made = [result(ahead[0]), ahead[1]] if pipelined else [result(f) for f in ahead]
    if pipelined:
        steps, outputs = made
        return lambda bar: run_pipelined(
            carry, lambda cr: steps(model, loads, _strong(cr), dt),
            # strongly typed as the program was compiled (a step's iteration count comes out
            # weak): else the call compiles it again (M4 134: 7.5 s of a first run)
            lambda head, carries: outputs.result()(model, loads, _strong(head),
                                                   _strong(carries)),
            c, n_blocks, save_every, bar, began)
    if headed:
        first = None

    def chunk(carry, n):
        assert n == c, (n, c)          # one chunk length: the one compiled
        return made[0](model, loads, _strong(carry), dt)

    return lambda bar: run_chunked(lambda: (carry, first), chunk, n_blocks, save_every, bar,
                                   time_axis=0, began=began, c=c)
