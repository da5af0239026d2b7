"""The simulate front door: dataset, NetCDF, errors for bad input and blow-ups."""
import numpy as np
import pytest
import xarray as xr
from conftest import CONFIGS

import hydro
import mfm
from mfm.io.config import parse_config

MODEL = mfm.load(CONFIGS / "m4_134.toml", hydro=False)  # mechanics in vacuum


def test_dataset_contents_and_netcdf_roundtrip(tmp_path):
    ds = mfm.simulate(MODEL, duration=0.5, dt=0.005, q0={"float3.angle": 0.1}, save_every=10)
    assert ds.sizes["time"] == 11 and ds.sizes["coordinate"] == 7 and ds.sizes["body"] == 8
    for v in ("q", "qd", "qdd", "body_position", "body_rotation", "joint_force", "joint_moment",
              "kinetic_energy", "potential_energy"):
        assert v in ds and "units" in ds[v].attrs
    assert ds.attrs["integrator"] == "rk4" and ds.attrs["dt"] == 0.005
    np.testing.assert_allclose(ds.time.values, np.arange(11) * 0.05, atol=1e-12)
    assert list(ds.coordinate_unit.values[:3]) == ["m", "m", "rad"]
    # the initial state is the one asked for, positions follow the config at q = 0 otherwise
    assert ds.q.sel(coordinate="float3.angle").values[0] == 0.1
    np.testing.assert_allclose(ds.body_position.sel(body="float2").values[0], [1.05, 0, -0.0733])
    # in vacuum the whole device falls freely: heave = −½ g t²
    t = ds.time.values
    np.testing.assert_allclose(ds.q.sel(coordinate="float1.heave").values, -0.5 * 9.81 * t**2, atol=1e-9)
    path = tmp_path / "run.nc"
    ds.to_netcdf(path)
    back = xr.open_dataset(path)
    xr.testing.assert_allclose(back.q, ds.q)
    assert back.attrs["model"] == "M4 134"


def test_bad_arguments_name_the_argument():
    with pytest.raises(ValueError, match="dt"):
        mfm.simulate(MODEL, duration=1.0, dt=-0.1)
    with pytest.raises(ValueError, match="duration"):
        mfm.simulate(MODEL, duration=float("nan"), dt=0.1)
    with pytest.raises(ValueError, match="integrator='euler'"):
        mfm.simulate(MODEL, duration=1.0, dt=0.1, integrator="euler")
    with pytest.raises(ValueError, match="q0: 'float9.angle'"):
        mfm.simulate(MODEL, duration=1.0, dt=0.1, q0={"float9.angle": 0.1})
    with pytest.raises(ValueError, match="shape"):
        mfm.simulate(MODEL, duration=1.0, dt=0.1, qd0=[0.0, 1.0])
    with pytest.raises(ValueError, match="save_every"):
        mfm.simulate(MODEL, duration=1.0, dt=0.1, save_every=3)


def test_blow_up_stops_with_time_and_cause():
    # a stiff spring (ω = 100 rad/s) stepped at ω dt = 5 > 2√2: RK4 is unstable
    model = mfm.compile_tree(parse_config({"bodies": [
        {"name": "s", "mass": 1.0, "com": [0, 0, 0], "principal_inertia": [1, 1, 1],
         "joint": {"type": "prismatic", "axis": [1, 0, 0], "stiffness": 1e4}}]})[1])
    with pytest.raises(mfm.SimulationError) as info:
        mfm.simulate(model, duration=200.0, dt=0.05, q0=[0.1])
    msg = str(info.value)
    assert "non-finite at t =" in msg and "s.stroke" in msg
    assert "shortest natural period 0.0628" in msg and "Reduce dt" in msg
    # the same model at a stable dt runs
    mfm.simulate(model, duration=1.0, dt=0.005, q0=[0.1])


def test_auto_radiation_takes_the_cheaper_and_says_why():
    # the convolution's work n_steps × stage offsets × (T_K/dt) lags × n² against the limit (the
    # history sum is formed once per step for each stage offset: RK4 3, Verlet 2): M4 134 (24
    # moved dofs, T_K ≈ 39 s) over 100 T_p at T_p/200 with RK4 is 2e11 multiply–adds (minutes):
    # the state space; 200 steps of it (2e9) and RM3's 2000 steps (5e7): the convolution. The
    # state space's states are integrated by RK4 where its error in the fitted modes is ≤ 1e-3
    # (M4 134 at dt 0.006: poles to |p| dt 0.09, ~2e-5), advanced exactly by Verlet (no
    # amplification factor declared) and by RK4 at a step too coarse for its poles.
    from mfm.runner.choices import (AUTO_CONVOLUTION_LIMIT, STATE_SPACE_TOLERANCE,
                                    choose_radiation)

    m4 = mfm.load(CONFIGS / "m4_134.toml")
    name, why = choose_radiation(m4, dt=0.006, n_steps=20_000)
    assert name == "state_space" and "24² moved dofs" in why and "> 2e+10" in why, why
    assert "its states integrated" in why, why
    err = float(why.split("response up to ")[1].split()[0])
    assert err <= STATE_SPACE_TOLERANCE, why
    lags = int(why.split(" lags")[0].split()[-1])
    assert abs(lags - m4.hydro.memory() / 0.006) <= 1
    assert choose_radiation(m4, dt=0.006, n_steps=200)[0] == "convolution"
    n_rk4 = int(AUTO_CONVOLUTION_LIMIT / (3 * lags * 24**2))
    assert choose_radiation(m4, dt=0.006, n_steps=n_rk4 + 1)[0] == "state_space"
    assert choose_radiation(m4, dt=0.006, n_steps=n_rk4 + 1, integrator="verlet")[0] == "convolution"
    name, why = choose_radiation(m4, dt=0.006, n_steps=10**6, integrator="verlet")
    assert name == "state_space_exact" and "verlet declares no amplification factor" in why
    # a step 10× coarser takes the poles to |p| dt ≈ 0.9: RK4's error there is far above 1e-3
    name, why = choose_radiation(m4, dt=0.06, n_steps=10**6)
    assert name == "state_space_exact" and "its states advanced exactly" in why, why
    assert choose_radiation(MODEL, dt=0.01, n_steps=10**9) == ("none", "no water")


