"""Issue 34, the first answer: traced programs kept on disk (mfm.runner.programs) and a run in chunks
that compiles one copy of its outputs.

- A program saved by one process and loaded by another gives the bits of the ordinary jit call,
  and the later process traces nothing (jax's trace counter, not a timer).
- The key that names a program on disk changes with anything that changes the program: the
  static data of the arguments' pytree (numpy arrays by their bytes, not their repr), the
  shapes, dtypes and weak types of the leaves, the static arguments; what it cannot key (a
  function, a user's own class) takes the ordinary path.
- A damaged file is made anew, not trusted.
"""
from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import textwrap
import types

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from conftest import CONFIGS, ROOT, fresh_programs

from mfm import host
from mfm.runner import programs as _programs
from mfm.runner.door import RUNNER


@jax.jit
def _affine(p, x):
    return {"y": p["a"] @ x + p["b"], "n": jnp.sum(x)}


def test_a_saved_program_gives_the_ordinary_bits(monkeypatch, tmp_path):
    fresh_programs(monkeypatch, tmp_path)
    rng = np.random.default_rng(1)
    p = {"a": jnp.asarray(rng.normal(size=(5, 5))), "b": jnp.asarray(rng.normal(size=5))}
    x = jnp.asarray(rng.normal(size=5))
    before = dict(_programs.COUNTS)
    made = _programs.program(_affine, "affine", (p, x))
    assert _programs.COUNTS["saved"] == before["saved"] + 1
    assert len(list(tmp_path.glob("affine-*.bin"))) == 1
    monkeypatch.setattr(_programs, "_MADE", {})          # as a new process finds it
    loaded = _programs.program(_affine, "affine", (p, x))
    assert _programs.COUNTS["loaded"] == before["loaded"] + 1
    want = _affine(p, x)
    for got in (made(p, x), loaded(p, x)):
        assert got.keys() == want.keys()
        for k in want:
            np.testing.assert_array_equal(got[k], want[k])    # the same program: the same bits
    # the output shapes come from the saved program, as the ordinary path's eval_shape gives them
    shapes = loaded.shapes(p, x)
    assert {k: (v.shape, v.dtype) for k, v in shapes.items()} == {
        k: (v.shape, v.dtype) for k, v in jax.eval_shape(_affine, p, x).items()}
    with pytest.raises(ValueError, match="another structure"):
        loaded({"a": p["a"]}, x)


def test_a_damaged_file_is_made_anew(monkeypatch, tmp_path):
    fresh_programs(monkeypatch, tmp_path)
    p = {"a": jnp.eye(3), "b": jnp.ones(3)}
    x = jnp.arange(3.0)
    _programs.program(_affine, "affine", (p, x))
    (path,) = tmp_path.glob("affine-*.bin")
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])   # a truncated write
    monkeypatch.setattr(_programs, "_MADE", {})
    before = dict(_programs.COUNTS)
    again = _programs.program(_affine, "affine", (p, x))
    assert _programs.COUNTS["saved"] == before["saved"] + 1 and (
        _programs.COUNTS["loaded"] == before["loaded"])
    np.testing.assert_array_equal(again(p, x)["y"], _affine(p, x)["y"])


@dataclasses.dataclass(frozen=True)
class _Option:
    order: int
    name: str


