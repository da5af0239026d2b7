"""Issue 54 items 15, 16 and 18: faults of a run's process and of a sweep's cluster.

- 15: a Ctrl-C while a first run compiles ends the process at once (its compilations ran on pool
  threads that Python joins at exit: the process ended when they had, 9 to 35 s later).

- 16: a sweep on a cluster whose workers die (every one holding the model) finishes on the
  restarted workers with the clean run's bits (the model was scattered data, lost with them:
  every chunk not yet run failed); a LocalCluster that does not start is blamed on a missing
  ``__main__`` guard only where the script lacks one.
- 18: ``progress=True`` (the command line's path) gives the bits of the run without a bar, every
  output variable; a warm cache copied to another folder is used there (nothing compiled anew).
"""
from __future__ import annotations

import io
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
import warnings

import numpy as np
import pytest

from conftest import CONFIGS, ROOT

import hydro
import mfm

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


def test_a_progress_bar_gives_the_bits_of_the_run_without_one():
    """The bar runs in chunks whose outputs are made in each chunk after its steps, in groups of
    DEFERRED_RECORD_WIDTH samples; a chunk of 10 blocks (RM3, 200 samples: chunk_plan's 20
    updates) put each sample elsewhere in its group than the run in one program did, and XLA's
    vectorised outputs differ in the last bits with the place (q̈, joint and hydro forces up to
    2e-7 relative, item 18). Reference: the same call without a bar; tolerance: none."""
    model = mfm.load(CONFIGS / "rm3.toml")
    sea = hydro.Regular(height=2.5, period=8.0)
    kw = dict(duration=20.0, dt=0.1, ramp=10.0)
    plain = mfm.simulate(model, sea, **kw)
    barred = mfm.simulate(model, sea, progress={"file": io.StringIO()}, **kw)
    assert set(plain.data_vars) == set(barred.data_vars)
    differ = [v for v in plain.data_vars
              if not np.array_equal(plain[v].values, barred[v].values, equal_nan=True)]
    assert not differ, differ


# a first run that counts what it traced and saved (mfm.runner.programs.COUNTS) and jax's
# persistent cache's misses (its monitoring events)
_WARM_RUN = """
import json, jax, hydro, mfm
from mfm.runner import programs
misses = []
jax.monitoring.register_event_listener(
    lambda name, **kw: misses.append(name) if name.endswith("/cache_misses") else None)
m = mfm.load(%r)
mfm.simulate(m, hydro.Regular(height=1.0, period=8.0), duration=10.0, dt=0.1, ramp=5.0)
print(json.dumps(dict(programs.COUNTS, misses=len(misses))))
"""


# Python's own SIGINT handler set first, as an interpreter started with SIGINT not ignored sets
# it: a child of a process that ignores SIGINT (a test worker after some suites' clusters)
# inherits the ignoring, and Python then installs no handler: the interrupt never arrived (the
# run went to its end in the full suite)
_INTERRUPTED_RUN = """
import signal
signal.signal(signal.SIGINT, signal.default_int_handler)
import sys, jax, hydro, mfm
m = mfm.load(%r)
mfm.simulate(m, hydro.Regular(height=2.5, period=8.0), duration=200.0, dt=0.1, ramp=40.0,
             progress={"delay": 0, "mininterval": 0})
print("finished")
"""

# seconds from the interrupt to the end of the process: the interpreter's own exit (a few tenths
# of a second) with room for a loaded machine; before the fix RM3's compilations held it 9 s
# (XLA's default level) and 4-6 s at the tests' fast level
CTRL_C_SECONDS = 2.5


