"""The wind-thrust load (seed 003, Stansby & Li eq. 33): H = ½ ρ A C_T(U) (U − u_hub)|U − u_hub| at
the hub, each property against something independent of the load's own code (hand values from
the CSV, finite differences, closed-form statics and kinematics)."""
from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import CONFIGS, ROOT

import mfm
from mfm.io.config import parse_config
from mfm.loads import BodyPointOutputs, LinearBodyMatrix, WindThrust
from mfm.loads.wind import WindWarning

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

RHO, R = 1.2, 63.0
A = math.pi * R**2
# C_T by hand from mfm/data/nrel5mw_ct.csv: U = 11.4 lies 0.8 of the way from the 11.0 row
# (0.72987175) to the 11.5 row (0.70701647); 8.0, 3.0 and 24.0 are rows of the table
CT = {11.4: 0.72987175 + 0.8 * (0.70701647 - 0.72987175), 8.0: 0.7629228, 3.0: 0.99,
      24.0: 0.06345518, 2.0: 0.0}
EXACT = 1e-12       # the same float operations in another order: rounding only


def thrust(U, u=0.0, ct=None, area=A, rho=RHO):
    ct = CT[U] if ct is None else ct
    return 0.5 * rho * area * ct * (U - u) * abs(U - u)


def _model(joint, com=(0.0, 0.0, 0.0), mass=1e6, inertia=1e9):
    return mfm.compile_tree(parse_config({"bodies": [
        {"name": "platform", "mass": mass, "com": list(com), "principal_inertia": [inertia] * 3,
         "joint": joint}]})[1])


def _slider(k=0.0, dofs=("surge",)):
    """One body on horizontal sliders (no gravity moment, no rotation): the hub moves as q̇."""
    return _model({"type": "free", "dofs": list(dofs), "stiffness": k})


def _hinge(k=0.0, com=(0.0, 0.0, 0.0), mass=1e6, inertia=1e9):
    """One body on a hinge about +y through the origin (a positive angle swings +z towards +x)."""
    joint = {"type": "revolute", "axis": [0, 1, 0], "point": [0, 0, 0]}
    if k:
        joint["stiffness"] = k
    return _model(joint, com, mass, inertia)


def _generalised(model, load, q, qd):
    """Bᵀ F: the generalised load of the load's body wrenches at (q, q̇)."""
    q, qd = jnp.asarray(q, jnp.float64), jnp.asarray(qd, jnp.float64)
    kin = mfm.kinematics(model, q, qd)
    out = load.evaluate(mfm.loads.Context(model, 0.0, q, qd, jnp.zeros(0), kin))
    return np.asarray(jnp.einsum("nai,na->i", kin.B, out.body)), np.asarray(out.body)


@pytest.mark.parametrize("U", [11.4, 8.0])
def test_fixed_hub_feels_the_mean_thrust(U):
    # hub at rest: Q = ½ ρ A C_T U² on surge, the force along +x and no other component
    m = _slider()
    w = WindThrust.create(m, "platform", [0.0, 0.0, 90.0], rotor_radius=R, wind_speed=U)
    assert abs(float(w.thrust_coefficient[0]) / CT[U] - 1) < EXACT
    Q, body = _generalised(m, w, [0.0], [0.0])
    assert abs(Q[0] / thrust(U) - 1) < EXACT
    assert np.allclose(body[0, 1:3], 0.0, atol=0.0)


@pytest.mark.parametrize("u", [0.0, 3.0, 11.4, 15.0])
def test_moving_hub_feels_the_relative_wind(u):
    # u = U: no thrust; u > U: the hub outruns the wind and the thrust turns negative
    m = _slider()
    w = WindThrust.create(m, "platform", [0.0, 0.0, 90.0], rotor_radius=R, wind_speed=11.4)
    Q, _ = _generalised(m, w, [0.0], [u])
    expected = thrust(11.4, u)
    assert abs(Q[0] - expected) <= EXACT * thrust(11.4)
    if u > 11.4:
        assert Q[0] < 0


def test_wind_direction_in_the_horizontal_plane():
    # wind towards 30° from +x: u_hub = v·d, force H d on (surge, sway)
    m = _slider(dofs=("surge", "sway"))
    w = WindThrust.create(m, "platform", [0.0, 0.0, 90.0], rotor_radius=R, wind_speed=8.0,
                          direction_deg=30.0)
    v = np.array([2.0, -1.0])
    d = np.array([math.cos(math.radians(30)), math.sin(math.radians(30))])
    Q, _ = _generalised(m, w, [0.0, 0.0], v)
    assert np.abs(Q - thrust(8.0, v @ d) * d).max() < EXACT * thrust(8.0)


