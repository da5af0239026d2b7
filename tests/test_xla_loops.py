"""The time loop compiled as one function (mfm._xla): the option reaches XLA, the rollout's loop
qualifies, and the numbers are those of XLA's kernel-by-kernel runtime."""
import json
import os
import subprocess
import sys

import jax.numpy as jnp
import numpy as np
import pytest

import hydro
import mfm
from mfm import _xla, integrators
from mfm.timedomain.rollout import rollout_jit
from mfm.timedomain.setup import model_loads

from conftest import CONFIGS, ROOT

N_STEPS = 300


def test_the_option_is_added_to_xla_flags_once():
    opt = _xla.OPTION
    assert _xla.with_loop_option("", 5) == f"--xla_backend_extra_options={opt}=5"
    assert (_xla.with_loop_option("--xla_backend_optimization_level=0", 5)
            == f"--xla_backend_optimization_level=0 --xla_backend_extra_options={opt}=5")
    # XLA keeps one map of extra options: the option joins an existing flag, comma-separated
    assert (_xla.with_loop_option("--xla_backend_extra_options=a=1 --x=2", 5)
            == f"--xla_backend_extra_options=a=1,{opt}=5 --x=2")
    mine = f"--xla_backend_extra_options={opt}=1024"
    assert _xla.with_loop_option(mine, 5) == mine           # the user's setting wins


def _rm3_rollout_script(n_steps):
    """The rollout both processes run: RM3 in a regular wave, Verlet with exact radiation."""
    return f"""
import json, jax.numpy as jnp, hydro, mfm
from mfm.timedomain.setup import model_loads
m = mfm.load({str(CONFIGS / 'rm3.toml')!r})
q0 = jnp.zeros(m.n_coordinates)
q, qd = mfm.rollout(m, q0, q0, dt=0.1, n_steps={n_steps}, integrator="verlet",
                    loads=model_loads(m, hydro.Regular(height=2.5, period=8.0), dt=0.1,
                                      duration={n_steps} * 0.1, ramp=10.0,
                                      radiation="state_space_exact", integrator="verlet"),
                    save_every={n_steps})[1:3]
print(json.dumps({{"q": [float(x) for x in q.reshape(-1)], "qd": [float(x) for x in qd.reshape(-1)],
                  "whole": mfm._xla.LOOPS_COMPILED_WHOLE}}))
"""


@pytest.fixture(scope="module")
def rm3():
    m = mfm.load(CONFIGS / "rm3.toml")
    loads = model_loads(m, hydro.Regular(height=2.5, period=8.0), dt=0.1, duration=N_STEPS * 0.1,
                        ramp=10.0, radiation="state_space_exact", integrator="verlet")
    return m, loads


def test_the_rollout_loop_is_compiled_whole(rm3):
    """Guards the speed of the time step: an op the small-loop pass refuses (a scatter, a custom
    call) in a load's time step would silently bring back the kernel-by-kernel loop (2x slower
    for M4 134)."""
    assert _xla.LOOPS_COMPILED_WHOLE, os.environ.get("XLA_FLAGS")
    m, loads = rm3
    q0 = jnp.zeros(m.n_coordinates)
    z0 = jnp.concatenate([ld.initial_state(m) for ld in loads])
    txt = rollout_jit.lower(m, loads, q0, q0, z0, jnp.asarray(0.0), jnp.asarray(0.1),
                             n_steps=N_STEPS, integrator=integrators.get("verlet"),
                             save_every=N_STEPS, record=False).compile().as_text()
    assert "xla_cpu_small_call" in txt


@pytest.mark.parametrize("config,radiation", [("stansby_li", "state_space_exact"),
                                              ("hallak_fwwp", "state_space_exact")])
