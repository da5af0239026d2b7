"""Many runs of one topology in one compiled call (:func:`simulate_batch`): cases in lanes of one
vmapped loop, groups of lanes one after another, parts of the cases on host threads."""
from __future__ import annotations

import dataclasses
import functools
import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from .. import results
from ..errors import SimulationError
from ..frequency.drift import run_mean_drift
from ..loads.assembly import (CaseLoads, as_loads, carried_loads_batch, compile_view,
                              initial_states)
from ..validation import check_model, finite_number, initial_vector, whole_number
from ..timedomain import integrators as _integrators
from .checks import check_sea_read, refuse_convolution, refuse_impossible
from .progress import progress_bar, progress_options, run_chunked
from .threads import background, keeping_interrupts, result
from ..timedomain.record import Recording, map_in_groups, output_names
from ..timedomain.rollout import TRACES, rollout_blocks, rollout_impl, rollout_start
from ..timedomain.setup import declared_stage_offsets, model_loads, stage_offsets


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
    return map_in_groups(g, xs, lanes)


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
    # daemon threads, waited for here: a Ctrl-C ends the process at once, not at the end of the
    # parts' compilation and run (mfm.runner.threads)
    made = [background(lambda k: jax.block_until_ready(call(k)), k, name="mfm-batch")
            for k in range(n)]
    return [result(f) for f in made]


def _join_parts(outs, B):
    """The parts' outputs joined on the case axis, the padding cases dropped (numpy; one part,
    as on a GPU, is taken as it is, not copied: 2,000 samples of 480 M4 134 cases are 0.2 GB)."""
    if len(outs) == 1:
        return jax.tree_util.tree_map(lambda a: np.asarray(a)[:B], outs[0])
    return jax.tree_util.tree_map(lambda *a: np.concatenate([np.asarray(x) for x in a])[:B],
                                  *outs)


def _tables(waves, polar, g):
    """The water's tables (exc (G, n, n_dof), eta (G, n), and a wave drift's (G, n, n_dof)) of the
    cases ``g``, made on the device in one call (:func:`_tables_jit`), from the thread that runs
    the cases: a part's tables are made beside the other parts' work. (numpy's route, case by
    case, was as fast on 2 cores with only the moved dofs' columns, 17.0 against 17.2 s per
    thread for 240 cases × 20,000 steps of M4 134, and slower on 16, 2.3×: its Python loop holds
    the GIL.)"""
    return _tables_jit(jax.tree_util.tree_map(lambda a: jnp.asarray(a[g]), waves), polar)


@jax.jit
def _tables_jit(waves, polar):
    """The water's tables of a part's cases (a :class:`~mfm.loads.water.WaveSum` with a leading
    case axis; ``polar`` the excitation table's polar form, every case's), made on the device:
    (exc (G, n, n_dof), eta (G, n)) and, with a wave drift, its (G, n, n_dof)."""
    return jax.vmap(lambda w: w.tables(polar))(waves)


def _stacked(items):
    """Cases' pytrees of one structure (their loads, or models) stacked leaf by leaf on a leading
    case axis. Leaves of different shapes are refused naming the leaf: with ``vary_loads`` each
    case's loads are made alone, so a load that reads its sea's components at the time step (the
    nonlinear level's hulls, the relative drag's flow, ``[[morison]]``) has as many as its sea."""
    paths = jax.tree_util.tree_flatten_with_path(items[0])[0]
    leaves = [jax.tree_util.tree_leaves(x) for x in items]
    for j, (path, _) in enumerate(paths):
        shapes = sorted({np.shape(lv[j]) for lv in leaves})
        if len(shapes) > 1:
            raise ValueError(
                f"simulate_batch: the cases' {jax.tree_util.keystr(path)} differ in shape "
                f"({shapes}); with vary_loads each case's loads are made alone, so a load that "
                "reads the sea's components at the time step (the nonlinear level's hulls, drag on "
                "the relative flow, [[morison]]) has as many as its sea: give the seas as many "
                "components, leave vary_loads out (the water then pads its cases to one count), "
                "or run the cases with mfm.simulate")
    return jax.tree_util.tree_map(lambda *a: jnp.asarray(np.stack([np.asarray(x) for x in a])),
                                  *items)