def test_hub_damping_from_the_linearisation():
    # −∂Q/∂q̇ of the engine's linearisation = ρ A C_T U at the hub; against a central difference
    # of the thrust in hub velocity (H is quadratic in u: the difference is exact up to rounding,
    # 1e-6 leaves room for the step h = 1e-3 m/s against U)
    U = 11.4
    m = _slider()
    w = WindThrust.create(m, "platform", [0.0, 0.0, 90.0], rotor_radius=R, wind_speed=U)
    h = 1e-3
    fd = -(_generalised(m, w, [0.0], [h])[0][0] - _generalised(m, w, [0.0], [-h])[0][0]) / (2 * h)
    c_hand = RHO * A * CT[U] * U
    base = mfm.frequency.linear_system(m, q0=np.zeros(1)).C[0, 0]
    c = mfm.frequency.linear_system(m, q0=np.zeros(1), loads=w).C[0, 0] - base
    assert abs(fd / c_hand - 1) < 1e-6 and abs(c / c_hand - 1) < 1e-6, (fd, c, c_hand)
    # on a hinge with the hub 80 m above it, the hub velocity is 80 θ̇: C = ρ A C_T U 80²
    mh = _hinge()
    wh = WindThrust.create(mh, "platform", [0.0, 0.0, 80.0], rotor_radius=R, wind_speed=U)
    ch = mfm.frequency.linear_system(mh, q0=np.zeros(1), loads=wh).C[0, 0]
    assert abs(ch / (c_hand * 80.0**2) - 1) < 1e-6


@pytest.mark.parametrize("theta", [0.0, 0.3])
def test_thrust_moment_about_a_hinge(theta):
    # hub 80 m above a hinge about +y: r × F = (80 sin θ, 0, 80 cos θ) × (H, 0, 0) → 80 cos θ H
    m = _hinge()
    w = WindThrust.create(m, "platform", [0.0, 0.0, 80.0], rotor_radius=R, wind_speed=11.4)
    Q, _ = _generalised(m, w, [theta], [0.0])
    assert abs(Q[0] / (80.0 * math.cos(theta) * thrust(11.4)) - 1) < EXACT


def test_equilibrium_shifts_by_thrust_over_stiffness():
    # a spring-restrained slider: q₀ = H/k (linear: Newton is exact up to its tolerance)
    k = 1e5
    m = _slider(k=k)
    w = WindThrust.create(m, "platform", [0.0, 0.0, 90.0], rotor_radius=R, wind_speed=11.4)
    q0, _ = mfm.equilibrium(m, loads=w)
    assert abs(q0[0] / (thrust(11.4) / k) - 1) < 1e-9
    # a torsion spring on a hinge (CoM on the axis: no gravity moment): k θ = 80 cos θ H, solved
    # by hand with brentq
    from scipy.optimize import brentq

    kt = 5e8
    mh = _hinge(k=kt)
    wh = WindThrust.create(mh, "platform", [0.0, 0.0, 80.0], rotor_radius=R, wind_speed=11.4)
    theta = brentq(lambda th: kt * th - 80.0 * math.cos(th) * thrust(11.4), 0.0, 1.0)
    q0, _ = mfm.equilibrium(mh, loads=wh)
    assert abs(q0[0] - theta) < 1e-10 * theta


# ------------------------------------------------------------------------------------- config
BASE = '''
[[bodies]]
name = "platform"
mass = 1e6
com = [0.0, 0.0, 0.0]
principal_inertia = [1e9, 1e9, 1e9]
[bodies.joint]
type = "free"
dofs = ["surge"]
stiffness = 1e5
'''


def _config(tmp_path, wind: str):
    p = tmp_path / "turbine.toml"
    p.write_text(BASE + "[[wind_thrust]]\n" + wind)
    return p


def test_config_reads_wind_thrust(tmp_path, monkeypatch):
    # bundled table when thrust_coefficient is omitted; a relative table path is relative to the
    # config file (run from another directory); a number is used as it is
    (tmp_path / "tables").mkdir()
    (tmp_path / "tables" / "ct.csv").write_text("# a made-up rotor\nwind_speed_mps,Ct\n4.0,0.8\n12.0,0.4\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    for line, U, ct in (("", 11.4, CT[11.4]),
                        ('thrust_coefficient = "tables/ct.csv"\n', 8.0, 0.6),  # midway 0.8 → 0.4
                        ("thrust_coefficient = 0.75\n", 8.0, 0.75)):
        m = mfm.load(_config(tmp_path, f'body = "platform"\nhub = [0, 0, 90]\nrotor_radius = 63\n'
                                       f'wind_speed = {U}\nname = "t1"\n' + line))
        (w,) = [ld for ld in m.loads if isinstance(ld, WindThrust)]
        assert w.names == ("t1",)
        assert abs(float(w.thrust_coefficient[0]) / ct - 1) < EXACT
        Q, _ = _generalised(m, w, [0.0], [0.0])
        assert abs(Q[0] / thrust(U, ct=ct) - 1) < EXACT
    assert "nrel5mw_ct.csv" in WindThrust.create(m, "platform", [0, 0, 90], rotor_radius=R,
                                                 wind_speed=8.0).provenance()["wind_platform_wind0_ct_source"]