@pytest.mark.filterwarnings("ignore:A JAX array is being set as static")
def test_the_key_changes_with_whatever_changes_the_program(monkeypatch):
    import equinox as eqx

    # this file's own types, keyed as mfm's are (their code does not change within the test)
    monkeypatch.setattr(_programs, "_KEYED_MODULES", _programs._KEYED_MODULES + (__name__,))

    class Table(eqx.Module):          # a pytree with static data, as a Load is
        values: jnp.ndarray
        grid: np.ndarray = eqx.field(static=True)
        label: str = eqx.field(static=True)

    grid = np.linspace(0.0, 1.0, 5000)
    base = (Table(jnp.ones(3), grid, "a"), jnp.zeros(4))
    k0 = _programs.key("f", base, {"option": _Option(2, "rk4")})
    assert k0 == _programs.key("f", base, {"option": _Option(2, "rk4")})
    # numbers of the array leaves do not change the program: the same key
    assert k0 == _programs.key("f", (Table(7.0 * jnp.ones(3), grid, "a"), jnp.ones(4)),
                               {"option": _Option(2, "rk4")})
    moved = grid.copy()
    moved[2500] += 1e-12                  # the middle of an array numpy's repr elides
    changed = [
        (Table(jnp.ones(3), moved, "a"), jnp.zeros(4)),                # static array bytes
        (Table(jnp.ones(3), grid, "b"), jnp.zeros(4)),                 # static string
        (Table(jnp.ones(3), grid, "a"), jnp.zeros(5)),                 # a leaf's shape
        (Table(jnp.ones(3), grid, "a"), jnp.zeros(4, jnp.float32)),    # a leaf's dtype
        (Table(jnp.ones(3), grid, "a"), jnp.asarray(0.0) + jnp.zeros(4)[0]),  # another structure
        (Table(jnp.ones(3), grid, "a"), jnp.zeros(4), None),          # another structure
    ]
    keys = {_programs.key("f", args, {"option": _Option(2, "rk4")}) for args in changed}
    keys |= {_programs.key("f", base, {"option": _Option(3, "rk4")}),
             _programs.key("f", base, {"option": _Option(2, "verlet")}),
             _programs.key("g", base, {"option": _Option(2, "rk4")})}
    assert k0 not in keys and len(keys) == len(changed) + 3
    # a weakly typed leaf traces otherwise than a strongly typed one
    weak, strong = jnp.asarray(1.0), jnp.asarray(1.0, jnp.float64)
    assert weak.weak_type and not strong.weak_type
    assert _programs.key("f", (weak,), {}) != _programs.key("f", (strong,), {})
    assert _programs.key("f", (1.0,), {}) != _programs.key("f", (np.float64(1.0),), {})


def test_a_module_imported_after_the_first_key_keys_only_settings_off_its_code(monkeypatch):
    # M4 134's checks' linearisation was keyed twice in one process: the radiation fit's check
    # (mfm.frequency.fitcheck) is imported between its two calls, and its settings at their
    # defaults changed the key. A module imported late now keys what differs from its code.
    import importlib.abc
    import importlib.util

    class Source(importlib.abc.SourceLoader):      # a module from text, as a .py file gives it
        def __init__(self, text):
            self.text = text

        def get_filename(self, fullname):
            return f"<{fullname}>"

        def get_data(self, path):
            return self.text.encode()

    monkeypatch.setattr(_programs, "_DEFAULTS", {})
    args = (jnp.zeros(3),)
    _programs.key("f", args, {})                  # the process's first key, if none was made
    k0 = _programs.key("f", args, {})
    source = Source("TOLERANCE = 0.05\nBAND = (0.5, 2.0)\nBYTES = 2 * 2**30\n"
                    "PICKED = 64 if len('ab') > 5 else 12\nTWICE = 1\nTWICE = 2\n")
    spec = importlib.util.spec_from_loader("mfm._late_probe", source)
    late = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "mfm._late_probe", late)
    source.exec_module(late)
    # constants only: a condition or a second assignment is no default (it stays keyed)
    assert _programs._literal_defaults(late) == {"TOLERANCE": 0.05, "BAND": (0.5, 2.0),
                                                 "BYTES": 2**31}
    keyed = [s for s in _programs._settings() if s.startswith("mfm._late_probe.")]
    assert keyed == ["mfm._late_probe.PICKED=12", "mfm._late_probe.TWICE=2"]
    del late.PICKED, late.TWICE
    assert _programs.key("f", args, {}) == k0     # at its code's values: the same program
    for name, value in [("TOLERANCE", 0.1), ("BAND", (0.5, 3.0)), ("BYTES", 2.0**31)]:
        before = getattr(late, name)
        monkeypatch.setattr(late, name, value)    # another value (2.0**31: another type)
        assert _programs.key("f", args, {}) != k0, name
        monkeypatch.setattr(late, name, before)
    assert _programs.key("f", args, {}) == k0
    # a module imported before the first key keeps all of its settings in the key
    assert _programs._EARLY is not None and "mfm.runner.programs" in _programs._EARLY
    assert any(s.startswith("mfm.runner.xla.") for s in _programs._settings())


