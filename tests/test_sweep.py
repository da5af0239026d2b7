"""Sweeps in chunks (:func:`mfm.sweep`): in this process and on a Dask LocalCluster of two worker
processes, against one in-process ``simulate_batch`` over the same cases (the independent
reference: one vmapped call, no chunks, no pickling, no cluster); a failed chunk marked and rerun
alone; bad arguments.

Cost: two compilations of RM3 here (the reference's 4-case shape, the chunks' 2-case shape; the
other tests reuse them or compile nothing) and a cluster of two workers (its start, one cheap-XLA
compilation per worker, in parallel): 56 s of wall time on the 2 shared cores at load ~5, 116–233 s
at load 8–12 (`pytest -n 0 tests/test_sweep.py --durations=10`, 2026-11-23). The
M4 134 power matrix through a sweep is measured by benchmarks/power_matrix.py.
"""
import os
import sys
import warnings

import numpy as np
import pytest
import xarray as xr

import hydro
import mfm
from conftest import CONFIGS

sweep_mod = sys.modules["mfm.studies.sweep"]          # mfm.sweep is the function

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

PERIODS = (7.0, 8.0, 9.0, 10.0)
# the fast path; 60 steps at 0.1 s (dt = 1 s goes non-finite at t = 41 s in this many steps)
KW = dict(n_steps=60, integrator="verlet", radiation="state_space_exact")
# the same cases one at a time, in one call or in chunks, make the same operations: they differ by
# nothing or by the round-off of XLA's vectorised loops (measured 0 to 2e-15 relative), 1e-12 of
# the scale; a vmapped loop differs by what round-off moves in these runs (round_off_floor)
RTOL = 1e-12


@pytest.fixture(scope="module")
def rm3():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mfm.load(CONFIGS / "rm3.toml")


@pytest.fixture(scope="module")
def seas():
    return [hydro.Regular(height=h, period=T) for h in (1.0, 2.0) for T in PERIODS[:2]]


@pytest.fixture(scope="module")
def reference(rm3, seas):
    return mfm.simulate_batch(rm3, seas, dt=0.1, **KW)


@pytest.fixture(scope="module")
def round_off_floor(rm3, seas, reference):
    """What round-off alone moves in these runs: the reference's cases with every excitation value
    changed by 4 units in the last place (× (1 + 2⁻⁵⁰)), each variable's largest change. RM3 has
    no surge restoring and its first step meets an unramped wave: a change of 1e-15 in the
    forcing moves the spar's pitch by 3e-8 of itself after one RK4 step, and the cases' q by
    ~1e-9 m over these 60 steps (measured 2026-11-26; the same whatever the change's size from
    1e-15 to 1e-9, the trajectory's own sensitivity). Code that differs only in round-off (a
    vmapped loop against one case at a time, operands shared or stacked) differs by this much,
    not by ε: that is the tolerance of such a comparison, measured here on the machine that runs
    it."""
    import dataclasses

    def nudged(i, loads):
        water = loads[0]
        return (dataclasses.replace(water, exc_values=water.exc_values * (1.0 + 2.0**-50)),) \
            + tuple(loads[1:])

    other = mfm.simulate_batch(rm3, seas, dt=0.1, vary_loads=nudged, **KW)
    return {name: float(np.abs(np.asarray(other[name]) - np.asarray(reference[name])).max())
            for name in reference.data_vars}


def assert_same(ds, ref, floor=None):
    """Equal to RTOL of each variable's scale (round-off of the same operations in another order),
    or, given ``floor`` (:func:`round_off_floor`), to 10 × what round-off moves in these runs."""
    for name in ref.data_vars:
        a, b = np.asarray(ds[name]), np.asarray(ref[name])
        assert a.shape == b.shape, name
        scale = max(float(np.abs(b).max()), 1e-300)
        tol = RTOL * scale if floor is None else max(RTOL * scale, 10.0 * floor[name])
        assert float(np.abs(a - b).max()) <= tol, (name, float(np.abs(a - b).max()), tol)
    for name in ("sea_height", "sea_period", "sea_heading"):
        np.testing.assert_array_equal(ds[name], ref[name])
        assert ds[name].attrs == ref[name].attrs


def test_chunks_in_process_equal_one_batch_and_keep_its_labels(rm3, seas, reference):
    ds = mfm.sweep(rm3, seas, dt=0.1, chunk_size=3, progress=False, **KW)   # chunks of 2
    assert_same(ds, reference)
    assert list(ds.sweep_chunk.values) == [0, 0, 1, 1] and not ds.failed.any()
    assert ds.attrs["sweep_chunk_size"] == 2 and ds.attrs["sweep_scheduler"] == "in-process"
    # simulate_batch's provenance and units, with the sweep's settings beside them
    for k in ("config_sha256", "database_sha256", "integrator", "radiation", "n_steps"):
        assert ds.attrs[k] == reference.attrs[k], k
    assert ds.q.attrs == reference.q.attrs and ds.sweep_failed_chunks == "none"
    # a power matrix: (height, period) from the case labels
    P = ds.pto_power.sum("pto").mean("step").set_index(case=["sea_height", "sea_period"])
    assert P.unstack("case").shape == (2, 2)