def test_a_ctrl_c_while_a_first_run_compiles_ends_the_process_at_once(tmp_path):
    """Item 15. Empty caches (the compilation, program and fit caches in tmp_path); SIGINT once the
    bar says "compiling" (the run's programs and the checks' linearisation then compile on other
    threads); the process ends within CTRL_C_SECONDS with Python's KeyboardInterrupt status and
    message, and no thread's traceback or abort."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("JAX_COMPILATION_CACHE")}
    env.update(MFM_COMPILATION_CACHE=str(tmp_path / "jax"), MFM_FIT_CACHE=str(tmp_path / "fits"),
               PYTHONPATH=str(ROOT), PYTHONUNBUFFERED="1")
    child = subprocess.Popen([sys.executable, "-c", _INTERRUPTED_RUN % str(CONFIGS / "rm3.toml")],
                             env=env, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    seen = b""
    try:
        while b"compiling" not in seen:
            more = child.stderr.read1(4096)
            assert more, (child.wait(), seen.decode(errors="replace")[-3000:])
            seen += more
        time.sleep(0.5)          # the threads under way: tracing done, XLA compiling
        child.send_signal(signal.SIGINT)
        sent = time.perf_counter()
        out, err = child.communicate(timeout=120)
        took = time.perf_counter() - sent
    finally:
        if child.poll() is None:
            child.kill()
    err = (seen + err).decode(errors="replace")
    assert child.returncode == -signal.SIGINT, (child.returncode, err[-3000:])
    assert "KeyboardInterrupt" in err and b"finished" not in out
    for bad in ("Exception in thread", "terminate called", "Fatal Python error", "Segmentation"):
        assert bad not in err, err[-3000:]
    print(f"ended {took:.2f} s after the interrupt")
    assert took < CTRL_C_SECONDS, f"the process ended {took:.1f} s after the interrupt"


# a Ctrl-C raised while the main thread runs a gc callback (as jax's _xla_gc_callback, where the
# full suite's lost interrupt was raised): the interpreter prints it and goes on
_LOST_INTERRUPT = """
import gc, os, signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)
import hydro, mfm
from mfm.runner.threads import keeping_interrupts

armed = []

def interrupt_inside_gc(phase, info):
    # armed with a count: the interrupt at that collection (simulate's at its 5th, well inside
    # its body: not one that its arguments' allocations might start)
    if armed and phase == "start":
        armed[0] -= 1
        if armed[0]:
            return
        armed.pop()
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):      # bytecode, where Python runs the handler
            pass

gc.callbacks.append(interrupt_inside_gc)

def work():
    armed.append(1)
    gc.collect()
    return "went on"

def outcome(call):
    try:
        call()
        return "went on"
    except KeyboardInterrupt:
        return "raised"

def kept():
    with keeping_interrupts():
        return work()

