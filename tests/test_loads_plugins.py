"""Loads as plug-ins: one definition serves the time domain, the equilibrium and the frequency
domain; the build step apart from the model type; no import cycle; body-point outputs."""
from __future__ import annotations

import ast
import dataclasses
import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp

import numpy as np
import pytest
from conftest import CONFIGS, ROOT

import hydro
import mfm
from mfm.loads import BodyPointOutputs, JointLoad, LinearBodyMatrix, Load, LoadOutput
from mfm.studies.wec import harmonic_amplitude

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

SPHERE_DB = ROOT / "hydro" / "data" / "sphere.nc"


def _imports(package: str) -> dict[str, set[str]]:
    """module → the modules of ``mfm``/``hydro`` it imports, anywhere in the file (imports inside
    functions included: a cycle hidden in a function is still a cycle)."""
    graph = {}
    for path in sorted((ROOT / package).rglob("*.py")):
        rel = path.relative_to(ROOT).with_suffix("")
        parts = list(rel.parts)
        is_init = parts[-1] == "__init__"
        mod = ".".join(parts[:-1] if is_init else parts)
        pkg = mod if is_init else mod.rsplit(".", 1)[0]
        deps = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                deps |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = pkg.split(".")
                    base = base[:len(base) - (node.level - 1)]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module
                # `from pkg import module` imports the module (and runs pkg/__init__ first, as
                # every import does); `from module import name` imports the module
                deps |= {f"{target}.{a.name}" for a in node.names}
                deps.add(target)
        graph[mod] = {d for d in deps if d.split(".")[0] in ("mfm", "hydro")}
    return graph


def _module_graph(*packages) -> dict[str, set[str]]:
    """:func:`_imports` of ``packages`` with every dependency a module of them: an imported name
    (a class, a function) stands for its module, and ``from pkg import module`` for the module
    alone (not the package's __init__, which runs for any import of its modules)."""
    graph = {}
    for package in packages:
        graph.update(_imports(package))
    out = {}
    for m, deps in graph.items():
        mods = {d for d in deps if d in graph}
        named = {d.rsplit(".", 1)[0] for d in deps if d not in graph}
        # a package that appears only as the parent of modules imported from it
        parents = {d for d in mods if any(x.startswith(d + ".") for x in mods)
                   and d not in named}
        out[m] = ((mods - parents) | (named & set(graph))) - {m}
    return out


def test_import_graph_has_no_cycle_and_hydro_never_imports_mfm():
    graph = _module_graph("mfm", "hydro")
    for m, deps in graph.items():
        if m.startswith("hydro"):
            assert not {d for d in deps if d.startswith("mfm")}, (m, deps)
    # nothing inside imports the front door (mfm/__init__ imports everything): only `python -m mfm`
    assert not {m for m, deps in graph.items() if "mfm" in deps and m != "mfm.__main__"}
    # the package __init__ files re-export their modules: leave them out of the cycle search
    nodes = {m for m in graph if m not in ("mfm", "hydro", "mfm.loads", "mfm.frequency")}
    state = {}

    def visit(m, path):
        state[m] = 1
        for d in graph[m] & nodes:
            if state.get(d) == 1:
                raise AssertionError("import cycle: " + " → ".join(path + [m, d]))
            if d not in state:
                visit(d, path + [m])
        state[m] = 2

    for m in sorted(nodes):
        if m not in state:
            visit(m, [])


def _is_sys_path(node) -> bool:
    return (isinstance(node, ast.Attribute) and node.attr == "path"
            and isinstance(node.value, ast.Name) and node.value.id == "sys")


