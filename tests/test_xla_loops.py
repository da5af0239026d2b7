"""The time loop compiled as one function (mfm.runner.xla): the option reaches XLA, the rollout's loop
qualifies, and the numbers are those of XLA's kernel-by-kernel runtime."""
import json
import os
import subprocess
import sys

import jax.numpy as jnp
import numpy as np
import pytest

import hydro
import jax
import mfm
from hydro import fitcache
from mfm import integrators
from mfm import backend as _backend
from mfm.runner import xla as _xla
from mfm.timedomain.rollout import rollout_jit
from mfm.timedomain.setup import model_loads

from conftest import CONFIGS, ROOT

N_STEPS = 300


def test_the_option_is_added_to_xla_flags_once():
    opt = _backend.OPTION
    assert _backend.with_loop_option("", 5) == f"--xla_backend_extra_options={opt}=5"
    assert (_backend.with_loop_option("--xla_backend_optimization_level=0", 5)
            == f"--xla_backend_optimization_level=0 --xla_backend_extra_options={opt}=5")
    # XLA keeps one map of extra options: the option joins an existing flag, comma-separated
    assert (_backend.with_loop_option("--xla_backend_extra_options=a=1 --x=2", 5)
            == f"--xla_backend_extra_options=a=1,{opt}=5 --x=2")
    mine = f"--xla_backend_extra_options={opt}=1024"
    assert _backend.with_loop_option(mine, 5) == mine           # the user's setting wins