def test_what_the_key_cannot_name_takes_the_ordinary_path(monkeypatch, tmp_path):
    import equinox as eqx

    fresh_programs(monkeypatch, tmp_path)

    class WithFunction(eqx.Module):
        scale: jnp.ndarray
        rule: object = eqx.field(static=True)

    @jax.jit
    def f(m, x):
        return m.rule(m.scale * x)

    m = WithFunction(jnp.asarray(2.0), jnp.sin)
    with pytest.raises(_programs._Unkeyable):
        _programs.key("f", (m, jnp.ones(2)), {})
    before = dict(_programs.COUNTS)
    got = _programs.program(f, "f", (m, jnp.ones(2)))(m, jnp.ones(2))
    assert _programs.COUNTS["ordinary"] == before["ordinary"] + 1
    assert not list(tmp_path.iterdir())
    np.testing.assert_array_equal(got, jnp.sin(2.0 * jnp.ones(2)))

    class Local:                      # a type outside mfm, hydro, jax, equinox, numpy
        pass

    with pytest.raises(_programs._Unkeyable, match="Local"):
        _programs.key("f", (), {"rule": Local})


# A first run through the command line in two processes sharing the caches: the second loads
# the run's programs (start, chunk, the checks' linearisation) instead of tracing them, and its
# dataset has the bits of a run with no cache at all.
SCRIPT = textwrap.dedent("""
    import sys, warnings
    import jax, mfm, hydro, numpy as np
    from mfm.runner import programs as _programs
    from jax._src import monitoring
    traced = []
    monitoring.register_event_duration_secs_listener(
        lambda name, dur, **kw: traced.append(dur) if name.endswith("jaxpr_trace_duration") else None)
    m = mfm.load(sys.argv[1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = mfm.simulate(m, None, duration=0.6, dt=0.01, q0={"upper.angle": 0.4},
                          progress=True)
        whole = mfm.simulate(m, None, duration=0.6, dt=0.01, q0={"upper.angle": 0.4})
    ds.to_netcdf(sys.argv[2])
    whole.to_netcdf(sys.argv[2] + ".whole.nc")
    print("COUNTS", _programs.COUNTS["loaded"], _programs.COUNTS["saved"], sum(traced))
""")