def _whole(varying, shared):
    """A case's loads from its own leaves (``varying``, sliced by the loop over cases) and those
    every case shares (``shared``: None where the cases' loads were stacked whole)."""
    return varying if shared is None else eqx.combine(varying, shared)


@functools.partial(jax.jit, static_argnames=("model_axis", "n_steps", "integrator", "save_every",
                                             "record", "lanes"))
def _batch_jit(model, loads, shared, q0, qd0, z0, t0, dt, *, model_axis, n_steps, integrator,
               save_every, record, lanes):
    return _over_cases(lambda m, lds, d: rollout_impl(m, _whole(lds, shared), q0, qd0, z0, t0, d,
                                                       n_steps, integrator, save_every, record),
                       model, model_axis, (loads, dt), lanes)


@functools.partial(jax.jit, static_argnames=("model_axis", "integrator", "record", "lanes"))
def _start_batch_jit(model, loads, shared, q0, qd0, z0, t0, dt, *, model_axis, integrator, record,
                     lanes):
    return _over_cases(lambda m, lds, d: rollout_start(m, _whole(lds, shared), q0, qd0, z0, t0, d,
                                                        integrator, record),
                       model, model_axis, (loads, dt), lanes)


@functools.partial(jax.jit, static_argnames=("model_axis", "n_blocks", "integrator", "save_every",
                                             "record", "lanes"))