def _rm3_rollout_script(n_steps):
    """The rollout both processes run: RM3 in a regular wave, Verlet with exact radiation. Prints
    the states, whether the loop was compiled whole, and the sha256 of every array the rollout is
    handed (the model's and the loads': the excitation table, the radiation fit, ...)."""
    return f"""
import hashlib, json, jax, numpy as np, jax.numpy as jnp, hydro, mfm
from mfm.timedomain.setup import model_loads
m = mfm.load({str(CONFIGS / 'rm3.toml')!r})
q0 = jnp.zeros(m.n_coordinates)
loads = model_loads(m, hydro.Regular(height=2.5, period=8.0), dt=0.1, duration={n_steps} * 0.1,
                    ramp=10.0, radiation="state_space_exact", integrator="verlet")
h = hashlib.sha256()
for x in jax.tree_util.tree_leaves((m, loads)):
    if hasattr(x, "dtype"):
        h.update(np.asarray(x).tobytes())
q, qd = mfm.rollout(m, q0, q0, dt=0.1, n_steps={n_steps}, integrator="verlet", loads=loads,
                    save_every={n_steps})[1:3]
print(json.dumps({{"q": [float(x) for x in q.reshape(-1)], "qd": [float(x) for x in qd.reshape(-1)],
                  "whole": mfm.backend.LOOPS_COMPILED_WHOLE, "inputs": h.hexdigest()}}))
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
    assert _backend.LOOPS_COMPILED_WHOLE, os.environ.get("XLA_FLAGS")
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


def _roundoff_bound(m, loads, n_steps, dt):
    """A first-order bound on how far two programs that evaluate the same HLO with their sums in
    another order (another emitter, vector width or FMA contraction) can end apart after
    ``n_steps``: Σ_k Σ_j |∂y_N/∂τ_j(k)| · γ · S_j, per component of y = (q, q̇) at the end.

    - ∂y_N/∂τ_j(k): the response of the end state to a generalised force on coordinate j during
      step k, by reverse mode through the same rollout (a :class:`CoordinateForceSeries` added to
      its loads). Summing |·| over steps and coordinates bounds every sign pattern of the local
      differences, coherent ones included (a constant weight−buoyancy rounding repeats every step).
    - S_j, what the step rounds, as a generalised force on coordinate j: the sum of the magnitudes
      of the terms that make its load, Σ_b |B_bj|ᵀ (|weight_b| + Σ_loads |F_b| + |M_b Ẋ_b|) +
      |joint load| + Σ_loads |τ_j| (the weight and buoyancy of RM3 are ~1.6e7 N and cancel; the
      net load is ~10x smaller), plus the state update's own rounding u|q|, u|q̇| per step as
      the force that makes that change in one step, |M*| (|q|/dt² + |q̇|/dt). Taken as the largest
      over the run's samples.
    - γ = 2 m u: each program's sum of m terms is within m u Σ|terms| of the exact sum (Higham's
      γ_m), m = 6 n_bodies + n_q + n_states + n_loads + 1 the longest sum of a step (the body rows
      through Bᵀ, the coordinates of the solve, the radiation states, the loads' sum).
    """
    from mfm.loads.assembly import applied_loads
    from mfm.loads.generic import CoordinateForceSeries
    from mfm.mechanics.dynamics import evaluate, gravity_loads, joint_loads
    from mfm.mechanics.kinematics import kinematics
    from mfm.timedomain.rollout import init_memories

    n = m.n_coordinates
    q0 = jnp.zeros(n)
    z = jnp.concatenate([ld.initial_state(m) for ld in loads])
    mem = init_memories(m, loads, 0.0, q0, q0, dt)

    def samples(values):
        f = CoordinateForceSeries(t0=jnp.asarray(0.0), step=jnp.asarray(dt), values=values)
        return mfm.rollout(m, q0, q0, dt=dt, n_steps=n_steps, integrator="verlet",
                           loads=tuple(loads) + (f,), save_every=n_steps // 6)[:3]

    (t, qs, qds), pullback = jax.vjp(samples, jnp.zeros((n_steps + 1, n)))
    # the end state's 2n components, one reverse pass each: J[o, k, j] = ∂y_N[o]/∂τ_j(k)
    eye = jnp.eye(2 * n)
    J = jax.vmap(lambda e: pullback((jnp.zeros_like(t), jnp.zeros_like(qs).at[-1].set(e[:n]),
                                     jnp.zeros_like(qds).at[-1].set(e[n:])))[0])(eye)

    @jax.jit
    @jax.vmap
    def scale(tk, q, qd):
        # the radiation states at rest: the radiation's force is in the loads' |F|
        kin = kinematics(m, q, qd)
        body, tau, mass, _, outs = applied_loads(m, loads, tk, q, qd, z, kin, mem, with_outputs=True)
        ev = evaluate(m, q, qd, tau=tau, body_loads=body, extra_mass=mass, kin=kin)
        inertia = jnp.abs(ev.Xdot) * jnp.concatenate(
            [jnp.repeat(m.mass[:, None], 3, 1), jnp.abs(m.inertia).max(axis=2)], axis=1)
        Fs = jnp.abs(gravity_loads(m)) + inertia + sum(
            jnp.abs(o.body) for o in outs if o.body is not None)
        Mstar = jnp.abs(mfm.mass_matrix(m, q)) + (0.0 if mass is None else jnp.abs(mass))
        return (jnp.einsum("naj,na->j", jnp.abs(kin.B), Fs) + jnp.abs(joint_loads(m, q, qd))
                + sum(jnp.abs(o.tau) for o in outs if o.tau is not None)
                + Mstar @ (jnp.abs(q) / dt**2 + jnp.abs(qd) / dt))

    S = np.asarray(scale(t, qs, qds)).max(axis=0)
    J = np.asarray(J)
    n_terms = 6 * m.n_bodies + n + len(z) + len(loads) + 1
    gamma = 2 * n_terms * np.finfo(float).eps / 2
    return np.einsum("okj,j->o", np.abs(J), S) * gamma


def test_compiled_whole_gives_the_kernel_by_kernel_numbers(rm3, tmp_path, monkeypatch):
    """The same rollout in a process with XLA's default threshold (the loop run kernel by kernel).

    The two processes must first be handed the same inputs, to the last bit (checked: the sha256
    of every array of the model and its loads). They were not always: each fitted the radiation's
    state space itself, a least-squares fit whose answer moves with the order of the BLAS's sums
    (its threads): two such fits put the end states 1.4e-7 apart (q̇ pitch; MFM_FIT_CACHE=off
    without OPENBLAS_NUM_THREADS=1, measured), which is what failed elsewhere at rtol 1e-10 and
    was no difference of the loop's emitters. Here the child reads the fit this process wrote.

    With the same inputs the two emitters evaluate the same HLO and may only sum in another order:
    their end states may differ by at most the round-off bound of :func:`_roundoff_bound`
    (~1e-11 of the states for these 300 steps; on the machine this was written on they were
    equal to the bit)."""
    monkeypatch.setenv("MFM_FIT_CACHE", str(tmp_path))
    fitcache.clear()                    # fitted here now and written where the child reads it
    here = {}
    exec(_rm3_rollout_script(N_STEPS).replace("print(json.dumps(", "here.update(("), {"here": here})
    assert here["whole"] is True
    env = dict(os.environ, XLA_FLAGS=_backend.with_loop_option(
        os.environ.get("XLA_FLAGS", "").replace(f"{_backend.OPTION}={_backend.LOOP_THRESHOLD}", ""), 1024))
    out = subprocess.run([sys.executable, "-c", _rm3_rollout_script(N_STEPS)], env=env, cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    other = json.loads(out.stdout.strip().splitlines()[-1])
    assert other["whole"] is False
    assert other["inputs"] == here["inputs"], "the two processes rolled out different inputs"
    m, loads = rm3
    bound = _roundoff_bound(m, loads, N_STEPS, 0.1)
    a = np.concatenate([np.asarray(here[k]).reshape(2, -1)[-1] for k in ("q", "qd")])
    b = np.concatenate([np.asarray(other[k]).reshape(2, -1)[-1] for k in ("q", "qd")])
    assert np.all(np.isfinite(a)) and np.abs(a).max() > 0
    # the bound is a bound, not a loose tolerance: far below the states and the 1e-7 of two fits
    assert np.all(bound < 1e-9 * np.abs(a).max()), bound
    assert np.all(np.abs(a - b) <= bound), (np.abs(a - b), bound)


_CACHE_SCRIPT = f"""
import json, jax
hits = []
jax.monitoring.register_event_listener(
    lambda name, **kw: hits.append(1) if name == "/jax/compilation_cache/cache_hits" else None)
import mfm
at_import = jax.config.jax_compilation_cache_dir          # import mfm sets no cache
mfm.runner.xla.compilation_cache()                        # what the first front door does
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)   # RM3 compiles fast
here = {{"q": None, "qd": None}}
if RUN:
    exec({_rm3_rollout_script(20)!r}.replace("print(json.dumps(", "here.update(("), {{"here": here}})