def test_a_second_process_loads_the_programs_and_gives_the_same_bits(tmp_path):
    import xarray as xr

    script = tmp_path / "run.py"
    script.write_text(SCRIPT)
    env = dict(os.environ, PYTHONPATH=str(ROOT), MFM_COMPILATION_CACHE=str(tmp_path / "jax"))
    env.pop("JAX_COMPILATION_CACHE_DIR", None)      # this test's own, empty, caches
    cfg = str(CONFIGS / "double_pendulum.toml")
    runs = []
    for k, cache in enumerate(("on", "on", "off")):
        e = dict(env, MFM_COMPILATION_CACHE="off") if cache == "off" else env
        r = subprocess.run([sys.executable, str(script), cfg, str(tmp_path / f"{k}.nc")],
                           env=e, capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr[-3000:]
        line = next(ln for ln in r.stdout.splitlines() if ln.startswith("COUNTS"))
        runs.append(tuple(float(v) for v in line.split()[1:]))
    (l0, s0, _), (l1, s1, trace1), (l2, s2, trace2) = runs
    assert l0 == 0 and s0 >= 3          # the first saves start, chunk, linearisation, whole run
    assert l1 == s0 and s1 == 0         # the second loads every one and saves none
    assert l2 == 0 and s2 == 0          # no cache: the ordinary path
    # tracing left: the small eager helpers (tables, memories), not the run's programs
    assert trace1 < 0.5 * trace2, (trace1, trace2)
    ref = xr.load_dataset(tmp_path / "2.nc")
    for k in (0, 1):
        for name in (f"{k}.nc", f"{k}.nc.whole.nc"):
            got = xr.load_dataset(tmp_path / name)
            for var in ("q", "qd", "qdd", "joint_force", "kinetic_energy"):
                np.testing.assert_array_equal(got[var].values, ref[var].values, err_msg=name)


def test_a_disabled_bar_is_no_bar():
    """tqdm's own ``disable=True`` (tqdm then makes a bar without its clock) runs the plain way."""
    import mfm

    m = mfm.load(CONFIGS / "double_pendulum.toml")
    kw = dict(duration=0.3, dt=0.01, q0={"upper.angle": 0.4})
    np.testing.assert_array_equal(mfm.simulate(m, progress={"disable": True}, **kw).q.values,
                                  mfm.simulate(m, **kw).q.values)


@pytest.mark.parametrize("kept", [True, False], ids=["saved program", "ordinary path"])
def test_a_compiled_program_is_not_compiled_again_when_called(monkeypatch, tmp_path, kept):
    """compile() from shapes (as a run compiles its chunk on another thread), then a call with
    arrays of those shapes (committed to the device, as a program's outputs are) runs that
    executable: XLA compiles once (counted by jax's events, not timed). The call used to lower
    the concrete arrays anew, with other sharding annotations, and compile again."""
    fresh_programs(monkeypatch, tmp_path)
    if not kept:
        monkeypatch.setattr(_programs, "folder", lambda: None)
    scale = 3.0 if kept else 5.0          # a program of each case's own, compiled nowhere else

    @jax.jit
    def fn(p, x):
        return {"y": p["a"] @ x + scale * p["b"]}

    rng = np.random.default_rng(2)
    put = lambda a: jax.device_put(a, jax.devices()[0])       # noqa: E731  (committed)
    p = {"a": put(rng.normal(size=(7, 7))), "b": put(rng.normal(size=7))}
    x = put(rng.normal(size=7))
    shapes = jax.tree_util.tree_map(lambda a: jax.ShapeDtypeStruct(a.shape, a.dtype), (p, x))
    compiles = []   # XLA compilations, or the persistent cache's answers in their stead

    def listen(event, duration, **_):
        if event == "/jax/core/compile/backend_compile_duration":
            compiles.append(event)

    def hit(event, **_):
        if event == "/jax/compilation_cache/cache_hits":
            compiles.append(event)

    jax.monitoring.register_event_duration_secs_listener(listen)
    jax.monitoring.register_event_listener(hit)
    try:
        made = _programs.program(fn, "affine7", shapes)
        made.compile(*shapes)
        assert len(compiles) == 1
        got = made(p, x)
        assert len(compiles) == 1, "the call compiled the program again"
    finally:
        jax.monitoring.unregister_event_duration_listener(listen)
        jax.monitoring.unregister_event_listener(hit)
    np.testing.assert_array_equal(got["y"], fn(p, x)["y"])
    if not kept:
        # arguments of other shapes: the jit's own path, which compiles for them
        small = ({"a": p["a"][:3, :3], "b": p["b"][:3]}, x[:3])
        np.testing.assert_array_equal(made(*small)["y"], fn(*small)["y"])


def test_the_moved_dofs_of_a_load_come_from_a_saved_program(monkeypatch, tmp_path):
    """mfm.load's search for the hydro dofs the joints move (H(q) at three random q, ~0.7 s of
    tracing each load) is a kept program: a later process loads it, and finds the same dofs as
    the ordinary jit call."""
    import mfm
    from mfm.loads import water

    fresh_programs(monkeypatch, tmp_path)
    m = mfm.load(CONFIGS / "sphere.toml")
    spec = m.hydro
    d_ref = spec.d_ref
    assert len(list(tmp_path.glob("h_samples-*.bin"))) == 1
    monkeypatch.setattr(_programs, "_MADE", {})             # as a new process finds it
    before = dict(_programs.COUNTS)
    got = water.moving_dofs(m, spec.body_index, d_ref)
    assert _programs.COUNTS["loaded"] == before["loaded"] + 1
    monkeypatch.setattr(_programs, "folder", lambda: None)   # the ordinary path
    np.testing.assert_array_equal(got, water.moving_dofs(m, spec.body_index, d_ref))
    with host.using(host.PLAIN):                             # the core's own jit
        np.testing.assert_array_equal(got, water.moving_dofs(m, spec.body_index, d_ref))
    np.testing.assert_array_equal(got, spec.moving)


def test_a_pipelined_run_calls_the_executables_it_compiled(monkeypatch):
    """A pipelined run (mfm.runner.progress.run_pipelined) compiles its steps and outputs
    programs ahead, from shapes; every chunk's call must then match what was compiled (structure,
    shapes, dtypes, weak types), else it compiles again while the run goes (M4 134's outputs
    program: 7.5 s more of a first run, when a step's weakly typed iteration count reached it)."""
    import mfm
    from mfm.runner import progress
    from mfm.runner import pipeline

    made = {}
    program = _programs.program

    def keep(jitted, name, args, static=None, **kw):
        made[name] = program(jitted, name, args, static, **kw)
        return made[name]

    calls = []
    call = _programs.Program.__call__

    def counted(self, *args):
        if any(self is p for n, p in made.items() if n in ("rollout_steps", "rollout_outputs")):
            calls.append(self._compiled is not None
                         and _programs._signature(args) == self._compiled[0])
        return call(self, *args)

    monkeypatch.setattr(pipeline._programs, "program", keep)
    monkeypatch.setattr(_programs.Program, "__call__", counted)
    monkeypatch.setattr(progress, "PIPELINE_MIN_SAMPLES", 2000)
    m = mfm.load(CONFIGS / "double_pendulum.toml")
    for integrator in ("verlet", "rk4"):
        made.clear()
        calls.clear()
        ds = mfm.simulate(m, duration=21.1, dt=0.01, q0={"upper.angle": 0.5},
                          integrator=integrator)
        assert ds.sizes["time"] == 2111
        n_chunks = progress.pipeline_plan(2110, multiple=32)[1]
        assert len(calls) == 2 * n_chunks and all(calls), (integrator, calls)   # two programs


def _freeze_count(env_extra):
    code = "import gc, mfm; print(gc.get_freeze_count())"
    env = dict(os.environ, **env_extra)
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                         text=True, check=True).stdout
    return int(out.split()[-1])