def test_threads_and_lanes_give_the_same_cases(rm3, seas, reference, round_off_floor):
    """simulate_batch runs its cases in parts from host threads (one per core by default) and in
    groups of ``lanes`` vmapped together: every split must give the reference's numbers (threads:
    the same operations, RTOL; lanes: a vmapped loop, whose operations differ from one case's by
    round-off, which these runs amplify: :func:`round_off_floor`), a padded last part included,
    once compiled per shape."""
    trace = sys.modules["mfm.timedomain.rollout"].TRACES
    before = trace["rollout"]
    # 3 cases in 2 threads: parts of 2, the last padded by repeating its case, dropped after;
    # lanes=2 is a shape nothing else here compiles: the two threads share one compilation
    three = mfm.simulate_batch(rm3, seas[:3], dt=0.1, threads=2, lanes=2, **KW)
    assert trace["rollout"] == before + 1
    assert three.sizes["case"] == 3 and three.attrs["lanes"] == 2
    assert_same(three, reference.isel(case=slice(0, 3)), round_off_floor)
    assert_same(mfm.simulate_batch(rm3, seas, dt=0.1, threads=2, lanes=1, **KW), reference)
    assert_same(mfm.simulate_batch(rm3, seas, dt=0.1, threads=1, lanes=4, **KW), reference,
                round_off_floor)
    for bad in (0, 1.5, True):
        for name in ("threads", "lanes"):
            with pytest.raises(ValueError, match=name):
                mfm.simulate_batch(rm3, seas, dt=0.1, **{name: bad}, **KW)


def test_plan_pads_the_last_chunk_to_one_shape():
    plan = sweep_mod.plan_chunks(120, 16)        # 8 chunks of 15: no padding
    assert [c.cases.size for c in plan] == [15] * 8 and all(c.n_real == 15 for c in plan)
    plan = sweep_mod.plan_chunks(5, 2)
    assert [list(c.cases) for c in plan] == [[0, 1], [2, 3], [4, 4]]
    assert [c.n_real for c in plan] == [2, 2, 1]


def test_failed_chunk_is_marked_and_resumed_alone(rm3, seas, reference, monkeypatch, tmp_path):
    dts = np.array([0.1, 0.1, 1.0, 0.1])        # case 2 unstable: chunk 1 fails
    ds = mfm.sweep(rm3, seas, dt=dts, chunk_size=2, progress=False, **KW)
    assert list(ds.failed.values) == [False, False, True, True]
    assert np.isnan(ds.q.sel(case=[2, 3])).all() and np.isfinite(ds.q.sel(case=[0, 1])).all()
    assert "chunk 1 (cases 2–3): SimulationError" in ds.sweep_failed_chunks
    assert "went non-finite" in ds.sweep_failed_chunks
    assert list(ds.sea_period.values) == list(reference.sea_period.values)   # labels kept
    ds.to_netcdf(tmp_path / "sweep.nc")     # a failed sweep still saves, to resume later

    ran = []
    real = sweep_mod._run_chunk
    monkeypatch.setattr(sweep_mod, "_run_chunk",
                        lambda *a, **k: ran.append(list(a[2])) or real(*a, **k))
    fixed = mfm.sweep(rm3, seas, dt=0.1, chunk_size=2, resume=ds, progress=False, **KW)
    assert ran == [[2, 3]] and fixed.sweep_chunks_run == "1"
    assert_same(fixed, reference)
    assert not fixed.failed.any() and fixed.sweep_failed_chunks == "none"
    # the kept cases are the first run's numbers, untouched
    np.testing.assert_array_equal(fixed.q.sel(case=[0, 1]), ds.q.sel(case=[0, 1]))

    with pytest.raises(ValueError, match="resume: its case label"):
        mfm.sweep(rm3, seas[::-1], dt=0.1, chunk_size=2, resume=ds, progress=False, **KW)
    with pytest.raises(ValueError, match="resume: .*chunks of"):
        mfm.sweep(rm3, seas, dt=0.1, chunk_size=1, resume=ds, progress=False, **KW)
    with pytest.raises(mfm.SweepError, match="every chunk"):
        mfm.sweep(rm3, seas[:2], dt=1.0, chunk_size=2, progress=False, **KW)


def test_parameters_are_labelled_and_vary_loads_gets_the_sweep_case(rm3, seas, reference):
    seen = []
    ds = mfm.sweep(rm3, seas, dt=0.1, chunk_size=2, progress=False, **KW,
                   parameters={"drag_scale": ([1.0, 1.0, 1.0, 1.0], "1")},
                   vary_loads=lambda i, loads: seen.append(i) or loads)
    assert sorted(set(seen)) == [0, 1, 2, 3]     # the sweep's case indices, not the chunk's
    assert list(ds.drag_scale.values) == [1.0] * 4 and ds.drag_scale.units == "1"
    assert_same(ds, reference)