def test_bundled_table_is_the_shared_one_with_its_source():
    shipped = (ROOT / "mfm" / "data" / "nrel5mw_ct.csv").read_text()
    assert "Source: NREL/floris" in shipped and "wind_speed_mps,Ct" in shipped
    u, ct = mfm.loads.wind.read_ct_table(mfm.loads.wind.bundled_ct_table())
    assert u[0] == 0.0 and u[-1] == 50.0 and ct[u == 11.5][0] == 0.70701647
    # shipped with the package (pyproject package-data)
    assert '"data/*.csv"' in (ROOT / "pyproject.toml").read_text()


GOOD = {"body": '"platform"', "hub": "[0, 0, 90]", "rotor_radius": "63", "wind_speed": "11.4"}


@pytest.mark.parametrize("key, value, match", [
    ("hub_height", "90", r"wind_thrust\[0\]: unknown key"),
    ("body", '"nacelle"', r"wind_thrust\[0\]\.body: 'nacelle' is not a body"),
    ("hub", "[0, 90]", r"wind_thrust\[0\]\.hub: \[0, 90\]"),
    ("rotor_radius", "0", r"wind_thrust\[0\]\.rotor_radius: 0; give a radius > 0"),
    ("wind_speed", "-1.0", r"wind_thrust\[0\]\.wind_speed: -1\.0; give a mean wind speed ≥ 0"),
    ("wind_speed", None, r"wind_thrust\[0\]\.wind_speed: missing"),
    ("rho_air", '"air"', r"wind_thrust\[0\]\.rho_air: 'air' is not a finite number"),
    ("direction_deg", "true", r"wind_thrust\[0\]\.direction_deg"),
    ("thrust_coefficient", "5.0", r"wind_thrust\[0\]\.thrust_coefficient: 5\.0; give a number in"),
    ("thrust_coefficient", "[0.7]", r"wind_thrust\[0\]\.thrust_coefficient: \[0\.7\]"),
    ("thrust_coefficient", '"missing.csv"', r"wind_thrust\[0\]\.thrust_coefficient: .*missing\.csv"),
    ("thrust_coefficient", '"bad.csv"',
     r"wind_thrust\[0\]\.thrust_coefficient: .*needs columns wind_speed_mps and Ct"),
    ("thrust_coefficient", '"down.csv"', r"wind_thrust\[0\]\.thrust_coefficient: .*must increase"),
])
def test_config_errors_name_the_key(tmp_path, key, value, match):
    (tmp_path / "bad.csv").write_text("speed,thrust\n3,0.9\n")
    (tmp_path / "down.csv").write_text("wind_speed_mps,Ct\n5,0.9\n4,0.8\n")
    entry = dict(GOOD)
    if value is None:
        entry.pop(key)
    else:
        entry[key] = value
    with pytest.raises(mfm.ConfigError, match=match):
        mfm.load(_config(tmp_path, "".join(f"{k} = {v}\n" for k, v in entry.items())))


def test_duplicate_names_and_cut_out(tmp_path):
    one = "".join(f"{k} = {v}\n" for k, v in GOOD.items()) + 'name = "t"\n'
    with pytest.raises(mfm.ConfigError, match=r"wind_thrust\[0\]\.name: 't' names two"):
        mfm.load(_config(tmp_path, one + "[[wind_thrust]]\n" + one))
    # above cut-out (the table's last C_T > 0 is at 25.01 m/s): allowed, no thrust, a warning
    m = _slider()
    with pytest.warns(WindWarning, match="cut-out"):
        w = WindThrust.create(m, "platform", [0, 0, 90], rotor_radius=R, wind_speed=30.0)
    assert float(w.thrust_coefficient[0]) == 0.0
    assert _generalised(m, w, [0.0], [0.0])[0][0] == 0.0