print("plain", outcome(work))
print("kept", outcome(kept))
m = mfm.load(%r)
sea = hydro.Regular(height=1.0, period=8.0)
armed.append(5)
print("simulate", outcome(lambda: mfm.simulate(m, sea, duration=20.0, dt=0.1)))
print("handler", signal.getsignal(signal.SIGINT) is signal.default_int_handler)
"""


def test_a_ctrl_c_that_python_prints_and_forgets_is_raised_again(tmp_path):
    """Item 15, the full suite's failure of the test above (1 in 12 interrupts of a compiling
    run): Python raised the Ctrl-C inside jax's gc callback, printed it and went on, and the run
    finished. The interrupt here is raised inside a gc callback on purpose: a plain function
    goes on (the loss is real), a block under keeping_interrupts and mfm.simulate raise it, and
    the process's SIGINT handler is given back."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), MFM_FIT_CACHE=str(tmp_path / "fits"))
    out = subprocess.run([sys.executable, "-c", _LOST_INTERRUPT % str(CONFIGS / "sphere.toml")],
                         env=env, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    said = dict(line.split(" ", 1) for line in out.stdout.splitlines())
    assert said == {"plain": "went on", "kept": "raised", "simulate": "raised",
                    "handler": "True"}, (said, out.stderr[-3000:])
    # the first two in the main thread (an explicit gc.collect()); simulate's collection may
    # run on a compile thread, where the interrupt is then raised in the main thread's own code
    assert out.stderr.count("Exception ignored in") >= 2, out.stderr[-3000:]


def _files(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


def test_a_warm_cache_copied_to_another_folder_is_used_there(tmp_path):
    """Item 18: the traced programs' key held the cache's folder (mfm.runner.xla.COMPILATION_CACHE
    among mfm's settings), and jax's compilation keys held it too (its default GPU autotuning
    folder inside the cache's, in every compilation's options): a warm cache copied elsewhere
    traced and compiled every program again. Counted, not timed: the second process in the copy
    saves no program, misses nothing in jax's cache and adds no file."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("JAX_COMPILATION_CACHE")}
    # every compilation kept, however short (else one under the threshold in the first process
    # is a miss in the second whatever the key: the machine's load decides)
    env.update(MFM_FIT_CACHE=str(tmp_path / "fits"), PYTHONPATH=str(ROOT),
               JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0",
               JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES="0")
    code = _WARM_RUN % str(CONFIGS / "sphere.toml")

    def run(folder):
        out = subprocess.run([sys.executable, "-c", code], env=dict(env, MFM_COMPILATION_CACHE=str(
            folder)), capture_output=True, text=True, timeout=600, cwd=ROOT)
        assert out.returncode == 0, out.stderr[-3000:]
        return json.loads(out.stdout.strip().splitlines()[-1])

    first = run(tmp_path / "a")
    assert first["saved"] > 0 and first["misses"] > 0, first       # it filled the cache
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    before = _files(tmp_path / "b")
    second = run(tmp_path / "b")
    assert second["saved"] == 0 and second["loaded"] == first["saved"], (first, second)
    assert second["misses"] == 0, second
    assert _files(tmp_path / "b") == before


def _chunks_under_way(dask_scheduler):
    """The keys of the sweep's chunks the scheduler has sent to a worker and not had back."""
    return [str(ts.key) for ts in dask_scheduler.tasks.values()
            if ts.state == "processing" and "-chunk" in str(ts.key)]


# the sweep's fast path of tests/test_sweep.py: 60 steps at 0.1 s
SWEEP_KW = dict(n_steps=60, integrator="verlet", radiation="state_space_exact", progress=False)


def test_a_sweep_whose_workers_are_killed_finishes_with_the_clean_bits(tmp_path):
    """Item 16. Two workers; when the third chunk's case starts (a marker file), both workers are
    killed (SIGKILL: every copy of the model gone) and their nannies start new ones. The sweep
    finishes every chunk and equals the same sweep run in this process, bit for bit (chunk_size
    1: each chunk one case, one thread, the same program on both sides; the workers get this
    process's XLA flags). Then a chunk whose worker is killed under it, the scheduler allowed no
    retry, is reported by name, and a resume= of that sweep gives the clean bits. Cost: 25 s at
    load 2, 50-60 s at load 6-7 on the 2 shared cores (half of it this process's clean sweep: the
    load, the fit and the compilation of RM3; the cluster's part ~22 s, each worker compiling the
    chunk before and after the kill)."""
    distributed = pytest.importorskip("distributed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rm3 = mfm.load(CONFIGS / "rm3.toml")
    seas = [hydro.Regular(height=h, period=T) for h in (1.0, 2.0) for T in (7.0, 8.0)]
    marker = str(tmp_path / "reached")

    def same(i, loads):
        return loads

    def stall_once(i, loads):
        """The third case waits to be killed, the first time it runs (a nested function:
        cloudpickle sends it by value)."""
        if i == 2:
            try:
                open(marker, "x").close()
            except FileExistsError:
                return loads
            time.sleep(120)
        return loads

    clean = mfm.sweep(rm3, seas, dt=0.1, chunk_size=1, vary_loads=same, **SWEEP_KW)
    env = {"XLA_FLAGS": os.environ.get("XLA_FLAGS", ""), "OPENBLAS_NUM_THREADS": "1"}
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, env=env) as cluster, \
            distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        killed = []

        def kill_when_reached():
            deadline = time.monotonic() + 300
            while not os.path.exists(marker) and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(0.3)
            for pid in pids.values():
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)

        threading.Thread(target=kill_when_reached, daemon=True).start()
        ds = mfm.sweep(rm3, seas, dt=0.1, chunk_size=1, client=client, vary_loads=stall_once,
                       **SWEEP_KW)
        assert sorted(killed) == sorted(pids.values())
        assert set(client.run(os.getpid).values()).isdisjoint(killed)    # new workers ran it
        assert not ds.failed.values.any(), ds.sweep_failed_chunks
        for name in clean.data_vars:
            np.testing.assert_array_equal(ds[name].values, clean[name].values, err_msg=name)

        # a chunk whose worker dies under it, once the scheduler gives up on it (allowed-failures,
        # 0 here to keep the test short), is named for resume=, the others kept; the resume runs
        # it alone and gives the clean bits. Its worker is killed once it is the only chunk under
        # way (the scheduler counts a death against every task it had sent to that worker)
        cluster.scheduler.allowed_failures = 0
        stalled = tmp_path / "stalled"

        def stall(i, loads):
            if i == 1:
                stalled.write_text(str(os.getpid()))
                time.sleep(120)
            return loads

        def kill_when_alone():
            deadline = time.monotonic() + 300
            while time.monotonic() < deadline:
                busy = client.run_on_scheduler(_chunks_under_way)
                if stalled.exists() and len(busy) == 1 and "-chunk1-" in busy[0]:
                    os.kill(int(stalled.read_text()), signal.SIGKILL)
                    return
                time.sleep(0.2)

        threading.Thread(target=kill_when_alone, daemon=True).start()
        # two of the cases (chunk_size 1: each the same program and bits as in the clean sweep)
        dies = mfm.sweep(rm3, seas[2:], dt=0.1, chunk_size=1, client=client, vary_loads=stall,
                         **SWEEP_KW)
        assert list(dies.failed.values) == [False, True], dies.sweep_failed_chunks
        assert "chunk 1 (cases 1–1): KilledWorker" in dies.sweep_failed_chunks
        fixed = mfm.sweep(rm3, seas[2:], dt=0.1, chunk_size=1, client=client, vary_loads=same,
                          resume=dies, **SWEEP_KW)
    assert fixed.sweep_chunks_run == "1"
    for name in clean.data_vars:
        if "case" in clean[name].dims:
            np.testing.assert_array_equal(fixed[name].values, clean[name].values[2:],
                                          err_msg=name)


@pytest.mark.parametrize("guarded", [True, False])
def test_a_cluster_that_does_not_start_blames_the_main_guard_only_where_it_lacks(
        tmp_path, monkeypatch, guarded):
    """Item 16: the refusal said "needs its code under `if __name__ == '__main__':`" for any
    RuntimeError of the LocalCluster, to a script that had the guard. Now only where the script
    (sys.modules['__main__'], its file read) has none; else the error and where to look. The
    cluster's start is stood in by a LocalCluster that fails as distributed's does when its
    workers die while starting."""
    distributed = pytest.importorskip("distributed")
    import types

    sweep_mod = sys.modules["mfm.studies.sweep"]
    script = tmp_path / "power_matrix.py"
    body = "import mfm\nmfm.sweep(model, seas, client='local')\n"
    script.write_text("def main():\n    " + body.replace("\n", "\n    ").rstrip() + "\n\n"
                      "if __name__ == '__main__':\n    main()\n" if guarded else body)
    main = types.ModuleType("__main__")
    main.__file__ = str(script)
    monkeypatch.setitem(sys.modules, "__main__", main)

    def dies(*a, **k):
        try:
            raise OSError("Nanny failed to start worker process: the worker was killed")
        except OSError as e:
            raise RuntimeError("Cluster failed to start: Nanny failed to start.") from e

    monkeypatch.setattr(distributed, "LocalCluster", dies)
    with pytest.raises(RuntimeError) as err:
        sweep_mod._open_client("local", 2)
    text = str(err.value)
    assert "Nanny failed to start worker process: the worker was killed" in text
    if guarded:
        assert "put its code under" not in text and "The script is not the cause" in text
    else:
        assert "put its code under `if __name__ == '__main__':`" in text


def test_a_front_doors_warnings_point_at_its_caller():
    """keeping_interrupts is a block inside simulate and simulate_batch, not a wrapper around
    them: as a decorator it put every warning of theirs on its own line in mfm/runner/threads.py
    (an extra frame under the warnings' stacklevel) instead of the user's call."""
    model = mfm.load(CONFIGS / "sphere.toml")
    sea = hydro.Regular(height=0.5, period=4.0)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        mfm.simulate(model, sea, duration=3.0, dt=1.0)
        mfm.simulate_batch(model, [sea], dt=1.0, n_steps=3)
    assert got and {w.filename for w in got} == {__file__}, [(w.filename, w.lineno) for w in got]
