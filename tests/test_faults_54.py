"""Issue 54 items 15, 16 and 18: faults of a run's process and of a sweep's cluster.

- 15: a Ctrl-C while a first run compiles ends the process at once (its compilations ran on pool
  threads that Python joins at exit: the process ended when they had, 9 to 35 s later).

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
import time

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


_INTERRUPTED_RUN = """
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

