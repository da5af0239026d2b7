"""The package's three layers (docs/ARCHITECTURE.md): a pure core that knows no cache, thread,
progress display or dataset; a runner that does that work around it; front doors. And
``import mfm`` changes no global state a user did not ask for."""
import ast
import json
import re
import subprocess
import sys

import numpy as np
import pytest

import mfm
from conftest import CONFIGS, ROOT

# the pure core: mechanics, loads, the time domain's integrators/rollout/recording, the
# linearisation at rest and the frequency domain's numbers, and the two leaves it may import
# (what it asks of its host; what XLA does with its loops)
CORE = ["mfm/mechanics", "mfm/loads", "mfm/timedomain", "mfm/frequency", "mfm/host.py",
        "mfm/backend.py"]
# hydro's water science (its database readers, caches and BEM driver are its own host layer)
HYDRO_SCIENCE = ["hydro/waves.py", "hydro/excitation.py", "hydro/radiation.py",
                 "hydro/statespace.py", "hydro/vectorfit.py", "hydro/passivity.py",
                 "hydro/seabatch.py"]
HOST_WORDS = r"_programs|ThreadPoolExecutor|import xarray|fitcache|progress"


def _files(places):
    for place in places:
        p = ROOT / place
        yield from (sorted(p.rglob("*.py")) if p.is_dir() else [p])


def test_the_core_names_no_host_machinery():
    """The issue's grep, over the core's folders: no program cache, thread pool, xarray, fit
    cache or progress display (in code or prose: a docstring naming one is a dependency too)."""
    hits = [f"{f.relative_to(ROOT)}:{i}: {line.strip()}"
            for f in _files(CORE) for i, line in enumerate(f.read_text().splitlines(), 1)
            if re.search(HOST_WORDS, line)]
    assert not hits, "\n".join(hits)
    # hydro's science takes labelled databases (xarray is its data type, as capytaine's), but no
    # cache, thread or progress display
    hits = [f"{f.relative_to(ROOT)}:{i}: {line.strip()}"
            for f in _files(HYDRO_SCIENCE) for i, line in enumerate(f.read_text().splitlines(), 1)
            if re.search(HOST_WORDS.replace("|import xarray", ""), line)]
    assert not hits, "\n".join(hits)
    # the grep finds what it looks for: the runner has each of them
    runner = "\n".join(f.read_text() for f in _files(["mfm/runner"]))
    for word in HOST_WORDS.split("|"):
        assert re.search(word, runner), word


def _imports(path):
    """Every module a file imports, at its top or inside a function, as absolute names."""
    package = ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")
            if node.level:
                base = base[:len(base) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module
            out.add(name)
            out.update(f"{name}.{a.name}" for a in node.names)
    return out


def test_the_core_imports_nothing_of_the_layers_above_it():
    """Data flows one way: the core imports no runner, dataset builder, config reader, study
    or command line; no tqdm, no thread pool, no xarray (hydro's readers give it numbers)."""
    above = ("mfm.runner", "mfm.results", "mfm.io", "mfm.studies", "mfm_cli", "mfm.cli",
             "tqdm", "concurrent", "threading", "xarray", "hydro.fitcache", "hydro.fitstore",
             "hydro.contentkey")
    bad = {str(f.relative_to(ROOT)): sorted(m for m in _imports(f) if m.startswith(above))
           for f in _files(CORE)}
    assert not {k: v for k, v in bad.items() if v}, bad


def test_import_mfm_changes_no_global_state():
    """In a fresh process with jax, numpy and xarray imported: ``import mfm`` leaves os.environ
    as it was (XLA's option reaches the backend as it starts, then XLA_FLAGS is given back),
    the garbage collector as it was (enabled, nothing frozen), and adds to sys.modules only real
    modules (no stand-ins without a spec); it makes no cache folder. mfm.load then turns jax's
    compilation cache on."""
    code = """
import gc, json, os, sys, tempfile
os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp()
import jax, numpy, xarray, scipy, equinox
env, enabled, frozen, before = dict(os.environ), gc.isenabled(), gc.get_freeze_count(), set(sys.modules)
import mfm
new = set(sys.modules) - before
print(json.dumps({
    "env": {k: [env.get(k), os.environ.get(k)] for k in set(env) | set(os.environ)
            if env.get(k) != os.environ.get(k)},
    "gc": [enabled, gc.isenabled(), frozen, gc.get_freeze_count()],
    "stand_ins": sorted(m for m in new if getattr(sys.modules[m], "__spec__", None) is None
                        and m.startswith(("mfm", "hydro"))),
    "mfm_without_file": sorted(m for m in new if m.startswith("mfm")
                               and not getattr(sys.modules[m], "__file__", None)),
    "cache_dir": jax.config.jax_compilation_cache_dir,
    "folders": os.listdir(os.environ["XDG_CACHE_HOME"]),
    "whole": mfm.backend.LOOPS_COMPILED_WHOLE,
    "after_load": (mfm.load(sys.argv[1]), jax.config.jax_compilation_cache_dir)[1],
}))
"""
    env = {k: v for k, v in __import__("os").environ.items()
           if k not in ("XLA_FLAGS", "JAX_COMPILATION_CACHE_DIR", "MFM_COMPILATION_CACHE")}
    env["PYTHONPATH"] = str(ROOT)
    out = subprocess.run([sys.executable, "-c", code, str(CONFIGS / "double_pendulum.toml")],
                         env=env, capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr[-2000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["env"] == {}, got["env"]
    enabled, now_enabled, frozen, now_frozen = got["gc"]
    assert enabled and now_enabled and now_frozen == frozen
    assert got["stand_ins"] == [] and got["mfm_without_file"] == []
    assert got["cache_dir"] is None and got["folders"] == []
    assert got["whole"] is True            # and XLA's option took effect all the same
    # a session starts with a model: mfm.load turns the compilation cache on (a model without
    # water, whose load compiles nothing of the runner's own), under XDG_CACHE_HOME
    assert got["after_load"] and got["after_load"].endswith("/mfm/jax"), got["after_load"]


def test_the_core_under_the_plain_host_gives_the_runners_numbers():
    """The host changes where programs and tables come from, not the numbers: the sphere's
    equilibrium and RAOs with the plain host (jax's jit) against the runner's (programs from
    disk, compiled at a low optimisation level). Equal to round-off: the same HLO compiled at two
    optimisation levels may sum in another order (1e-12 relative, far above the ~1e-15 seen)."""
    from mfm import host
    from mfm.frequency import rest, response
    from mfm.runner.door import RUNNER

    model = mfm.load(CONFIGS / "sphere.toml")
    assert host.current() is RUNNER                  # mfm's default once imported
    with host.using(host.PLAIN):
        assert host.current() is host.PLAIN
        q_core = np.asarray(rest.equilibrium(model)[0])
        core = response.solve_raos(model, np.linspace(0.5, 2.0, 5)).x
    assert host.current() is RUNNER                  # given back
    q_door = np.asarray(mfm.equilibrium(model)[0])
    np.testing.assert_allclose(q_core, q_door, rtol=1e-12, atol=1e-12)
    door = mfm.frequency_response(model, np.linspace(0.5, 2.0, 5))["rao"].values
    np.testing.assert_allclose(core, door, rtol=1e-12, atol=1e-14 * np.abs(door).max())
    with pytest.raises(ZeroDivisionError), host.using(host.PLAIN):
        1 / 0
    assert host.current() is RUNNER