def test_importing_mfm_freezes_nothing():
    # import mfm leaves the collector as it was (issue 52: no global state at import); the
    # command line freezes at its exit, its own process (below)
    assert _freeze_count({"MFM_GC_FREEZE": ""}) == 0


def test_the_command_line_freezes_after_its_imports_and_at_exit_once(monkeypatch):
    import gc

    import mfm_cli
    from mfm.runner import collector as _gc

    registered, frozen = [], []
    monkeypatch.setattr(_gc, "_at_exit", False)
    # the module's own view of atexit and gc (the test process's own objects stay collectable)
    monkeypatch.setattr(_gc, "atexit", types.SimpleNamespace(register=registered.append))
    monkeypatch.setattr(_gc, "gc", types.SimpleNamespace(freeze=lambda: frozen.append(1)))
    monkeypatch.delenv("MFM_GC_FREEZE", raising=False)
    for _ in range(2):
        assert mfm_cli.main(["info", str(CONFIGS / "double_pendulum.toml")]) == 0
    assert frozen == [1, 1]                             # each command, after its imports
    assert registered == [_gc.freeze]                   # the exit's: once, however many ran
    monkeypatch.setattr(_gc, "gc", gc)
    # the handler itself moves what exists into the permanent generation (and undoes nothing)
    monkeypatch.setenv("MFM_GC_FREEZE", "off")
    assert _gc.freeze() is False
    monkeypatch.delenv("MFM_GC_FREEZE")
    before = gc.get_freeze_count()
    made = [object() for _ in range(10)] + [[i] for i in range(1000)]
    assert _gc.freeze() is True and gc.get_freeze_count() >= before + 1000
    del made


@pytest.mark.parametrize("kept", [True, False], ids=["saved programs", "ordinary path"])
def test_a_warm_run_traces_nothing(monkeypatch, tmp_path, kept):
    """A second ``simulate`` of the same request, on the model loaded again (a notebook cell run
    twice), traces no jax program: not the run's (kept by jax or by mfm.runner.programs), and not the
    load memories' shapes the run asks first (a ``jax.eval_shape`` of a new closure traced them
    again on every call: 0.13 s of M4 134's warm run). Counted by jax's trace events, not timed;
    pipelined (the outputs beside the time loop) as a long run is, with a memory to shape."""
    import warnings

    from jax._src import monitoring

    import hydro
    import mfm
    from mfm.runner import progress

    fresh_programs(monkeypatch, tmp_path)
    if not kept:
        monkeypatch.setattr(_programs, "folder", lambda: None)
    monkeypatch.setattr(progress, "PIPELINE_MIN_SAMPLES", 16)
    traced = []

    def listen(name, dur, **kw):
        if name.endswith("jaxpr_trace_duration"):
            traced.append(name)

    sea = hydro.Regular(height=1.0, period=6.0)
    kw = dict(duration=4.0, dt=0.1, radiation="state_space", check_stability=False)

    def run():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return mfm.simulate(mfm.load(CONFIGS / "sphere.toml"), sea, **kw)

    first = run()
    monitoring.register_event_duration_secs_listener(listen)
    try:
        second = run()
    finally:
        monitoring.unregister_event_duration_listener(listen)
    assert traced == [], traced
    np.testing.assert_array_equal(second.q.values, first.q.values)