print(json.dumps({{"dir": jax.config.jax_compilation_cache_dir, "hits": len(hits),
                  "at_import": at_import,
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
    assert first["at_import"] is None                   # import mfm turns no cache on
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


def test_wide_products_are_made_column_by_column_and_keep_the_loop_whole():
    """se3.matmul_small with the loop compiled whole on a CPU: a product of more than 8,192
    multiplications (Wu & Yuan's A∞ H, 75 × 75 × 18; Hᵀ(A∞ H); BᵀMB over 16 bodies) is made as
    matrix–vector products in a loop, a narrower one (M4 134's 24 × 24 × 7) stays one
    multiply–reduce. Both are X Y to the round-off of a sum of k terms (|X||Y| k u), in value,
    derivatives and under vmap; and a time loop holding the wide one is still compiled whole."""
    from mfm.mechanics import se3

    if jax.default_backend() != "cpu":
        pytest.skip("the column form is the CPU's (a GPU keeps the multiply–reduce)")
    assert _backend.LOOPS_COMPILED_WHOLE
    rng = np.random.default_rng(7)
    cases = [((75, 75), (75, 18), False, True), ((24, 24), (24, 7), False, False),
             ((32, 32), (32, 8), False, False), ((32, 32), (32, 9), False, True),   # 8,192 | 9,216
             ((16, 6, 18), (16, 6, 18), True, True), ((8, 6, 7), (8, 6, 7), True, False)]
    for xs, ys, tr, wide in cases:
        X, Y = rng.standard_normal(xs), rng.standard_normal(ys)
        Xm, Ym = (X.reshape(-1, xs[-1]), Y.reshape(-1, ys[-1])) if tr else (X, Y)
        want = Xm.T @ Ym if tr else X @ Y
        k = Xm.shape[0] if tr else X.shape[1]
        bound = k * np.finfo(float).eps * ((np.abs(Xm).T @ np.abs(Ym)) if tr
                                           else np.abs(X) @ np.abs(Y))
        f = jax.jit(lambda X, Y, tr=tr: se3.matmul_small(X, Y, transpose_x=tr))
        got = np.asarray(f(jnp.asarray(X), jnp.asarray(Y)))
        assert np.all(np.abs(got - want) <= bound), (xs, np.abs(got - want).max())
        jaxpr = str(jax.make_jaxpr(f)(X, Y))
        assert ("scan" in jaxpr or "while" in jaxpr) == wide, (xs, ys)     # the columns' loop
        # linear in Y: its Jacobian is X (Xᵀ) itself, exactly; a vmapped call is the calls
        J = np.asarray(jax.jacfwd(lambda Y: se3.matmul_small(jnp.asarray(X), Y, transpose_x=tr))(
            jnp.asarray(Y)))
        Jw = np.einsum("ij,kl->ikjl", Xm.T if tr else X, np.eye(Ym.shape[1]))
        np.testing.assert_array_equal(J.reshape(Jw.shape[0], Jw.shape[1], -1),
                                      Jw.reshape(Jw.shape[0], Jw.shape[1], -1))
        batch = jnp.stack([jnp.asarray(Y), 2.0 * jnp.asarray(Y)])
        v = np.asarray(jax.vmap(lambda Y: se3.matmul_small(jnp.asarray(X), Y, transpose_x=tr))(batch))
        assert np.all(np.abs(v[1] - 2.0 * got) <= 2.0 * bound)

    A = jnp.asarray(rng.standard_normal((75, 75)))

    @jax.jit
    def loop(H):
        def step(i, H):
            return H + 1e-6 * se3.matmul_small(A, H)
        return jax.lax.fori_loop(0, 100, step, H)

    H0 = jnp.asarray(rng.standard_normal((75, 18)))
    assert "xla_cpu_small_call" in loop.lower(H0).compile().as_text()
