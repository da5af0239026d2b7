"""The model at rest has one linearisation (mfm.frequency.rest), shared by the equilibrium, the
frequency domain and the checks of a run; and the package's old import paths still work.

Which loads count at rest: a load whose static_load() is None has nothing static (a time history,
a probe) and is left out. The time domain used to keep such a load as it is, evaluated at t = 0,
while the frequency domain dropped it. Dropping is right: a torque history's value at t = 0 is not
part of what restores the model. On a point-mass double pendulum (analytic: ω² = (g/L)(2 ∓ √2),
hanging equilibrium q = 0) under a torque series whose first value is large, the equilibrium and
the stability check's shortest period stay the analytic ones; keeping the series at t = 0 would
move the equilibrium to where gravity balances the torque (0.2 rad here) and, through
∂M⁻¹/∂q · τ(0), the old ∂q̈/∂q's periods by tens of per cent."""
import importlib
import math
import warnings

import jax.numpy as jnp
import numpy as np
import pytest

import mfm
from mfm.frequency import rest
from mfm.io.config import parse_config
from mfm.loads import BodyPointOutputs, CoordinateForceSeries, LinearBodyMatrix

G, L = 9.81, 1.0


def point_mass_double_pendulum():
    tiny = [1e-9, 1e-9, 1e-9]
    bodies = [{"name": "upper", "mass": 1.0, "com": [0, 0, -L], "principal_inertia": tiny,
               "joint": {"type": "revolute", "axis": [0, 1, 0], "point": [0, 0, 0]}},
              {"name": "lower", "parent": "upper", "mass": 1.0, "com": [0, 0, -2 * L],
               "principal_inertia": tiny,
               "joint": {"type": "revolute", "axis": [0, 1, 0], "point": [0, 0, -L]}}]
    return mfm.compile_tree(parse_config({"model": {"gravity": G}, "bodies": bodies})[1],
                            name="pendulum", gravity=G)


def torque_series(model, value):
    """A constant torque history on both hinges from t = 0 (large: ~ the weights' moments)."""
    return CoordinateForceSeries(t0=jnp.asarray(0.0), step=jnp.asarray(1.0),
                                 values=jnp.full((2, model.n_coordinates), value))


def test_a_time_history_neither_moves_the_equilibrium_nor_the_periods():
    model = point_mass_double_pendulum()
    series = torque_series(model, 5.0)
    probe = BodyPointOutputs(points=mfm.mechanics.points.BodyPoints.on_bodies(
        model.com, [1], [np.asarray(model.com[1])]), names=("tip",))
    extra = (series, probe)
    assert rest.static_loads(extra) == ()
    # the equilibrium of the frequency domain: hanging, whatever the series (keeping it at t = 0
    # would balance 5 N m against the weights: ~0.2 rad)
    q0, _ = mfm.equilibrium(model, loads=extra)
    assert np.abs(q0).max() < 1e-12
    # the stability check's shortest period (the run's checks): the analytic fast mode, to the
    # tiny inertias' 1e-9 and the round-off of the jet
    T_exact = 2 * math.pi / math.sqrt(G / L * (2 + math.sqrt(2)))
    T = rest.shortest_natural_period(model, np.zeros(2), rest.still_water_loads(model, extra))
    assert abs(T / T_exact - 1) < 1e-7
    # the same linear system as the frequency domain's, with or without the series
    sys = mfm.frequency.linear_system(model, np.zeros(2), loads=extra)
    J, K = rest.linearised_at_rest(model, np.zeros(2), rest.still_water_loads(model, extra))
    np.testing.assert_array_equal(K, sys.K)
    np.testing.assert_allclose(J, -np.linalg.solve(sys.M, sys.K), rtol=1e-12)
    # and the run records the same: nothing unrestored, no stability warning at dt = T/50
    with warnings.catch_warnings():
        warnings.simplefilter("error", mfm.StabilityWarning)
        ds = mfm.simulate(model, duration=0.1, dt=T_exact / 50, loads=extra)
    assert ds.attrs["no_restoring"] == ""


def test_the_stability_check_warns_past_the_limit_of_the_analytic_period():
    # RK4 is stable for ω dt < 2.785: at ω_max dt = 3 the run's check must warn
    model = point_mass_double_pendulum()
    w = math.sqrt(G / L * (2 + math.sqrt(2)))
    with pytest.warns(mfm.StabilityWarning, match="shortest natural period"):
        mfm.simulate(model, duration=3.0 / w * 4, dt=3.0 / w, loads=torque_series(model, 5.0))


def test_a_damping_ratio_is_set_from_the_linearisation_above_the_loads(tmp_path):
    # a [[body_matrices]] damping_ratio needs the model's linearisation, which the loads never
    # import: mfm.load sets it (mfm.frequency.resolve_damping_ratios), LinearBodyMatrix.create
    # through the resolver mfm.frequency registers; a load with a ratio still unset refuses to run
    cfg = tmp_path / "sphere.toml"
    src = (mfm_root() / "configs" / "sphere.toml").read_text().replace(
        'database = "../hydro/data/sphere.nc"', f'database = "{mfm_root() / "hydro/data/sphere.nc"}"')
    cfg.write_text(src)
    plain = mfm.load(cfg)
    made = LinearBodyMatrix.create(plain, "sphere", damping_ratio={"heave": 0.2})
    assert made.damping_ratios == ()
    c = float(made.damping[0, 2, 2])
    cfg.write_text(src + '\n[[body_matrices]]\nbody = "sphere"\ndamping_ratio = {heave = 0.2}\n')
    built = next(ld for ld in mfm.load(cfg).loads if isinstance(ld, LinearBodyMatrix))
    assert c > 0 and float(built.damping[0, 2, 2]) == c
    table = LinearBodyMatrix.parse_table([{"body": "sphere", "damping_ratio": {"heave": 0.2}}],
                                         list(plain.body_names))
    pending = LinearBodyMatrix.from_parsed(table, plain)
    with pytest.raises(ValueError, match="resolve_damping_ratios"):
        mfm.frequency.linear_system(plain, loads=pending)
    assert float(mfm.frequency.resolve_damping_ratios(plain, pending).damping[0, 2, 2]) == c


def mfm_root():
    from conftest import ROOT
    return ROOT


def test_old_import_paths_are_gone():
    """The flat module paths of before the house layout (mfm.water, mfm.stability, ...) were
    dropped (CHANGELOG.md): the stand-ins that kept them were planted in sys.modules at import.
    ``mfm.simulate`` is the function; an old module fails to import as any missing module."""
    assert callable(mfm.simulate)
    for old in ("mfm.water", "mfm.stability", "mfm.se3", "mfm._compat"):
        with pytest.raises(ModuleNotFoundError):
            importlib.import_module(old)
    with pytest.raises(AttributeError, match="no attribute 'no_such_module'"):
        mfm.no_such_module
