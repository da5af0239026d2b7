"""Sweeps past one machine: many cases of one topology (a power matrix, design parameters × sea
states) split into chunks of :func:`mfm.simulate_batch`, run one after another in this process or
on a Dask distributed cluster, and gathered into one labelled dataset.

Why chunks: one ``simulate_batch`` call over every case holds every case's excitation table
and saved outputs at once (the M4 134 power matrix, 120 cases × 20,000 steps: 3 GB in one call);
chunks bound the memory. Why Dask: it is
the field's library for spreading Python work over processes and machines (a ``LocalCluster`` on
one machine, the same call on any cluster given its scheduler address), with futures per task, so
that one chunk that fails does not lose the others.

Every chunk has the same number of cases (the last one padded by repeating its last case, the
padding dropped after), so a worker compiles one shape once and reuses it for all its chunks; the
model is a task's result (its pickled bytes unpickled on a worker, fetched by the others), kept
there under a hash of those bytes, so later sweeps of the same model on the same cluster (a
resume) do not compile again. Not scattered data: the scheduler makes a task's result again when
the workers holding it die, where scattered data is lost with them (and every chunk not yet run
with it); a chunk whose worker dies is run again by the scheduler.

``level="spectral"`` skips all of that for a model linear over its sea states: the cases are the
linear frequency-domain response of :func:`mfm.runner.spectral.spectral_sweep` (one linearisation, one RAO
solve on the union of the seas' frequencies), in one call.
"""
from __future__ import annotations

import collections
import hashlib
import numbers
import pickle
import time
import traceback
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..errors import SweepError  # noqa: F401  (exported)
from ..runner.spectral import spectral_sweep
from ..results import gather_cases, label_cases, sea_labels
from ..timedomain import integrators as _integrators
from ..runner.batch import simulate_batch
from ..runner.progress import progress_bar, progress_options
from ..timedomain.setup import model_loads
from ..validation import check_model, finite_number

# options passed through to simulate_batch (one value for every case, except dt and ramp)
BATCH_OPTIONS = ("integrator", "radiation", "state_space_options", "memory", "save_every", "t0",
                 "q0", "qd0", "loads", "outputs", "lanes", "threads")

# the models a worker process keeps, by the hash of their pickled bytes: a model unpickled again
# would find its compilations (the HydroSpec is compared by content) but not its HydroSpec's
# kernels and fits, which would be computed again; the first one unpickled is reused instead
_WORKER_MODELS: collections.OrderedDict = collections.OrderedDict()
_WORKER_MODELS_KEPT = 4

# names of simulate_batch's result and the sweep's own: not parameter names
RESERVED = ("case", "step", "coordinate", "coordinate_unit", "pto", "time", "q", "qd", "dt",
            "pto_power", "pto_displacement", "eta", "failed", "sweep_chunk")


@dataclass
class _Chunk:
    index: int
    cases: np.ndarray           # the global case indices it runs (padding included)
    n_real: int                 # how many of them are its own (the rest repeat its last case)