@pytest.mark.parametrize("p", [-0.05 + 2.0j, -0.4 + 0.0j, -0.01 + 8.0j])
def test_integrated_state_error_bounds_the_modes_response(p):
    """The bound of choose_radiation's integrated states, against the steady response of one
    mode x_{n+1} = a x_n + e^{iωn dt} computed by stepping it (not by the formula), a = RK4's
    R(p dt) and a = e^{p dt}, on a dense grid of ω around the mode: the largest relative
    difference equals the bound to first order in it (within 5 %)."""
    from mfm.timedomain.integrators import RK4
    from mfm.runner.choices import integrated_state_error

    dt = 0.15 / abs(p)                           # |p| dt = 0.15: the bound ~1e-4 to 1e-3
    bound = integrated_state_error(RK4.amplification, np.array([p * dt]))
    w = abs(p.imag) + np.linspace(-3, 3, 301) * max(-p.real, 1e-3)
    n = int(30 / (-p.real * dt))                 # 30 decay times: the transient is e^-30
    steps = np.exp(1j * w * dt)

    def steady(a):
        x = np.zeros_like(w, dtype=complex)
        for _ in range(n):                       # x_n e^{-iωn dt}: the steady amplitude
            x = (a * x + 1.0) / steps
        return x * steps

    exact, rk4 = steady(np.exp(p * dt)), steady(RK4.amplification(p * dt))
    got = np.max(np.abs(rk4 - exact) / np.abs(exact))
    assert 1e-6 < bound < 1e-2
    assert abs(got - bound) <= 0.05 * bound, (got, bound)


def test_auto_runs_the_state_space_it_chose(monkeypatch):
    """radiation="auto" takes what choose_radiation says (here the integrated state space, the
    convolution limit set to 0 so that a short RM3 run takes the state space) and runs it: the
    same q to the last bit as radiation="state_space", the choice and why in the result."""
    from mfm.runner import choices

    monkeypatch.setattr(choices, "AUTO_CONVOLUTION_LIMIT", 0.0)
    m = mfm.load(CONFIGS / "rm3.toml")
    sea = hydro.Regular(height=1.0, period=8.0)
    kw = dict(duration=4.0, dt=0.1, ramp=2.0)
    auto = mfm.simulate(m, sea, **kw)
    assert auto.attrs["radiation"] == "state_space", auto.attrs["radiation"]
    assert "its states integrated" in auto.attrs["radiation_choice"]
    np.testing.assert_array_equal(auto.q.values,
                                  mfm.simulate(m, sea, radiation="state_space", **kw).q.values)


def test_outputs_computed_after_the_loop_equal_those_inside_it(monkeypatch):
    # a recorded run with a small memory evaluates its outputs after the time loop, vmapped over
    # the saved samples; forcing them back into the loop must give the same numbers (to round-off:
    # the vectorised products may sum in another order)
    import jax

    from mfm.timedomain import record as S
    from mfm.timedomain.rollout import TRACES
    m = mfm.load(CONFIGS / "double_pendulum.toml")
    kw = dict(duration=1.37, dt=0.01, q0={"upper.angle": 0.8}, save_every=1)
    after = mfm.simulate(m, **kw)
    monkeypatch.setattr(S, "DEFERRED_RECORD_MEMORY", -1)
    jax.clear_caches()                     # the setting is read when the rollout is traced
    before = TRACES["rollout"]
    inside = mfm.simulate(m, **kw)
    assert TRACES["rollout"] == before + 1
    assert after.sizes["time"] == 138
    for v in after.data_vars:
        if np.issubdtype(after[v].dtype, np.number):
            np.testing.assert_allclose(after[v].values, inside[v].values, rtol=1e-12, atol=1e-12,
                                       err_msg=v)


def test_simulate_records_every_output_but_not_the_loads_states():
    """simulate keeps every output (:data:`OUTPUTS`) but no per-sample states z (its dataset has
    none; an integrated state-space fit has ~10³ a sample): the rollout with OUTPUTS gives the
    outputs of ``record=True`` to the last bit, and an empty z where that one has the fit's."""
    from mfm.timedomain.record import OUTPUTS
    from mfm.timedomain.setup import model_loads

    m = mfm.load(CONFIGS / "rm3.toml")
    loads = model_loads(m, hydro.Regular(height=1.0, period=8.0), dt=0.1, duration=3.0,
                        ramp=1.0, radiation="state_space")
    q0 = np.zeros(m.n_coordinates)
    every = mfm.rollout(m, q0, q0, dt=0.1, n_steps=30, loads=loads, record=True)
    kept = mfm.rollout(m, q0, q0, dt=0.1, n_steps=30, loads=loads, record=OUTPUTS)
    assert every[4].shape[0] == 31 and every[4].shape[1] > 10
    assert kept[4].shape == (31, 0)
    for a, b in zip(every[:4] + every[5:6], kept[:4] + kept[5:6]):
        np.testing.assert_array_equal(a, b)
    assert every[6].keys() == kept[6].keys()
    for k in every[6]:
        np.testing.assert_array_equal(every[6][k], kept[6][k], err_msg=k)