# ------------------------------------------------------------------------------------ outputs
def test_simulation_records_thrust_and_hub_accelerations():
    # a pendulum (hinge about +y, CoM 10 m below, hub 80 m above) released in the wind. Its hub
    # velocity in closed form from (θ, θ̇), v = 80 θ̇ (cos θ, 0, −sin θ), differenced in time
    # gives the recorded acceleration to O(dt²) (1e-3 of the peak at dt = 0.01 s, ω ≈ 0.7 rad/s);
    # the thrust is ½ ρ A C_T (U − v_x)|U − v_x|; gravity's accelerometer part g Rᵀ e_z is
    # (−g sin θ, 0, g cos θ) for a pitch θ about +y
    L, dt, U = 80.0, 0.01, 11.4
    m = _hinge(com=(0.0, 0.0, -10.0), mass=1e7, inertia=1e9)
    w = WindThrust.create(m, "platform", [0.0, 0.0, L], rotor_radius=R, wind_speed=U, name="hub")
    ds = mfm.simulate(m, None, duration=20.0, dt=dt, loads=w)
    assert ds.wind_thrust.attrs["units"] == "N" and ds.hub_acceleration.attrs["units"] == "m/s2"
    assert ds.hub_gravity_acceleration.attrs["units"] == "m/s2"
    assert ds.wind_thrust.dims == ("time", "wind_load")
    assert ds.hub_acceleration.dims == ("time", "wind_load", "axis")
    th, thd = ds.q.values[:, 0], ds.qd.values[:, 0]
    assert np.ptp(th) > 0.05       # it moved (the static tilt is ≈ 0.056 rad)
    v = L * thd[:, None] * np.stack([np.cos(th), np.zeros_like(th), -np.sin(th)], 1)
    acc = ds.hub_acceleration.sel(wind_load="hub").values
    fd = (v[2:] - v[:-2]) / (2 * dt)
    assert np.abs(fd - acc[1:-1]).max() < 1e-3 * np.abs(acc).max()
    H = 0.5 * RHO * A * CT[U] * (U - v[:, 0]) * np.abs(U - v[:, 0])
    assert np.abs(ds.wind_thrust.sel(wind_load="hub").values - H).max() < EXACT * thrust(U)
    g = float(m.gravity)
    grav = ds.hub_gravity_acceleration.sel(wind_load="hub").values
    assert np.abs(grav - g * np.stack([-np.sin(th), 0 * th, np.cos(th)], 1)).max() < EXACT * g
    assert float(ds.attrs["wind_hub_speed_mps"]) == U


def test_thrust_rao_from_the_hub_rao():
    # a floating sphere (surge restrained by a spring) with a small rotor 2 m above its CoM: the
    # thrust RAO is −ρ A C_T U (−iω) x̂_hub with x̂_hub from a [[points]] probe at the hub
    m = mfm.load(CONFIGS / "sphere.toml")
    hub = [0.0, 0.0, 1.7]
    w = WindThrust.create(m, "sphere", hub, rotor_radius=0.5, wind_speed=8.0)
    probe = BodyPointOutputs.create(m, {"hub": ("sphere", hub)})
    spring = LinearBodyMatrix.create(m, "sphere", stiffness=[1e3, 0, 0, 0, 0, 0])
    omega = np.array([1.5, 3.0])
    fr = mfm.frequency_response(m, omega, loads=[w, probe, spring])
    x = fr.point_rao.sel(point="hub", axis="x").values
    expected = -RHO * math.pi * 0.25 * CT[8.0] * 8.0 * (-1j * omega) * x
    got = fr.wind_thrust_rao.values[:, 0]
    assert np.abs(x).min() > 0 and np.abs(got - expected).max() < 1e-12 * np.abs(expected).max()


def test_vmap_over_wind_speeds():
    # a batch of loads from with_wind_speed, evaluated under one jax.vmap: ½ ρ A C_T(U) U² per U,
    # C_T by hand from the table (0 below cut-in); one compiled function serves every U
    m = _slider()
    w = WindThrust.create(m, "platform", [0.0, 0.0, 90.0], rotor_radius=R, wind_speed=8.0)
    Us = np.array([2.0, 3.0, 8.0, 11.4, 24.0])
    batch = jax.vmap(w.with_wind_speed)(jnp.asarray(Us))
    kin = mfm.kinematics(m, jnp.zeros(1), jnp.zeros(1))

    zero = jnp.zeros(1)

    @jax.jit
    def surge_force(ld):
        return ld.evaluate(mfm.loads.Context(m, 0.0, zero, zero, jnp.zeros(0), kin)).body[0, 0]

    got = np.asarray(jax.vmap(surge_force)(batch))
    expected = np.array([thrust(U) for U in Us])
    assert np.abs(got - expected).max() < EXACT * expected.max()
    assert got[0] == 0.0
    for U in (9.0, 13.0):
        surge_force(w.with_wind_speed(U))
    assert surge_force._cache_size() == 1