def test_programs_run_once_compile_fast_and_give_the_same_numbers(monkeypatch, tmp_path):
    """A program run once per call (the jet of the checks, the equilibrium and the frequency
    domain) is compiled with XLA's backend at level 0 (mfm.runner.xla.once_options), on the saved and
    the ordinary path alike, and gives the numbers of the program compiled at XLA's default
    level within round-off; XLA_FLAGS naming the level, or MFM_FAST_COMPILE=off, keeps XLA's own
    choice. The suite itself compiles everything at level 0 (conftest), so the flags are set
    here as a user's process has them."""
    import mfm
    from mfm.runner import xla as _xla
    from mfm.frequency import rest

    flags = " ".join(f for f in os.environ.get("XLA_FLAGS", "").split()
                     if "optimization_level" not in f)
    monkeypatch.setenv("XLA_FLAGS", flags)
    monkeypatch.delenv(_xla.ONCE_ENV, raising=False)
    assert _xla.once_options() == (_xla.ONCE_OPTIONS if jax.default_backend() == "cpu" else None)
    if jax.default_backend() != "cpu":
        pytest.skip("level 0 is asked for on a CPU only")
    monkeypatch.setenv(_xla.ONCE_ENV, "off")
    assert _xla.once_options() is None
    monkeypatch.setenv(_xla.ONCE_ENV, "on")
    monkeypatch.setenv("XLA_FLAGS", flags + " --xla_backend_optimization_level=2")
    assert _xla.once_options() is None
    monkeypatch.setenv("XLA_FLAGS", flags)

    asked = []
    plain_compile = jax.stages.Lowered.compile

    def spy(self, compiler_options=None, **kw):
        asked.append(compiler_options)
        return plain_compile(self, compiler_options, **kw)

    monkeypatch.setattr(jax.stages.Lowered, "compile", spy)
    m = mfm.load(CONFIGS / "double_pendulum.toml")
    keyed, static, mems = rest._static_functions(m, rest.still_water_loads(m, ()))
    q = jnp.asarray([0.3, -0.2])
    args = (keyed, static, mems, q)
    reference = plain_compile(rest._static_jet.lower(*args),
                              {"xla_backend_optimization_level": 2})(*args)
    for kept in (True, False):
        fresh_programs(monkeypatch, tmp_path / str(kept))
        if not kept:
            monkeypatch.setattr(_programs, "folder", lambda: None)
        del asked[:]
        with host.using(RUNNER):                 # as a front door hands it
            got = rest._jet_program(*args)(*args)
            # the program again, as the next linearisation or equilibrium asks for it: no new
            # compilation (the ordinary path's jit cache does not hold a program compiled with
            # options)
            rest._jet_program(*args)(*args)
        assert asked == [_xla.ONCE_OPTIONS], asked        # compiled once, at level 0
        for a, b in zip(jax.tree_util.tree_leaves(got), jax.tree_util.tree_leaves(reference)):
            a, b = np.asarray(a), np.asarray(b)
            # the same operations in the same order, fused differently: a few ulps of the
            # largest entry at most
            np.testing.assert_allclose(a, b, rtol=0, atol=64 * np.finfo(float).eps
                                       * max(np.abs(b).max(), 1e-300))