def _chunk_batch_jit(model, loads, shared, carry, dt, *, model_axis, n_blocks, integrator,
                     save_every, record, lanes):
    TRACES["rollout_chunk"] += 1
    return _over_cases(lambda m, lds, c, d: rollout_blocks(m, _whole(lds, shared), c, d, n_blocks,
                                                            integrator, save_every, record),
                       model, model_axis, (loads, carry, dt), lanes)


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
    seas: a sea state or a sequence of them (``hydro.waves``; None for still water). Seas of
        different numbers of components share one structure (the shorter padded with
        zero-amplitude components), above linear too: the nonlinear level's hulls, drag on the
        relative flow and the wave drift take each case's own components (docs/nonlinear.md,
        Batches), and ``[[morison]]`` elements.
    dt, ramp: s, a number or one per case. Every case runs ``n_steps`` steps (so a sweep at
        dt = T_p/200 over 100 T_p is one shape: 20,000 steps).
    radiation: "state_space" (default; its arrays have one shape whatever dt), "none", or
        "convolution" (only when every case has the same number of lags, e.g. one dt).
    loads: extra loads for every case (as in :func:`simulate`).
    vary_loads: a function ``(case_index, loads) -> loads`` that changes load parameters per case
        (arrays only, e.g. ``equinox.tree_at`` on the water's ``drag`` for a drag-coefficient sweep,
        or on a wind load's speed): the cases stay one compiled, vmapped call. ``loads`` is the
        case's tuple (its water first, then the model's and the extra loads); the structure must
        not change. Each case's loads are made alone (unpadded): above linear and with
        ``[[morison]]``, seas of as many components.
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
    with keeping_interrupts():
        models = [check_model(m_) for m_ in (model if isinstance(model, (list, tuple)) else [model])]
        from ..radiation import resolve

        radiation, memory, state_space_options = resolve(radiation, memory, state_space_options)
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
        if not whole_number(n_steps) \
                or n_steps % save_every:
            raise ValueError(f"n_steps: {n_steps!r} must be a whole number ≥ 1 and a multiple of "
                             f"save_every={save_every}")
        t0 = finite_number(t0, "t0")
        memory = finite_number(memory, "memory", positive=True, allow_none=True)
        progress = progress_options(progress)
        if lanes is None:
            lanes = default_lanes(B)
        elif not whole_number(lanes):
            raise ValueError(f"lanes: {lanes!r}; give a whole number ≥ 1 of cases to advance "
                             "together in one vmapped loop, or None (1 on a CPU, all on a GPU)")
        lanes = int(lanes)
        if threads is None:
            threads = default_threads()
        elif not whole_number(threads):
            raise ValueError(f"threads: {threads!r}; give a whole number ≥ 1 of host threads, or None "
                             "(one per core on a CPU)")
        threads = min(int(threads), B)
        pick = lambda seq, i: seq[i if len(seq) > 1 else 0]  # noqa: E731
        structure = {m_.coordinates for m_ in models}
        if len(structure) > 1 or len({id(m_.hydro) for m_ in models}) > 1:
            raise ValueError("model: the models of a batch must share one topology and one hydro "
                             "spec (make them from one Model with equinox.tree_at)")
        integ = _integrators.get(integrator)
        outputs = output_names(outputs)
        extra = as_loads(loads)
        check_sea_read(models[0], extra, seas)
        refuse_impossible(models[0], extra + tuple(models[0].loads), int(n_steps), int(save_every),
                          cases=B, every_output=False, names=outputs, what="n_steps")
        m0 = models[0]
        if radiation == "convolution":
            # the shortest dt has the most lags
            refuse_convolution(m0, dt=float(dts.min()), memory=memory,
                               n_offsets=len(stage_offsets(integ)))
        dts_all = np.broadcast_to(dts, (B,))
        if vary_loads is None and len(models) == 1:
            # the cases' loads made together (loads.assembly.carried_loads_batch): what they share
            # once, what differs (the wave tables, what follows dt) with a leading case axis
            cases = carried_loads_batch(m0, [pick(seas, i) for i in range(B)], dts=dts_all,
                                        ramps=np.broadcast_to(ramps, (B,)), n_steps=int(n_steps),
                                        t0=t0, radiation=radiation, memory=memory,
                                        state_space_options=state_space_options,
                                        stage_offsets=stage_offsets(integ) if m0.hydro is not None
                                        else declared_stage_offsets(integ), extra=extra,
                                        mean_drift=run_mean_drift(m0))
            model_view, loads_view = compile_view(m0, cases.loads)
            # the view blanks static fields only: its leaves are the loads' own, in the same order
            mask = jax.tree_util.tree_unflatten(jax.tree_util.tree_structure(loads_view),
                                                jax.tree_util.tree_leaves(cases.batched))
            varying, shared = eqx.partition(loads_view, mask)
            waves = cases.waves
            if waves is not None and not outputs:
                # nothing recorded of the water: the time step reads the moved dofs' excitation alone
                moving = cases.loads[cases.waves_at].moving
                waves = waves if moving is None else dataclasses.replace(
                    waves, columns=tuple(int(k) for k in moving))

            def take(g):
                part = jax.tree_util.tree_map(lambda a: jnp.asarray(np.asarray(a)[g]), varying)
                if waves is None:
                    return part, None
                tables = _tables(waves, cases.polar, g)       # exc, eta (and a drift's)
                return cases.with_tables(tuple(part), *tables), tables[1]

            model_of = lambda g: model_view  # noqa: E731
            model_axis = None
            loads = cases
        else:
            drift_tables: dict = {}            # one per distinct model (the drift of its motions)

            def run_mean_drift_of(m):
                if id(m) not in drift_tables:
                    drift_tables[id(m)] = run_mean_drift(m)
                return drift_tables[id(m)]

            loads = [model_loads(pick(models, i), pick(seas, i), dt=float(pick(dts, i)),
                                 duration=n_steps * float(pick(dts, i)), t0=t0,
                                 ramp=float(pick(ramps, i)), radiation=radiation, memory=memory,
                                 state_space_options=state_space_options, integrator=integ,
                                 extra=extra, mean_drift=run_mean_drift_of(pick(models, i)))
                     for i in range(B)]
            if vary_loads is not None:
                if not callable(vary_loads):
                    raise ValueError(f"vary_loads: {vary_loads!r}; give a function (case_index, loads) "
                                     "-> loads")
                loads = [tuple(vary_loads(i, ld)) for i, ld in enumerate(loads)]
            # what the compiled call is handed (loads.assembly.compile_view: the host-only fields
            # blanked)
            views = [compile_view(pick(models, i), loads[i]) for i in range(B)]
            defs = {jax.tree_util.tree_structure(v[1]) for v in views}
            if len(defs) > 1:
                raise ValueError("simulate_batch: the cases' loads differ in structure (with "
                                 "radiation='convolution' the number of lags follows dt: give every "
                                 "case the same dt and memory, or use radiation='state_space')")
            stack = _stacked
            varying, shared = [v[1] for v in views], None
            take = lambda g: (stack([varying[i] for i in g]), None)  # noqa: E731
            model_axis = 0 if len(models) > 1 else None
            model_of = (lambda g: stack([views[i][0] for i in g])) if model_axis == 0 \
                else (lambda g: views[0][0])
        q0 = jnp.asarray(initial_vector(m0, q0, "q0"))
        qd0 = jnp.asarray(initial_vector(m0, qd0, "qd0"))
        first = loads[0]
        z0 = initial_states(m0, first)

        recording = Recording(outputs=outputs, states=False)     # the batch form: no z per sample
        known = set(results.record_specs(m0, first)[0])
        bad = [n for n in outputs if n not in known]
        if bad:
            raise ValueError(f"outputs: {bad} are not outputs of this model and its loads; accepted: "
                             f"{sorted(known)}")

        # the cases in `threads` parts of one size (the last padded by repeating its last case): one
        # compiled program serves every part, each run from its own host thread
        size = -(-B // threads)
        lanes = min(lanes, size)
        groups = [np.minimum(np.arange(k, k + size), B - 1) for k in range(0, B, size)]
        args, etas = [None] * len(groups), [None] * len(groups)

        def arg(k):
            """Part k's (model, loads, dt), made once, in the thread that runs it (its tables)."""
            if args[k] is None:
                part, etas[k] = take(groups[k])
                args[k] = (model_of(groups[k]), part, jnp.asarray(dts_all[groups[k]]))
            return args[k]

        t0_ = jnp.asarray(t0, jnp.float64)
        bar = progress_bar(progress, int(n_steps), f"{m0.name} × {B}")
        if bar is None:
            out = _join_parts(_in_threads(len(groups), lambda k: _batch_jit(
                *arg(k)[:2], shared, q0, qd0, z0, t0_, arg(k)[2], model_axis=model_axis,
                n_steps=int(n_steps), integrator=integ, save_every=int(save_every), record=recording,
                lanes=lanes)), B)
        else:
            def start():
                res = _in_threads(len(groups), lambda k: _start_batch_jit(
                    *arg(k)[:2], shared, q0, qd0, z0, t0_, arg(k)[2],
                    model_axis=model_axis, integrator=integ, record=recording, lanes=lanes))
                return [r[0] for r in res], _join_parts([r[1] for r in res], B)

            def chunk(carries, c):
                res = _in_threads(len(groups), lambda k: _chunk_batch_jit(
                    *arg(k)[:2], shared, carries[k], arg(k)[2], model_axis=model_axis,
                    n_blocks=c, integrator=integ, save_every=int(save_every), record=recording,
                    lanes=lanes))
                return [r[0] for r in res], _join_parts([r[1] for r in res], B)

            out = run_chunked(start, chunk, int(n_steps) // int(save_every), int(save_every), bar,
                               time_axis=1)
        if isinstance(loads, CaseLoads) and loads.waves is not None:
            # the elevation for the dataset, from the tables the device made
            loads = loads.with_eta(np.concatenate([np.asarray(e) for e in etas])[:B])
        t, q, qd = (np.asarray(a) for a in out[:3])
        for i in range(B):
            if not (np.isfinite(q[i]).all() and np.isfinite(qd[i]).all()):
                k = int(np.argmax(~np.isfinite(q[i]).all(axis=1) | ~np.isfinite(qd[i]).all(axis=1)))
                raise SimulationError(f"simulate_batch: case {i} went non-finite at t = {t[i, k]:.6g} s "
                                      f"(dt = {pick(dts, i):.4g} s); run it alone with mfm.simulate "
                                      "for the diagnosis")
        settings = dict(radiation=radiation, n_steps=int(n_steps), t0=t0, lanes=lanes,
                        ramp_s=repr(ramps.tolist()), seas=repr(seas))
        labels = results.sea_labels(seas) if len(seas) == B else {}
        recorded = {k: np.asarray(v) for k, v in out[6].items()} if outputs else {}
        return results.batch(m0, [pick(models, i) for i in range(B)], loads, integ, t, q, qd, dts,
                             settings, save_every, labels, recorded)