def test_every_load_keeps_the_loop_whole(config, radiation):
    """The loads of the other systems (wind thrust, body matrices, hydraulic PTO): none brings an
    op the whole-loop compilation refuses (a scatter, a LAPACK call, a library fusion). (Wu & Yuan's
    catenary lines and 18 coordinates qualify too, measured; loading them costs 45 s.)"""
    m = mfm.load(CONFIGS / f"{config}.toml")
    loads = model_loads(m, hydro.Regular(height=1.0, period=8.0), dt=0.05, duration=1.0,
                        ramp=0.5, radiation=radiation, integrator="verlet")
    q0 = jnp.zeros(m.n_coordinates)
    z0 = jnp.concatenate([ld.initial_state(m) for ld in loads])
    txt = rollout_jit.lower(m, loads, q0, q0, z0, jnp.asarray(0.0), jnp.asarray(0.05),
                             n_steps=20, integrator=integrators.get("verlet"), save_every=20,
                             record=False).compile().as_text()
    assert "xla_cpu_small_call" in txt


def test_compiled_whole_gives_the_kernel_by_kernel_numbers(rm3):
    """The same rollout in a process with XLA's default threshold (the loop run kernel by kernel):
    the two emitters evaluate the same HLO, so the states agree to round-off (1e-10 relative,
    after 300 steps of a lightly damped system that amplifies nothing)."""
    env = dict(os.environ, XLA_FLAGS=_xla.with_loop_option(
        os.environ.get("XLA_FLAGS", "").replace(f"{_xla.OPTION}={_xla.LOOP_THRESHOLD}", ""), 1024))
    out = subprocess.run([sys.executable, "-c", _rm3_rollout_script(N_STEPS)], env=env, cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    other = json.loads(out.stdout.strip().splitlines()[-1])
    assert other["whole"] is False
    here = {}
    exec(_rm3_rollout_script(N_STEPS).replace("print(json.dumps(", "here.update(("), {"here": here})
    assert here["whole"] is True
    for k in ("q", "qd"):
        a, b = np.asarray(here[k]), np.asarray(other[k])
        assert np.all(np.isfinite(a)) and np.abs(a).max() > 0
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10 * np.abs(b).max())


_CACHE_SCRIPT = f"""
import json, jax
hits = []
jax.monitoring.register_event_listener(
    lambda name, **kw: hits.append(1) if name == "/jax/compilation_cache/cache_hits" else None)
import mfm
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)   # RM3 compiles fast
here = {{"q": None, "qd": None}}
if RUN:
    exec({_rm3_rollout_script(20)!r}.replace("print(json.dumps(", "here.update(("), {{"here": here}})
print(json.dumps({{"dir": jax.config.jax_compilation_cache_dir, "hits": len(hits),
                  "q": here["q"], "qd": here["qd"]}}))
"""


def _child(env_changes, run=False):
    """A fresh process with these environment changes: its cache folder, and with ``run`` the
    cache hits and states of a short RM3 rollout."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("JAX_COMPILATION_CACHE_DIR", _xla.CACHE_ENV)}
    env.update(env_changes)
    out = subprocess.run([sys.executable, "-c", f"RUN = {run}\n" + _CACHE_SCRIPT], env=env, cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_compiled_programs_are_kept_on_disk_and_loaded_by_a_later_process(tmp_path):
    """mfm turns on jax's persistent compilation cache: a second fresh process loads the
    programs the first compiled (cache hits) and gives the same bits; MFM_COMPILATION_CACHE names
    the folder or turns it off; jax's own JAX_COMPILATION_CACHE_DIR wins over both."""
    folder = tmp_path / "cache"
    first = _child({_xla.CACHE_ENV: str(folder)}, run=True)
    assert first["dir"] == str(folder) and any(folder.iterdir())
    second = _child({_xla.CACHE_ENV: str(folder)}, run=True)
    assert second["hits"] > first["hits"]
    assert second["q"] == first["q"] and second["qd"] == first["qd"]
    assert _child({_xla.CACHE_ENV: "off"})["dir"] is None
    own = tmp_path / "own"
    assert _child({_xla.CACHE_ENV: str(folder), "JAX_COMPILATION_CACHE_DIR": str(own)})["dir"] \
        == str(own)
    # the default folder, under XDG_CACHE_HOME
    assert _child({"XDG_CACHE_HOME": str(tmp_path / "xdg")})["dir"] \
        == str(tmp_path / "xdg" / "mfm" / "jax")