def test_a_pipelined_run_steps_before_its_outputs_program_is_ready(monkeypatch, tmp_path):
    """The outputs' program (the larger of a run's) compiles beside the first chunks, whose
    outputs wait for it on their own thread: the time loop does not wait for it. Here its
    compilation waits until the steps' program has run once (20 s at most); a run that waited
    for it before stepping would record that it compiled first. The dataset is the one made
    without the wait."""
    import threading
    import warnings

    import hydro
    import mfm
    from mfm.runner import progress

    fresh_programs(monkeypatch, tmp_path)
    monkeypatch.setattr(progress, "PIPELINE_MIN_SAMPLES", 16)
    sea = hydro.Regular(height=1.0, period=6.0)
    kw = dict(duration=4.0, dt=0.1, radiation="state_space", check_stability=False)
    model = mfm.load(CONFIGS / "sphere.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plain = mfm.simulate(model, sea, **kw)
    fresh_programs(monkeypatch, tmp_path / "again")
    order, stepped = [], threading.Event()
    real = _programs.program

    class Wrapped:
        def __init__(self, made, name):
            self.made, self.name = made, name

        def compile(self, *args):
            if self.name == "rollout_outputs":
                order.append("outputs compiling")
                stepped.wait(20)
                order.append("outputs compiled")
            return self.made.compile(*args)

        def __call__(self, *args):
            if self.name == "rollout_steps" and not stepped.is_set():
                order.append("stepped")
                stepped.set()
            return self.made(*args)

    def program(fn, name, *args, **kwargs):
        made = real(fn, name, *args, **kwargs)
        return Wrapped(made, name) if name in ("rollout_steps", "rollout_outputs") else made

    monkeypatch.setattr(_programs, "program", program)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = mfm.simulate(model, sea, **kw)
    # the outputs' compilation ends after the first step, whichever thread got to its part first
    # (on a loaded machine the steps may run before the outputs' thread has even traced them);
    # a run that waited for that compilation would step last
    assert sorted(order) == ["outputs compiled", "outputs compiling", "stepped"], order
    assert order[-1] == "outputs compiled", order
    for name in ("q", "qd", "joint_force", "hydro_force"):
        np.testing.assert_array_equal(ds[name].values, plain[name].values, err_msg=name)


# What a first answer compiles, counted (mfm.runner.xla.counting: jax.monitoring's events), not
# timed: the same on any machine. A first RM3 run with empty caches compiles the run's programs
# (the whole run, the checks' linearisation, the moved dofs' samples, the loads' memories at rest)
# and no program per host operation: a jnp.asarray or jnp.zeros of host data, an eager slice or
# sum compiled a program each (15 in this run before issue 55; mfm.backend.device_array). A
# second process with the caches filled compiles nothing: every program from the compilation
# cache, small ones included (MIN_COMPILE_SECONDS 0), the run's programs not traced again.
COUNTED = textwrap.dedent("""
    import sys, warnings
    import hydro, mfm
    from mfm.runner.xla import counting
    with counting() as c:
        m = mfm.load(sys.argv[1])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ds = mfm.simulate(m, hydro.Regular(height=2.5, period=8.0), duration=20.0, dt=0.1,
                              ramp=4.0)
    ds.to_netcdf(sys.argv[2])
    print("COUNTS", c.compiled, c.loaded, c.traced)
""")
# the programs of that first run: the whole run, the checks' linearisation (static_jet), the
# moved dofs' samples (h_samples), the loads' memories at rest, H at q0 for the fit's
# judgement; 5 on the tree of issue 55, one more of headroom for a program a change may add
MAX_FIRST_RUN_PROGRAMS = 6


def test_a_first_answer_compiles_its_programs_only_and_a_cached_one_none(tmp_path):
    import xarray as xr

    script = tmp_path / "run.py"
    script.write_text(COUNTED)
    env = dict(os.environ, PYTHONPATH=str(ROOT), MFM_COMPILATION_CACHE=str(tmp_path / "jax"),
               MFM_FIT_CACHE=str(tmp_path / "fits"))
    for var in ("JAX_COMPILATION_CACHE_DIR", "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"):
        env.pop(var, None)             # this test's own caches, with mfm's own settings
    counts = []
    for k in range(2):
        r = subprocess.run([sys.executable, str(script), str(CONFIGS / "rm3.toml"),
                            str(tmp_path / f"{k}.nc")], env=env, capture_output=True, text=True,
                           timeout=600)
        assert r.returncode == 0, r.stderr[-3000:]
        line = next(ln for ln in r.stdout.splitlines() if ln.startswith("COUNTS"))
        counts.append(tuple(int(v) for v in line.split()[1:]))
    (compiled0, loaded0, _), (compiled1, loaded1, traced1) = counts
    assert 3 <= compiled0 <= MAX_FIRST_RUN_PROGRAMS and loaded0 == 0, counts
    assert compiled1 == 0 and loaded1 == compiled0, counts
    # traced again: the few small jitted helpers that are not kept as traced programs (the
    # memories at rest, H at q0); the run's programs come from disk untraced
    assert traced1 < compiled0 + 4, counts
    a, b = xr.load_dataset(tmp_path / "0.nc"), xr.load_dataset(tmp_path / "1.nc")
    for var in ("q", "qd", "qdd", "pto_power"):
        np.testing.assert_array_equal(a[var].values, b[var].values, err_msg=var)