def _path_edits(source: str) -> list[str]:
    """The ways ``source`` reaches past the installed package: sys.path edited (insert, append,
    extend, assigned) or a module loaded from a file (importlib's spec_from_file_location)."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Attribute) and node.attr == "spec_from_file_location":
            out.append("spec_from_file_location")
        elif (isinstance(node, ast.Attribute) and node.attr in ("insert", "append", "extend")
              and _is_sys_path(node.value)):
            out.append(f"sys.path.{node.attr}")
        elif isinstance(node, (ast.Assign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(_is_sys_path(t.value if isinstance(t, ast.Subscript) else t) for t in targets):
                out.append("sys.path assigned")
    return out


def test_tests_notebooks_and_scripts_reach_no_script_by_path():
    # tests and notebooks import the package, never tools/ or benchmarks/; the scripts there run
    # with mfm installed and never edit sys.path (README, Architecture)
    import json

    sources = {p: p.read_text() for d in ("tools", "benchmarks", "tests")
               for p in sorted((ROOT / d).glob("*.py"))}
    for p in sorted((ROOT / "notebooks").glob("*.ipynb")):
        code = "\n".join("".join(c["source"]) for c in json.loads(p.read_text())["cells"]
                         if c["cell_type"] == "code")
        sources[p] = "\n".join(line for line in code.splitlines()
                               if not line.lstrip().startswith(("%", "!")))     # IPython magics
    assert len(sources) > 40
    bad = {str(p.relative_to(ROOT)): e for p, s in sources.items() if (e := _path_edits(s))}
    assert not bad, bad
    # the check sees what it looks for
    assert _path_edits("import sys\nsys.path.insert(0, 'tools')") == ["sys.path.insert"]
    assert _path_edits("import sys\nsys.path[:0] = ['tools']") == ["sys.path assigned"]
    assert _path_edits("import importlib.util as u\nu.spec_from_file_location('a', 'tools/a.py')")


def test_a_load_imports_only_the_mechanics_and_the_load_protocol():
    # the loads sit on the mechanics: what needs more (the model's linearisation for a damping
    # ratio, lines linearised about the equilibrium, datasets) is done above them (mfm.frequency,
    # mfm.io.build, mfm.results), never reached up to from a load module
    graph = _module_graph("mfm")
    # mfm.host (what the core asks of its host: a program, a mooring table) and mfm.backend
    # (what XLA does with the loops) are leaves beside the package, not above the loads: they
    # import nothing of mfm but the tables' maker (checked below); the runner's caches are never
    # reached from a load (tests/test_layers.py)
    # (mfm.loads.catenary_tables: the catenary load's tables, made on the host from MoorPy; it
    # imports nothing of mfm, checked below)
    # (mfm.radiation: the radiation strategies as objects, the description every front door and
    # the water's frequency terms resolve; it imports nothing of mfm, checked below)
    allowed = ("mfm.mechanics", "mfm.loads.base", "mfm.loads.pto", "mfm.loads.radiation",
               "mfm.loads.catenary_tables", "mfm.validation", "mfm.errors", "mfm.host",
               "mfm.backend", "mfm.radiation")
    assert {d for d in graph["mfm.backend"] if d.startswith("mfm")} == set(), graph["mfm.backend"]
    assert {d for d in graph["mfm.host"] if d.startswith("mfm")} <= {"mfm.loads.catenary_tables"}
    assert not {d for d in graph["mfm.loads.catenary_tables"] if d.startswith("mfm")}
    assert not {d for d in graph["mfm.radiation"] if d.startswith("mfm")}
    runners = ("mfm.loads", "mfm.loads.registry", "mfm.loads.assembly")
    for m, deps in graph.items():
        if m.startswith("mfm.loads") and m not in runners:
            bad = {d for d in deps if d.startswith("mfm") and not d.startswith(allowed)}
            assert not bad, f"{m} imports {sorted(bad)}"
    # and the runner builds the water beside the config's loads: loads only, and the checks
    # (and mfm.backend, the leaf that puts host arrays on the device)
    assert {d for d in graph["mfm.loads.assembly"] if d.startswith("mfm")} <= {
        "mfm.loads.base", "mfm.loads.water", "mfm.loads.radiation", "mfm.validation",
        "mfm.backend"}


def test_model_type_does_not_build():
    # mfm.mechanics.model is the type; building (config → tree → model + loads) lives in mfm.io.build
    src = (ROOT / "mfm" / "mechanics" / "model.py").read_text()
    assert "load_config" not in src and "def load(" not in src
    assert mfm.load is mfm.io.build.load


def _sphere_heave_config(tmp_path, extra=""):
    text = f'''
[model]
name = "sphere heave"
[hydro]
database = "{SPHERE_DB.as_posix()}"
[[bodies]]
name = "sphere"
mass = 2092.29322
com = [0.0, 0.0, -0.3]
principal_inertia = [833.3, 833.3, 833.3]
[bodies.joint]
type = "free"
dofs = ["heave"]
''' + extra
    p = tmp_path / "sphere_heave.toml"
    p.write_text(text)
    return p


def test_joint_load_preload_equilibrium_by_hand(tmp_path):
    # a heave-only sphere pushed down by a constant generalised load τ on its heave: the water
    # plane restores with C33 (buoyancy ρgV is constant at the CoB, the water-plane stiffness is
    # linear), so z₀ = (ρgV − mg + τ)/C33 exactly (the model's hydrostatics are linear in heave).
    m = mfm.load(_sphere_heave_config(tmp_path, '''
[[joint_loads]]
coordinate = "sphere.heave"
value = -5000.0
'''))
    spec = m.hydro
    C33 = float(spec.C_wp[2, 2])
    rho_g_V = spec.rho * spec.g * float(spec.volume[0])
    z_hand = (rho_g_V - float(m.mass[0]) * float(m.gravity) - 5000.0) / C33
    q0, _ = mfm.equilibrium(m)
    assert abs(q0[0] - z_hand) < 1e-9 * abs(z_hand), (q0, z_hand)
    # the same load through loads= on the plain model gives the same equilibrium
    plain = mfm.load(_sphere_heave_config(tmp_path))
    q1, _ = mfm.equilibrium(plain, loads=JointLoad.create(plain, {"sphere.heave": -5000.0}))
    assert abs(q1[0] - z_hand) < 1e-9 * abs(z_hand)
    # and the time domain settles there (still water, heavy extra damping to settle fast)
    d = LinearBodyMatrix.create(plain, "sphere", damping=[0, 0, 2e4, 0, 0, 0])
    ds = mfm.simulate(plain, None, duration=20.0, dt=0.01, radiation="none",
                      loads=[JointLoad.create(plain, {"sphere.heave": -5000.0}), d])
    assert abs(float(ds.q.values[-1, 0]) - z_hand) < 1e-6


def test_hinge_preload_equilibrium_by_hand():
    # a rod on a hinge with a torsion spring k, CoM at distance L below the hinge; preload τ:
    # τ − k θ − m g L sin θ = 0, solved by hand with scipy's brentq
    from scipy.optimize import brentq
    from mfm.io.config import parse_config

    k, mass, L, tau = 300.0, 10.0, 0.5, 40.0
    model = mfm.compile_tree(parse_config({"bodies": [
        {"name": "rod", "mass": mass, "com": [0, 0, -L], "principal_inertia": [1, 1, 1],
         "joint": {"type": "revolute", "axis": [0, 1, 0], "point": [0, 0, 0], "stiffness": k}}]})[1])
    # about +y, a positive angle swings the CoM towards −x: gravity's moment is −m g L sin θ
    theta = brentq(lambda th: tau - k * th - mass * 9.81 * L * math.sin(th), -1.0, 1.0)
    q0, _ = mfm.equilibrium(model, loads=JointLoad.create(model, {"rod.angle": tau}))
    assert abs(q0[0] - theta) < 1e-10


def test_damping_ratio_of_critical_comes_back(tmp_path):
    # 20 % of critical on the heave of a floating sphere (k = C33, m = M + A33(ωn) iterated): the
    # modal damping ratio of natural_frequencies is that number (single-dof mode: exact up to
    # the A(ω) interpolation, 1 % asked)
    m = mfm.load(_sphere_heave_config(tmp_path, '''
[[body_matrices]]
body = "sphere"
damping_ratio = {heave = 0.2}
'''))
    nat = mfm.natural_frequencies(m)
    assert abs(float(nat["damping_ratio"][0]) / 0.2 - 1) < 0.01, nat["damping_ratio"].values
    # the coefficient is 2 ζ √(k m) with the hand values
    spec = m.hydro
    C33 = float(spec.C_wp[2, 2])
    wn = float(nat["eigen"][0])
    A33 = float(spec.database().added_mass.interp(omega=wn)[2, 2])
    c_hand = 2 * 0.2 * math.sqrt(C33 * (float(m.mass[0]) + A33))
    ld = next(ld for ld in m.loads if isinstance(ld, LinearBodyMatrix))
    assert abs(float(ld.damping[0, 2, 2]) / c_hand - 1) < 1e-3
    # and it damps the time domain: a free decay's log decrement gives ζ back within a few %
    # (radiation adds ζ_rad, also reported)
    zr = float(nat["radiation_damping_ratio"][0])
    assert 0 < zr < 0.2


def test_body_matrix_load_changes_time_domain_and_frequency_domain_alike():
    # RM3 with a linear surge spring (a linearised mooring) and extra pitch damping on the spar,
    # given by loads=: the regular-wave amplitudes of the time domain equal frequency_response
    # of the same model and loads within 0.5 % (state-space radiation in both)
    m = mfm.load(CONFIGS / "rm3.toml")
    extra = LinearBodyMatrix.create(m, "spar", stiffness=[2e5, 0, 0, 0, 0, 0],
                                    damping=[0, 0, 0, 0, 5e8, 0])
    T, H = 8.0, 0.2
    w = 2 * math.pi / T
    fr = mfm.frequency_response(m, [w], radiation="state_space", loads=extra)
    fr0 = mfm.frequency_response(m, [w], radiation="state_space")
    ds = mfm.simulate(m, hydro.Regular(height=H, period=T), duration=60 * T, dt=T / 100,
                      ramp=5 * T, radiation="state_space", loads=extra)
    nat = mfm.natural_frequencies(m, loads=extra)["eigen"].values
    t = ds.time.values
    sel = t > t[-1] - 10 * T
    for c in m.coordinates:
        x_td = harmonic_amplitude(t[sel], ds.q.sel(coordinate=c).values[sel], w,
                                  nat[np.abs(nat - w) > 0.1 * w])
        x_fd = complex(fr.rao.sel(coordinate=c).values[0]) * H / 2
        assert abs(x_td / x_fd - 1) < 5e-3, (c, x_td, x_fd)
    # the load changed the answer (surge is restored now)
    s = "spar.surge" if "spar.surge" in m.coordinates else m.coordinates[0]
    assert abs(abs(fr.rao.sel(coordinate=s).values[0]) / abs(fr0.rao.sel(coordinate=s).values[0]) - 1) > 0.01


def test_body_point_outputs_time_domain_and_rao(tmp_path):
    # a point 2 m above the sphere's CoM: its acceleration equals the second difference of its
    # position (O(dt²): 1e-3 of the peak at dt = T/400) and, in a regular wave, the RAO × ω²
    # of the frequency domain (0.5 %, the TD–FD tolerance)
    m = mfm.load(CONFIGS / "sphere.toml")
    probe = BodyPointOutputs.create(m, {"hub": ("sphere", [0.0, 0.0, 1.7])})
    T, H = 3.0, 0.05
    w = 2 * math.pi / T
    dt = T / 400
    ds = mfm.simulate(m, hydro.Regular(height=H, period=T), duration=40 * T, dt=dt, ramp=5 * T,
                      radiation="state_space", loads=probe)
    pos = ds.point_position.sel(point="hub").values
    acc = ds.point_acceleration.sel(point="hub").values
    vel = ds.point_velocity.sel(point="hub").values
    fd = (pos[2:] - 2 * pos[1:-1] + pos[:-2]) / dt**2
    assert np.abs(fd - acc[1:-1]).max() < 1e-3 * np.abs(acc).max()
    assert np.abs((pos[2:] - pos[:-2]) / (2 * dt) - vel[1:-1]).max() < 1e-3 * np.abs(vel).max()
    fr = mfm.frequency_response(m, [w], radiation="state_space", loads=probe)
    nat = mfm.natural_frequencies(m)["eigen"].values
    t = ds.time.values
    sel = t > t[-1] - 10 * T
    for k, ax in enumerate("xz"):
        i = "xyz".index(ax)
        a_td = harmonic_amplitude(t[sel], acc[sel, i], w, nat[np.abs(nat - w) > 0.1 * w])
        a_fd = complex(fr.point_acceleration_rao.sel(point="hub", axis=ax).values[0]) * H / 2
        x_fd = complex(fr.point_rao.sel(point="hub", axis=ax).values[0]) * H / 2
        assert abs(a_fd / (-w**2 * x_fd) - 1) < 1e-12
        assert abs(a_td / a_fd - 1) < 5e-3, (ax, a_td, a_fd)


def test_hydraulic_pto_enters_the_frequency_domain():
    # a vertical piston from the sphere to the sea floor: its κ stiffens heave, its μ adds mass and
    # β damps it, in the linearisation exactly as k = κ, m = μ, c = β on the heave coordinate
    m = mfm.load(CONFIGS / "sphere.toml")
    from mfm.loads import HydraulicPTO
    from mfm.mechanics.points import BodyPoints

    i = m.body_index("sphere")
    pto = HydraulicPTO(a=BodyPoints.on_bodies(m.com, [i], [[0.0, 0.0, -0.3]]),
                       b=BodyPoints.on_bodies(m.com, [0], [[0.0, 0.0, -20.0]]),
                       mu=np.array([300.0]), beta=np.array([4e3]), kappa=np.array([2e3]),
                       length0=np.array([19.7]), b_fixed=(True,), names=("piston",))
    base = mfm.frequency.linear_system(m)
    sys = mfm.frequency.linear_system(m, loads=pto)
    k = m.coordinate_index("sphere.heave")
    assert abs(sys.K[k, k] - base.K[k, k] - 2e3) < 1e-6 * 2e3
    assert abs(sys.C[k, k] - base.C[k, k] - 4e3) < 1e-9 * 4e3
    assert abs(sys.M[k, k] - base.M[k, k] - 300.0) < 1e-9 * 300
    fr = mfm.frequency_response(m, [2.0], loads=pto)
    assert float(fr.hydraulic_pto_power.values[0, 0]) > 0


def test_config_tables_come_from_the_registry():
    from mfm.loads.registry import TABLES, load_class
    from mfm.io.config import TOP_KEYS

    for table in TABLES:
        assert table in TOP_KEYS
        cls = load_class(table)
        assert hasattr(cls, "parse_table") and hasattr(cls, "from_parsed")


def test_integrator_stage_offsets_drive_the_convolution():
    # an integrator declares its stages; one that does not is refused with the reason
    import dataclasses

    m = mfm.load(CONFIGS / "sphere.toml")

    @dataclasses.dataclass(frozen=True)
    class Silent(mfm.integrators.RK4):
        stage_offsets: tuple = None

    with pytest.raises(TypeError, match="stage_offsets"):
        mfm.simulate(m, None, duration=0.1, dt=0.01, integrator=Silent())
    # RK4 evaluates at 0, dt/2, dt: one weight set per stage
    from mfm.timedomain.setup import model_loads

    ld = model_loads(m, None, dt=0.01, duration=0.1, memory=1.0)[0]
    assert ld.rad.W_lag.shape[0] == 3 and ld.rad.stage_offsets == (0.0, 0.5, 1.0)
    ld = model_loads(m, None, dt=0.01, duration=0.1, memory=1.0, integrator="newmark")[0]
    assert ld.rad.stage_offsets == (0.0, 1.0)


def test_simulate_batch_records_named_outputs_as_simulate_does():
    # outputs=(...) in a batch: the same numbers simulate records (one compiled model, two seas),
    # to round-off (1e-9 of the peak: vmapped against single evaluation); unknown names are errors
    m = mfm.load(CONFIGS / "sphere.toml")
    probe = BodyPointOutputs.create(m, {"hub": ("sphere", [0.0, 0.0, 1.7])})
    seas = [hydro.Regular(height=0.05, period=T) for T in (2.5, 3.0)]
    ds = mfm.simulate_batch(m, seas, dt=0.01, n_steps=300, ramp=1.0, loads=probe,
                            outputs=("point_acceleration", "body_rotation"))
    assert ds.point_acceleration.dims == ("case", "step", "point", "axis")
    assert ds.point_acceleration.attrs["units"] == "m/s2"
    assert "joint_force" not in ds
    for i, sea in enumerate(seas):
        one = mfm.simulate(m, sea, duration=3.0, dt=0.01, ramp=1.0, loads=probe,
                           radiation="state_space")
        for name in ("point_acceleration", "body_rotation"):
            ref = one[name].values
            assert np.abs(ds[name].values[i] - ref).max() <= 1e-9 * np.abs(ref).max(), name
    # the progress bar's chunked run records the same
    ds2 = mfm.simulate_batch(m, seas, dt=0.01, n_steps=300, ramp=1.0, loads=probe,
                             outputs=("point_acceleration", "body_rotation"), progress=True)
    assert np.array_equal(ds2.point_acceleration.values, ds.point_acceleration.values)
    with pytest.raises(ValueError, match="outputs: \\['hub_speed'\\]"):
        mfm.simulate_batch(m, seas, dt=0.01, n_steps=10, outputs=("hub_speed",))


def test_simulate_batch_varies_load_parameters_per_case(tmp_path):
    # vary_loads: the water's drag set per case equals a model whose config has that drag (one
    # compiled batch against two loads of the config); the structure must not change
    import equinox as eqx
    text = (CONFIGS / "sphere.toml").read_text().replace('"../hydro/data/sphere.nc"',
                                                           f'"{SPHERE_DB.as_posix()}"')
    assert "[bodies.hydro]" not in text
    text += '\n[bodies.hydro]\ndrag_coefficient = [1.0, 1.0, 1.0]\ndrag_area = [3.0, 3.0, 3.0]\n'
    (tmp_path / "drag.toml").write_text(text)
    m = mfm.load(CONFIGS / "sphere.toml")
    md = mfm.load(tmp_path / "drag.toml")
    sea = hydro.Regular(height=0.3, period=3.0)
    scale = [0.0, 1.0]

    def with_drag(i, loads):
        water = loads[0]
        return (eqx.tree_at(lambda w: w.drag, water, water.drag + scale[i] * 0.5 * 1000.0 * 3.0),) + loads[1:]

    ds = mfm.simulate_batch(m, [sea, sea], dt=0.02, n_steps=300, ramp=1.0, vary_loads=with_drag)
    for i, mm in enumerate((m, md)):
        one = mfm.simulate(mm, sea, duration=6.0, dt=0.02, ramp=1.0, radiation="state_space")
        assert np.abs(ds.q.values[i] - one.q.values).max() <= 1e-9 * np.abs(one.q.values).max()
    assert np.abs(ds.q.values[1] - ds.q.values[0]).max() > 1e-3 * np.abs(ds.q.values[0]).max()
    with pytest.raises(ValueError, match="vary_loads"):
        mfm.simulate_batch(m, sea, dt=0.02, n_steps=10, vary_loads="drag")


# ------------------------------------------------------------------------ a load laid on a run

class WaveDriven(Load):
    """F = G η(t) on the one coordinate, η the run's sea at the origin: η = Σ a cos(φ − ω t)
    (hydro's convention). What it needs of the sea it takes in :meth:`for_run`: a wave effect
    as a plain load, with no water and no change to the runner."""
    gain: float
    amplitude: jnp.ndarray = dataclasses.field(default_factory=lambda: jnp.zeros(0))
    omega: jnp.ndarray = dataclasses.field(default_factory=lambda: jnp.zeros(0))
    phase: jnp.ndarray = dataclasses.field(default_factory=lambda: jnp.zeros(0))
    laid_on: tuple = eqx.field(static=True, default=())
    reads_sea: ClassVar[bool] = True

    def for_run(self, model, run):
        c = run.sea.components()
        return dataclasses.replace(self, amplitude=jnp.asarray(c.amplitude),
                                   omega=jnp.asarray(c.omega), phase=jnp.asarray(c.phase),
                                   laid_on=(run.dt, run.n_steps, run.stage_offsets))

    def evaluate(self, ctx):
        eta = jnp.sum(self.amplitude * jnp.cos(self.phase - self.omega * ctx.t))
        return LoadOutput(tau=jnp.atleast_1d(self.gain * eta))


def _heave_oscillator(m=2.0, k=8.0):
    return mfm.load({"model": {"name": "heave oscillator", "gravity": 0.0},
                     "bodies": [{"name": "mass", "mass": m, "com": [0.0, 0.0, 0.0],
                                 "principal_inertia": [1.0, 1.0, 1.0],
                                 "joint": {"type": "free", "dofs": ["heave"], "stiffness": [k]}}]})


def _forced_from_rest(t, m, k, gain, sea):
    """m ẍ + k x = G a cos(ωt − φ), x(0) = ẋ(0) = 0: X cos(ωt − φ) − X cos φ cos ω_n t
    − X (ω/ω_n) sin φ sin ω_n t, X = G a/(k − m ω²)."""
    c = sea.components()
    a, w, p = float(c.amplitude[0]), float(c.omega[0]), float(c.phase[0])
    wn = math.sqrt(k / m)
    X = gain * a / (k - m * w**2)
    return X * (np.cos(w * t - p) - math.cos(p) * np.cos(wn * t)
                - (w / wn) * math.sin(p) * np.sin(wn * t))


def test_a_load_laid_on_the_run_gets_its_sea_and_grid():
    """A user's wave-driven load (for_run takes the sea's components) on a mechanics-only heave
    oscillator: simulate and simulate_batch (two seas: the laid loads differ, so their arrays
    are stacked per case) against the forced oscillator's closed form. Tolerance 1e-7 of the
    amplitude: RK4 at ω dt ≤ 0.02 over 20 s errs ~ t ω⁵ dt⁴/120 ≈ 1e-9 relative."""
    m, k, G = 2.0, 8.0, 500.0
    model = _heave_oscillator(m, k)
    seas = [hydro.Regular(height=0.4, period=5.0, phase=0.7), hydro.Regular(height=0.2, period=3.0)]
    dt, n = 0.01, 2000
    t = dt * np.arange(n + 1)
    one = mfm.simulate(model, seas[0], duration=n * dt, dt=dt, loads=WaveDriven(G),
                       check_stability=False)
    ref = _forced_from_rest(t, m, k, G, seas[0])
    scale = np.abs(ref).max()
    np.testing.assert_allclose(one.q.values[:, 0], ref, rtol=0, atol=1e-7 * scale)
    batch = mfm.simulate_batch(model, seas, dt=dt, n_steps=n, loads=WaveDriven(G))
    for b, sea in enumerate(seas):
        ref = _forced_from_rest(t, m, k, G, sea)
        np.testing.assert_allclose(batch.q.values[b, :, 0], ref, rtol=0,
                                   atol=1e-7 * np.abs(ref).max())


def test_for_run_hands_the_grid_and_must_return_a_load():
    """The run's grid as the integrator declares it (Verlet: offsets 0 and 1), and a for_run
    that returns something else than a load is refused with the load's name."""
    from mfm.loads.assembly import carried_loads
    from mfm.timedomain.setup import model_loads

    model = _heave_oscillator()
    sea = hydro.Regular(height=0.4, period=5.0)
    laid = model_loads(model, sea, dt=0.05, duration=1.0, integrator="verlet",
                       extra=(WaveDriven(1.0),))
    assert laid[-1].laid_on == (0.05, 20, (0.0, 1.0))

    class Broken(WaveDriven):
        def for_run(self, model, run):
            return None

    with pytest.raises(TypeError, match="load Broken: for_run returned None, not a Load"):
        carried_loads(model, sea, dt=0.05, duration=1.0, extra=(Broken(1.0),))
    # a sea that no load reads is refused, by both time-domain front doors
    for run in (lambda: mfm.simulate(model, sea, duration=1.0, dt=0.05),
                lambda: mfm.simulate_batch(model, [sea, None], dt=0.05, n_steps=20)):
        with pytest.raises(ValueError, match="none of its loads reads a sea"):
            run()


def test_no_module_finds_the_water_by_its_type_or_place():
    """The water is found as any load is (its protocol methods: for_run, host_view,
    linear_hydro, with_tables of the batch's tables): outside its own module no code names the
    Water class in an isinstance or takes it as loads[0]."""
    import re

    hits = []
    for path in sorted((ROOT / "mfm").rglob("*.py")):
        if path.name == "water.py":
            continue
        for i, line in enumerate(path.read_text().splitlines(), 1):
            if re.search(r"isinstance\([^)]*\bWater\b|loads\[0\]\.|water_of\(", line):
                hits.append(f"{path.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not hits, "\n".join(hits)