def test_models_of_a_parameter_sweep_reach_their_cases(rm3, monkeypatch):
    import equinox as eqx

    models = [eqx.tree_at(lambda m: m.damping, rm3, rm3.damping * s) for s in (1.0, 2.0, 3.0)]
    got = []

    def spy(m, seas, **kw):     # what each chunk's simulate_batch receives (nothing compiled)
        got.append(([float(x.damping.sum()) for x in m], kw["dt"].tolist()))
        raise RuntimeError("spy")

    monkeypatch.setattr(sweep_mod, "simulate_batch", spy)
    with pytest.raises(mfm.SweepError, match="every chunk.*spy"):
        mfm.sweep(models, None, dt=[0.1, 0.2, 0.3], n_steps=2, chunk_size=2, progress=False)
    c = float(rm3.damping.sum())
    assert got == [([c, 2 * c], [0.1, 0.2]), ([3 * c, 3 * c], [0.3, 0.3])]   # last one padded


def test_bad_arguments_name_the_argument_and_what_is_accepted(rm3, seas):
    for kw, match in [(dict(chunk_size=0), "chunk_size: 0; give a whole number"),
                      (dict(chunk_size=2.5), "chunk_size: 2.5"),
                      (dict(client=3), "client: 3; give None"),
                      (dict(n_workers=2), "n_workers: 2 applies to client='local'"),
                      (dict(parameters={"c": [1.0]}), r"parameters\['c'\]: \[1.0\]; give one "
                                                      "number per case \\(4 cases\\)"),
                      (dict(parameters={"q": [1.0] * 4}), "parameters: 'q' is a name of the "
                                                            "result already"),
                      (dict(resume=xr.Dataset()), "resume: Dataset; give the dataset"),
                      (dict(progress="yes"), "progress: 'yes'"),
                      (dict(dt=[0.1, 0.1]), "one length or 1"),
                      (dict(vary_loads="drag"), "vary_loads: 'drag'")]:
        args = dict(dt=0.1, **KW, progress=False)
        args.update(kw)
        with pytest.raises(ValueError, match=match):
            mfm.sweep(rm3, seas, **args)
    with pytest.raises(TypeError, match=r"unknown options \['n_step'\]; accepted"):
        mfm.sweep(rm3, seas, dt=0.1, n_steps=3, n_step=3)


def test_missing_dask_names_the_extra(rm3, seas, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)     # import distributed -> ImportError
    with pytest.raises(ImportError, match=r"dask.distributed.*pip install 'mfm\[sweep\]'"):
        mfm.sweep(rm3, seas, dt=0.1, client="local", progress=False, **KW)


def _traces():
    return dict(sys.modules["mfm.timedomain.rollout"].TRACES)


def test_two_worker_cluster_equals_one_batch_and_compiles_once_per_worker(rm3, seas, reference):
    distributed = pytest.importorskip("distributed")
    # XLA's cheapest optimisation in the workers: compiling is most of these short runs (as in
    # the README and notebook smoke runs); the numbers still agree to 1e-12 with the reference
    flags = (os.environ.get("XLA_FLAGS", "") + " --xla_backend_optimization_level=0"
             " --xla_llvm_disable_expensive_passes=true").strip()
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None,
                                  env={"XLA_FLAGS": flags, "OPENBLAS_NUM_THREADS": "1"}
                                  ) as cluster, \
            distributed.Client(cluster) as client:
        # the same call given a scheduler address: 3 chunks on 2 workers
        ds = mfm.sweep(rm3, seas + seas[:1], dt=0.1, chunk_size=2,
                       client=cluster.scheduler_address, progress=False, **KW)
        assert_same(ds.isel(case=slice(0, 4)), reference)
        assert_same(ds.isel(case=[4]), reference.isel(case=[0]))
        assert ds.sweep_workers == 2 and ds.sweep_scheduler == cluster.scheduler_address
        traces = client.run(_traces)
        # every worker ran chunks, each compiled the rollout once
        assert len(traces) == 2 and all(t.get("rollout") == 1 for t in traces.values()), traces
        # a failed chunk on the cluster, and its resume through a Client: no new compilation
        bad = mfm.sweep(rm3, seas, dt=[0.1, 0.1, 0.1, 1.0], chunk_size=2, client=client,
                        progress=False, **KW)
        assert list(bad.failed.values) == [False, False, True, True]
        assert "chunk 1 (cases 2–3): SimulationError" in bad.sweep_failed_chunks
        fixed = mfm.sweep(rm3, seas, dt=0.1, chunk_size=2, client=client, resume=bad,
                          progress=False, **KW)
        assert_same(fixed, reference)
        assert client.run(_traces) == traces