def plan_chunks(n_cases: int, chunk_size: int) -> list[_Chunk]:
    """Split n_cases into ⌈n_cases / chunk_size⌉ chunks of one size
    s = ⌈n_cases / n_chunks⌉ ≤ chunk_size (balanced: 120 cases at chunk_size 16 are 8 chunks of 15, no padding); the last
    chunk is padded to s by repeating its last case."""
    n_chunks = -(-n_cases // chunk_size)
    size = -(-n_cases // n_chunks)
    out = []
    for k in range(n_chunks):
        real = np.arange(k * size, min((k + 1) * size, n_cases))
        pad = np.full(size - real.size, real[-1])
        out.append(_Chunk(k, np.concatenate([real, pad]).astype(int), int(real.size)))
    return out


def _run_chunk(models, token, cases, n_real, seas, dts, ramps, n_steps, options, vary_loads):
    """One chunk, where it runs (this process or a worker): ``simulate_batch`` on its cases, the
    padding dropped, ``case`` relabelled with the global indices. Returns ``("ok", dataset)`` or
    ``("failed", text, exception or None)``: a failure is data, so that the caller can mark it and
    go on."""
    try:
        if token is not None:
            kept = _WORKER_MODELS.get(token)
            if kept is None:
                _WORKER_MODELS[token] = models
                while len(_WORKER_MODELS) > _WORKER_MODELS_KEPT:
                    _WORKER_MODELS.popitem(last=False)
            else:
                models = kept
                _WORKER_MODELS.move_to_end(token)
        m = [models[i] for i in cases] if isinstance(models, list) else models
        vl = None if vary_loads is None else (lambda i, loads: vary_loads(int(cases[i]), loads))
        ds = simulate_batch(m, list(seas), dt=np.asarray(dts), ramp=np.asarray(ramps),
                                      n_steps=n_steps, vary_loads=vl, **options)
        ds = ds.isel(case=slice(0, n_real)).assign_coords(case=np.asarray(cases[:n_real]))
        return ("ok", ds)
    except Exception as e:      # noqa: BLE001 - a chunk's failure is reported, not raised
        # simulate_batch numbers the chunk's cases from 0: say which sweep cases they are
        text = (f"{type(e).__name__}: {e} [chunk case k is sweep case "
                f"{[int(i) for i in cases[:n_real]]}[k]]")
        try:
            pickle.dumps(e)
        except Exception:       # noqa: BLE001
            e = None
        return ("failed", text + "\n" + traceback.format_exc(), e)


def _per_case(value, name, B):
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    if arr.ndim != 1 or arr.size not in (1, B):
        raise ValueError(f"{name}: {value!r} must be one number of seconds or one per case ({B})")
    return np.broadcast_to(arr, (B,)).copy()


def _check_chunk_size(chunk_size):
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, numbers.Integral) \
            or chunk_size < 1:
        raise ValueError(f"chunk_size: {chunk_size!r}; give a whole number ≥ 1 of cases per "
                         "simulate_batch call")
    return int(chunk_size)


def _distributed():
    try:
        import distributed
    except ImportError:
        raise ImportError("mfm.sweep with a client (a cluster) needs dask.distributed, which is "
                          "not installed: pip install 'mfm[sweep]' (or pip install "
                          "'dask[distributed]'); client=None runs the chunks in this process "
                          "without it") from None
    return distributed


def _error_chain(e: BaseException) -> str:
    """The text of ``e`` and of its causes and contexts."""
    parts, seen = [], set()
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        parts.append(f"{type(e).__name__}: {e}")
        e = e.__cause__ or e.__context__
    return " <- ".join(parts)


def _main_guard_missing() -> bool:
    """Whether this process's main script would start workers again when they import it: the
    workers are started by spawning (dask's ``distributed.worker.multiprocessing-method``, spawn
    by default, or forkserver), ``__main__`` is a file (not a notebook, ``-c`` or an interactive
    session, which workers do not import), and that file has no ``__name__ == "__main__"``
    test; or this process is such a worker itself (``__mp_main__``)."""
    import ast
    import multiprocessing
    import sys

    try:
        import dask

        method = dask.config.get("distributed.worker.multiprocessing-method", "spawn")
    except Exception:       # noqa: BLE001 - dask's default
        method = "spawn"
    if method not in ("spawn", "forkserver"):
        return False
    main = sys.modules.get("__main__")
    if multiprocessing.parent_process() is not None and "__mp_main__" in sys.modules:
        return True
    path = getattr(main, "__file__", None)
    if not path:
        return False
    try:
        with open(path, encoding="utf-8") as f:
            tree = ast.parse(f.read())
    except (OSError, SyntaxError, ValueError, UnicodeDecodeError):
        return False            # not readable: no evidence against the script
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            names = [node.left, *node.comparators]
            if any(isinstance(n, ast.Name) and n.id == "__name__" for n in names) and any(
                    isinstance(n, ast.Constant) and n.value == "__main__" for n in names):
                return False
    return True


def _cluster_failed_text(e: RuntimeError) -> str:
    """What a LocalCluster that did not start says: a missing ``__main__`` guard only where the
    error is the one it makes (multiprocessing's "bootstrapping phase") or the script has none
    (:func:`_main_guard_missing`); else the error, and where to look."""
    chain = _error_chain(e)
    head = f"client='local': the LocalCluster's workers did not start ({chain})."
    if "bootstrapping phase" in chain or _main_guard_missing():
        return (f"{head} The workers are new processes that import the main script, and this "
                "one starts a cluster when imported: put its code under "
                "`if __name__ == '__main__':`; or run the chunks here with client=None")
    return (f"{head} The script is not the cause (it has its `if __name__ == '__main__':` "
            "guard, or the workers do not import it): see the workers' errors logged above (a "
            "worker killed for memory, a package they cannot import, no free port); or run the "
            "chunks here with client=None")


def _open_client(client, n_workers):
    """(client, what to close afterwards, a description of the scheduler)."""
    if client is None:
        return None, [], "in-process"
    if isinstance(client, str):
        distributed = _distributed()
        if client == "local":
            try:
                cluster = distributed.LocalCluster(n_workers=n_workers, threads_per_worker=1,
                                                   processes=True, dashboard_address=None)
            except RuntimeError as e:
                raise RuntimeError(_cluster_failed_text(e)) from e
            c = distributed.Client(cluster)
            return c, [c, cluster], f"LocalCluster ({len(cluster.workers)} workers)"
        try:
            c = distributed.Client(client, timeout="30s")
        except (OSError, ValueError, TypeError) as e:
            raise ValueError(f"client: {client!r} could not be reached as a Dask scheduler address "
                             f"({e}); give None (this process), 'local' (a LocalCluster), a "
                             "scheduler address such as 'tcp://10.0.0.1:8786', or a "
                             "distributed.Client") from None
        return c, [c], client
    try:
        import distributed
    except ImportError:             # then it cannot be a Client either
        distributed = None
    if distributed is not None and isinstance(client, distributed.Client):
        return client, [], str(client.scheduler.address)
    raise ValueError(f"client: {client!r}; give None (the chunks in this process), 'local' (a "
                     "distributed.LocalCluster), a scheduler address such as "
                     "'tcp://10.0.0.1:8786', or a distributed.Client")


def sweep(model, seas, *, dt=None, n_steps: int | None = None, chunk_size: int = 16,
          client=None, n_workers: int | None = None, ramp=0.0, parameters: dict | None = None,
          vary_loads=None, resume: xr.Dataset | None = None, progress: bool | dict = True,
          level: str | None = None, **options) -> xr.Dataset:
    """Run many cases of one topology in chunks of :func:`mfm.simulate_batch` and gather them into
    one dataset, the same as one ``simulate_batch`` over every case (to round-off: the vmapped
    width differs) with bounded memory, here or on a Dask cluster.

    model: a :class:`~mfm.mechanics.model.Model`, or one per case (made with ``equinox.tree_at`` from one
        Model: one topology, one hydro spec), as ``simulate_batch`` takes.
    seas: a sea state or one per case (``hydro.waves``; None for still water).
    dt, ramp: s, one number or one per case. n_steps: steps of every case.
    chunk_size: the most cases per ``simulate_batch`` call. The cases are split into ⌈B / chunk_size⌉
        chunks of one size (the last padded by repeating a case, dropped after): one compilation per
        process.
    client: None (default: the chunks one after another in this process; no dask needed),
        ``"local"`` (a ``distributed.LocalCluster`` of ``n_workers`` single-threaded worker
        processes, started and closed by this call), a scheduler address (``"tcp://host:8786"``:
        that cluster) or a ``distributed.Client``.
    parameters: ``{name: values}`` (one value per case, or ``(values, units)``) labelled as
        coordinates on ``case``, e.g. the damping each model of a parameter sweep has.
    vary_loads: ``(case_index, loads) -> loads`` as in ``simulate_batch``, called with the case's
        index in the whole sweep.
    resume: a dataset this function returned with failed chunks: only those chunks run again (the
        other cases are kept as they are) and the result merges both. The arguments must give the
        same cases (number, chunk size, sea labels, parameters, integrator, radiation, steps); dt
        may differ (e.g. smaller for the chunks that went non-finite).
    progress: True (default), False, or a dict of tqdm options: a bar over the chunks.
    level: None (default: the time domain, as ``options`` say) or ``"spectral"``: the linear
        frequency-domain level of the fidelity ladder (:func:`mfm.runner.spectral.spectral_sweep`), for a
        model that is linear over the sea states (:func:`mfm.reduce` measures it): linearised
        once, RAOs solved once on the union of the seas' frequencies, every case's statistics
        ``pto_power_mean`` and ``q_rms`` (case, …) in one call, no time stepping. With ``dt`` and
        ``n_steps`` it also synthesises the time series on the time domain's saved grid
        (t0 + k save_every dt, k = 0 … n_steps/save_every), steady state from t0 (``ramp`` does
        not apply: there is no start-up). It takes one model, the options ``q0``, ``loads``,
        ``radiation`` ("database", default, or "state_space": the time domain's fit),
        ``state_space_options``, ``save_every``, ``t0`` and ``parameters``; the chunks and the
        cluster do not apply.
    options: ``simulate_batch``'s other options (integrator, radiation, state_space_options,
        memory, save_every, t0, q0, qd0, loads, outputs, lanes, threads), the same for every
        case; on a cluster ``threads`` is 1 unless given (the workers share the cores). The fast path
        for long sea states is ``integrator="verlet", radiation="state_space_exact"``.

    Returns ``simulate_batch``'s dataset (case, step, coordinate; sea labels ``sea_hs``,
    ``sea_tp``, ``sea_gamma``, ``sea_heading``, … and the parameters as coordinates on ``case``)
    with ``sweep_chunk`` (case) the chunk each case ran in and ``failed`` (case) True where its
    chunk failed (its data NaN; the attribute ``sweep_failed_chunks`` names each such chunk, its cases
    and its error), and the sweep's settings in the attributes (``sweep_chunk_size``,
    ``sweep_chunks``, ``sweep_scheduler``, ``sweep_workers``, ``sweep_wall_s``). A power matrix:
    ``ds.set_index(case=["sea_hs", "sea_tp"]).unstack("case")``.
    Raises :class:`SweepError` when every chunk failed.
    """
    for m_ in (model if isinstance(model, (list, tuple)) else [model]):
        check_model(m_)
    if level is not None:
        return _spectral_sweep(model, seas, level, dt, n_steps, parameters, options,
                               dict(client=client, n_workers=n_workers, vary_loads=vary_loads,
                                    resume=resume))
    if dt is None or n_steps is None:
        raise ValueError(f"dt, n_steps: {dt!r}, {n_steps!r}; the time domain needs both (the "
                         "time step in s and the number of steps); level='spectral' needs neither")
    bad = sorted(set(options) - set(BATCH_OPTIONS))
    if bad:
        raise TypeError(f"sweep: unknown options {bad}; accepted: {list(BATCH_OPTIONS)} and "
                        "model, seas, dt, n_steps, chunk_size, client, n_workers, ramp, "
                        "parameters, vary_loads, resume, progress")
    chunk_size = _check_chunk_size(chunk_size)
    if n_workers is not None and (isinstance(n_workers, bool) or not isinstance(
            n_workers, numbers.Integral) or n_workers < 1):
        raise ValueError(f"n_workers: {n_workers!r}; give a whole number ≥ 1 of worker processes "
                         "for client='local', or None (one per core)")
    if n_workers is not None and not (isinstance(client, str) and client == "local"):
        raise ValueError(f"n_workers: {n_workers!r} applies to client='local' only (client is "
                         f"{client!r})")
    if vary_loads is not None and not callable(vary_loads):
        raise ValueError(f"vary_loads: {vary_loads!r}; give a function (case_index, loads) -> "
                         "loads")
    progress = progress_options(progress)
    if isinstance(n_steps, bool) or not isinstance(n_steps, numbers.Integral) or n_steps < 1:
        raise ValueError(f"n_steps: {n_steps!r} must be a whole number ≥ 1")

    models = list(model) if isinstance(model, (list, tuple)) else model
    seas_l = list(seas) if isinstance(seas, (list, tuple)) else [seas]
    sizes = {"model": len(models) if isinstance(models, list) else 1, "seas": len(seas_l)}
    try:
        sizes.update(dt=np.atleast_1d(np.asarray(dt, dtype=float)).size,
                     ramp=np.atleast_1d(np.asarray(ramp, dtype=float)).size)
    except (TypeError, ValueError):
        raise ValueError(f"dt, ramp: {dt!r}, {ramp!r}; give numbers of seconds (one, or one per "
                         "case)") from None
    B = max(sizes.values())
    if any(v not in (1, B) for v in sizes.values()):
        raise ValueError(f"sweep: the per-case arguments must have one length or 1; got {sizes}")
    if isinstance(models, list) and len(models) == 1:
        models = models[0]
    seas_l = seas_l * B if len(seas_l) == 1 else seas_l
    dts, ramps = _per_case(dt, "dt", B), _per_case(ramp, "ramp", B)
    params = _parameter_labels(parameters, B)
    chunks = plan_chunks(B, chunk_size)
    todo = [c.index for c in chunks]
    if resume is not None:
        todo = _chunks_to_resume(resume, chunks, B, seas_l, params, n_steps, options)

    m0 = models[0] if isinstance(models, list) else models
    if isinstance(models, list) and (len({id(m_.hydro) for m_ in models}) > 1
                                     or len({m_.coordinates for m_ in models}) > 1):
        raise ValueError("model: the models of a sweep must share one topology and one hydro "
                         "spec (make them from one Model with equinox.tree_at)")
    t_start = time.perf_counter()
    c, to_close, scheduler = _open_client(client, n_workers)
    workers = 1
    try:
        bar = progress_bar(None if progress is None else {"unit": "chunk", **progress},
                                      len(todo), f"{m0.name} sweep of {B}")
        results = {}
        args = dict(n_steps=int(n_steps), options=options, vary_loads=vary_loads)
        if c is None:
            for k in todo:
                ch = chunks[k]
                results[k] = _run_chunk(models, None, ch.cases, ch.n_real,
                                        [seas_l[i] for i in ch.cases], dts[ch.cases],
                                        ramps[ch.cases], **args)
                if bar is not None:
                    bar.update(1)
        else:
            workers = len(c.scheduler_info().get("workers", {})) or 1
            # a worker runs its chunk on one thread (the workers share the cores), unless told
            args["options"] = {"threads": 1, **options}
            results = _run_on_cluster(c, models, chunks, todo, seas_l, dts, ramps, args, bar)
        if bar is not None:
            bar.close()
    finally:
        for obj in to_close:
            obj.close()
    return _gather(results, chunks, resume, B, seas_l, dts, params, options, ramp,
                   dict(sweep_chunk_size=int(chunks[0].cases.size), sweep_chunks=len(chunks),
                        sweep_chunks_run=", ".join(map(str, todo)), sweep_scheduler=scheduler,
                        sweep_workers=int(workers),
                        sweep_wall_s=round(time.perf_counter() - t_start, 3)))


# the options the spectral level takes, and its defaults (the rest are the time stepping's)
SPECTRAL_OPTIONS = {"q0": None, "loads": None, "radiation": "database",
                    "state_space_options": None, "save_every": 1, "t0": 0.0}


def _spectral_sweep(model, seas, level, dt, n_steps, parameters, options, unused):
    """``sweep(..., level="spectral")``: :func:`mfm.runner.spectral.spectral_sweep` over the cases, on the
    time domain's saved grid when dt and n_steps are given, labelled as a sweep."""
    if level != "spectral":
        raise ValueError(f"level: {level!r}; accepted: None (the time domain, as the options "
                         "say) or 'spectral' (the linear frequency-domain level)")
    given = {k: v for k, v in unused.items() if v is not None}
    bad = sorted(set(options) - set(SPECTRAL_OPTIONS)) + sorted(given)
    if bad:
        raise ValueError(f"level='spectral': {bad} do not apply (no time stepping, one call); "
                         f"it takes the options {sorted(SPECTRAL_OPTIONS)}, dt, n_steps, ramp "
                         "(not applied: steady state) and parameters")
    if isinstance(model, (list, tuple)):
        raise ValueError(f"model: {len(model)} models; level='spectral' linearises one model for "
                         "every sea (run one sweep per model, or the time domain)")
    opts = {**SPECTRAL_OPTIONS, **options}
    seas_l = list(seas) if isinstance(seas, (list, tuple)) else [seas]
    B = len(seas_l)
    t = None
    if (dt is None) != (n_steps is None):
        raise ValueError(f"dt, n_steps: {dt!r}, {n_steps!r}; give both (the time series on the "
                         "time domain's grid) or neither (the statistics only)")
    if dt is not None:
        every = opts["save_every"]
        if isinstance(n_steps, bool) or not isinstance(n_steps, numbers.Integral) or n_steps < 1 \
                or isinstance(every, bool) or not isinstance(every, numbers.Integral) \
                or every < 1 or n_steps % every:
            raise ValueError(f"n_steps: {n_steps!r} must be a whole number ≥ 1 and a multiple of "
                             f"save_every={every!r}")
        try:
            dts = np.atleast_1d(np.asarray(dt, dtype=float))
        except (TypeError, ValueError):
            dts = None
        if dts is None or dts.ndim != 1 or dts.size not in (1, B) \
                or not np.all(np.isfinite(dts) & (dts > 0)):
            raise ValueError(f"dt: {dt!r}; give one positive time step in s, or one per case "
                             f"({B})")
        t0 = finite_number(opts["t0"], "t0")
        k = np.arange(int(n_steps) // int(every) + 1)
        t = t0 + np.broadcast_to(dts, (B,))[:, None] * int(every) * k[None]
    params = _parameter_labels(parameters, B)
    start = time.perf_counter()
    ds = spectral_sweep(model, seas_l, t=t, q0=opts["q0"], loads=opts["loads"],
                        radiation=opts["radiation"],
                        state_space_options=opts["state_space_options"])
    ds = label_cases(ds, params)
    attrs = {}
    if t is not None:
        ds = label_cases(ds, {"dt": (np.broadcast_to(dts, (B,)).copy(), {"units": "s"})},
                         as_data=True)
        attrs.update(save_every=int(opts["save_every"]), n_steps=int(n_steps), t0=float(t0))
    ds.attrs.update(**attrs, sweep_scheduler="in-process, one call (spectral level)",
                    sweep_wall_s=round(time.perf_counter() - start, 3))
    return ds


def _run_on_cluster(c, models, chunks, todo, seas_l, dts, ramps, args, bar):
    distributed = _distributed()
    import cloudpickle

    m0 = models[0] if isinstance(models, list) else models
    if m0.hydro is not None:
        # fit the radiation (or whatever the water caches) once here, so that every worker gets
        # the same fit in the model it receives instead of fitting again
        o = args["options"]
        model_loads(m0, seas_l[0], dt=float(dts[0]), duration=args["n_steps"] * dts[0],
                              radiation=o.get("radiation", "state_space"),
                              memory=o.get("memory"),
                              state_space_options=o.get("state_space_options"),
                              integrator=o.get("integrator", "rk4"))
    blob = cloudpickle.dumps(models)
    token = hashlib.sha256(blob).hexdigest()
    # the model as a task's result, not scattered data: the scheduler keeps the task (the
    # pickled bytes) and makes the model again on a live worker when every worker holding it
    # died; scattered data is lost with them, and with it every chunk not yet run ("cluster
    # lost scattered data": issue 54, item 16)
    remote = c.submit(_model_from, blob, token, key=f"mfm-sweep-model-{token}", pure=False)

    futures = {}
    for k in todo:
        ch = chunks[k]
        # a chunk whose worker dies is run again by the scheduler (up to its allowed-failures,
        # then KilledWorker: reported by name below, for resume=)
        f = c.submit(_run_chunk, remote, token, ch.cases, ch.n_real,
                     [seas_l[i] for i in ch.cases], dts[ch.cases], ramps[ch.cases], **args,
                     pure=False, key=f"mfm-sweep-{token[:12]}-chunk{k}-{time.time_ns()}")
        futures[f] = k
    results = {}
    for f in distributed.as_completed(list(futures)):
        k = futures[f]
        try:
            results[k] = f.result()
        except Exception as e:      # noqa: BLE001 - a chunk that killed its workers, a cancel
            results[k] = ("failed", f"{type(e).__name__}: {e} (on the cluster)", None)
        f.release()
        if bar is not None:
            bar.update(1)
    remote.release()
    return results


def _model_from(blob: bytes, token: str):
    """The sweep's model(s) on a worker, from their pickled bytes (the one this worker keeps
    under ``token`` where it has it: :func:`_run_chunk`)."""
    import cloudpickle

    kept = _WORKER_MODELS.get(token)
    return kept if kept is not None else cloudpickle.loads(blob)


def _parameter_labels(parameters, B):
    if parameters is None:
        return {}
    if not isinstance(parameters, dict):
        raise ValueError(f"parameters: {parameters!r}; give a dict {{name: values}} with one value "
                         f"per case ({B}), or {{name: (values, units)}}")
    out = {}
    for name, v in parameters.items():
        units = None
        if isinstance(v, tuple) and len(v) == 2 and isinstance(v[1], str):
            v, units = v
        try:
            arr = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            arr = None
        if not isinstance(name, str) or arr is None or arr.shape != (B,):
            raise ValueError(f"parameters[{name!r}]: {v!r}; give one number per case ({B} cases)")
        if name in RESERVED or name.startswith("sea_"):
            raise ValueError(f"parameters: {name!r} is a name of the result already (its "
                             f"variables {sorted(RESERVED)} and the sea labels sea_*); choose "
                             "another name")
        out[name] = (arr, {"long_name": "sweep parameter", **({"units": units} if units else {})})
    return out


def _chunks_to_resume(resume, chunks, B, seas_l, params, n_steps, options):
    """The chunks of ``resume`` that failed, after checking that it is this sweep."""
    need = ("failed", "sweep_chunk")
    if not isinstance(resume, xr.Dataset) or any(v not in resume for v in need) \
            or "sweep_chunk_size" not in resume.attrs:
        raise ValueError(f"resume: {type(resume).__name__}; give the dataset a previous "
                         "mfm.sweep returned (with its 'failed' and 'sweep_chunk' variables)")
    want = np.concatenate([np.full(c.n_real, c.index) for c in chunks])
    if resume.sizes["case"] != B or not np.array_equal(resume["sweep_chunk"].values, want):
        raise ValueError(f"resume: its {resume.sizes['case']} cases in chunks of "
                         f"{resume.attrs['sweep_chunk_size']} are not this sweep's {B} cases in "
                         f"chunks of {chunks[0].cases.size}: give the same cases and chunk_size")
    labels = dict(sea_labels(seas_l), **params)
    for name, (values, _) in labels.items():
        if name not in resume.coords or not np.allclose(resume[name].values, values,
                                                        rtol=1e-12, atol=0.0, equal_nan=True):
            raise ValueError(f"resume: its case label {name!r} differs from this sweep's: give "
                             "the same cases")
    given = {"integrator": _integrators.get(options.get("integrator", "rk4")).name,
             "radiation": options.get("radiation", "state_space"), "n_steps": int(n_steps)}
    for k, v in given.items():
        if str(resume.attrs.get(k)) != str(v):
            raise ValueError(f"resume: it ran with {k} = {resume.attrs.get(k)!r}, this call asks "
                             f"for {v!r}: give the same settings")
    return sorted({int(k) for k in resume["sweep_chunk"].values[resume["failed"].values]})


def _gather(results, chunks, resume, B, seas_l, dts, params, options, ramp, sweep_attrs):
    """One dataset over every case from the chunks' results (and the kept cases of ``resume``)."""
    ok = {k: r[1] for k, r in results.items() if r[0] == "ok"}
    failed = {k: r for k, r in results.items() if r[0] != "ok"}
    parts = [ok[k] for k in sorted(ok)]
    if resume is not None:
        keep = ~np.isin(resume["sweep_chunk"].values, list(results))
        if keep.any():
            parts.append(resume.isel(case=np.flatnonzero(keep))
                         .drop_vars(["failed", "sweep_chunk"]))
    if not parts:
        first = failed[min(failed)]
        errors = [f"chunk {k}: {failed[k][1]}" for k in sorted(failed)]
        err = SweepError(f"every chunk of the sweep failed; chunk {min(failed)}: "
                         f"{first[1].splitlines()[0]}", errors)
        if first[2] is not None:
            raise err from first[2]
        raise err
    nan_cases = [chunks[k].cases[:chunks[k].n_real] for k in sorted(failed)]
    failed_cases = np.zeros(B, dtype=bool)
    for idx in nan_cases:
        failed_cases[idx] = True
    dt = dts
    if resume is not None:
        rerun = np.isin(resume["sweep_chunk"].values, list(results))
        dt = np.where(rerun, dts, resume["dt"].values)
    chunk_of = np.concatenate([np.full(c.n_real, c.index) for c in chunks])
    report = []
    for k in sorted(failed):
        ch = chunks[k]
        first_line = failed[k][1].splitlines()[0]
        report.append(f"chunk {k} (cases {ch.cases[0]}–{ch.cases[ch.n_real - 1]}): {first_line}")
    if resume is not None:
        sweep_attrs["sweep_resumed_chunks"] = sweep_attrs["sweep_chunks_run"]
    ramps = np.atleast_1d(np.asarray(ramp, dtype=float))
    attrs = dict(seas=repr(seas_l), ramp_s=repr(ramps.tolist()),
                 sweep_failed_chunks="; ".join(report) if report else "none", **sweep_attrs)
    return gather_cases(parts, nan_cases, B, {**sea_labels(seas_l), **params}, dt, chunk_of,
                        failed_cases, attrs)
