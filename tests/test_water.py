"""The water through Bᵀ F (validation ladder steps 3–5): equilibrium, free decay, time domain
against the frequency domain of the same model, capytaine's own RAO, bad inputs."""
import dataclasses
import math

import numpy as np
import pytest
from conftest import CONFIGS, ROOT

import hydro
from hydro.prepare import HydroSpec
import mfm
from mfm import equilibrium, frequency_response, natural_frequencies

# per module, not session-wide: a database warning is expected here (the shipped BEM data)
pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


def load(name, **kw):
    return mfm.load(CONFIGS / f"{name}.toml", **kw)


def harmonic(t, y, w, extra=()):
    """Complex amplitude x of y ≈ c₀ + c₁t + Re[x e^{−iωt}] (+ free transients at ``extra``)."""
    cols = [np.ones_like(t), t, np.cos(w * t), np.sin(w * t)]
    for wn in extra:
        cols += [np.cos(wn * t), np.sin(wn * t), t * np.cos(wn * t), t * np.sin(wn * t)]
    c = np.linalg.lstsq(np.stack(cols, 1), y, rcond=None)[0]
    return c[2] + 1j * c[3]


def test_equilibrium_at_rest_stays_for_1000_s():
    # RM3 with masses = ρV and centres of mass above the centres of buoyancy: q = 0 is the exact
    # equilibrium; still water for 1000 s must not move it (drift < 1e-9 m).
    m = load("rm3")
    q0, info = equilibrium(m)
    np.testing.assert_allclose(q0, 0.0, atol=1e-12)
    assert info["free"] == ["spar.surge"]
    ds = mfm.simulate(m, None, duration=1000.0, dt=0.1, save_every=100)
    assert np.abs(ds.q.values).max() < 1e-9


def test_sphere_heave_free_decay_period():
    # T = 2π √((m + A₃₃(ωₙ))/C₃₃) with ωₙ solved by iteration; the radiation damping of a
    # hemisphere lengthens the damped period by 1/√(1 − ζ²) ≈ 0.3 % (ζ ≈ 0.08 measured from the
    # decay), inside the 1 % tolerance, and the memory adds no systematic shift beyond that.
    m = load("sphere")
    spec = m.hydro
    mass = float(m.mass[0])
    C33 = float(spec.C_wp[2, 2])
    db = spec.database()
    w = math.sqrt(C33 / (mass + float(db.added_mass.isel(omega=-1)[2, 2])))
    for _ in range(50):
        w = math.sqrt(C33 / (mass + float(db.added_mass.interp(omega=w)[2, 2])))
    T_n = 2 * math.pi / w
    # the same sphere with heave alone free
    bodies = mfm.io.config.parse_config({"bodies": [
        {"name": "sphere", "mass": mass, "com": [0, 0, -0.3], "principal_inertia": [833.3] * 3,
         "joint": {"type": "free", "dofs": ["heave"]}}]})[1]
    heave = mfm.compile_tree(bodies, name="sphere heave")
    heave = dataclasses.replace(heave, hydro=mfm.loads.water.load_hydro_spec(
        heave, bodies, {"database": str(ROOT / "hydro" / "data" / "sphere.nc")}, ROOT))
    ds = mfm.simulate(heave, None, duration=6 * T_n, dt=T_n / 200, q0=[0.05])
    t, z = ds.time.values, ds.q.values[:, 0]
    # upward zero crossings of the decaying heave
    i = np.where((z[:-1] < 0) & (z[1:] >= 0))[0]
    tc = t[i] - z[i] * (t[i + 1] - t[i]) / (z[i + 1] - z[i])
    T = np.mean(np.diff(tc[:3]))
    assert abs(T / T_n - 1) < 0.01, (T, T_n)
    # radiated energy is positive: the oscillation decays
    assert np.abs(z[-len(z) // 6:]).max() < 0.5 * 0.05
    E = ds.kinetic_energy + ds.potential_energy
    assert float(E[-1]) < float(E[0])


def td_vs_fd(model, T, H, radiation, periods=60):
    w = 2 * math.pi / T
    fr = frequency_response(model, [w], radiation=radiation)
    fr_db = frequency_response(model, [w])
    ds = mfm.simulate(model, hydro.Regular(height=H, period=T), duration=periods * T, dt=T / 100,
                      ramp=5 * T, radiation=radiation)
    wn = natural_frequencies(model)["eigen"].values
    wn = wn[np.abs(wn - w) > 0.1 * w]
    t = ds.time.values
    sel = t > t[-1] - 10 * T
    out = {}
    for c in model.coordinates:
        x_td = harmonic(t[sel], ds.q.sel(coordinate=c).values[sel], w, wn)
        x_fd = complex(fr.rao.sel(coordinate=c).values[0]) * H / 2
        x_db = complex(fr_db.rao.sel(coordinate=c).values[0]) * H / 2
        out[c] = (x_td, x_fd, x_db)
    return out


@pytest.mark.parametrize("radiation", ["convolution", "state_space"])
@pytest.mark.parametrize("coupling", [True, False], ids=["coupled", "uncoupled"])
def test_rm3_regular_wave_time_domain_matches_frequency_domain(radiation, coupling):
    # dt = T/100; H = 0.2 m keeps the geometric nonlinearity (rotation of the loads) far below the
    # tolerance. Amplitude and phase of every coordinate within 0.5 % of the frequency-domain
    # solution of the same model; against the raw database A(ω), B(ω) within 0.5 % too.
    m = load("rm3", body_coupling=coupling)
    res = td_vs_fd(m, 8.0, 0.2, radiation)
    for c, (x_td, x_fd, x_db) in res.items():
        assert abs(abs(x_td) / abs(x_fd) - 1) < 5e-3, (c, x_td, x_fd)
        assert abs(np.angle(x_td / x_fd)) < 5e-3, (c, x_td, x_fd)
        assert abs(x_td / x_db - 1) < 5e-3, (c, x_td, x_db)


@pytest.mark.parametrize("radiation", ["convolution", "state_space"])
def test_sphere_regular_wave_time_domain_matches_frequency_domain(radiation):
    m = load("sphere")
    res = td_vs_fd(m, 3.0, 0.05, radiation, periods=50)
    for c, (x_td, x_fd, x_db) in res.items():
        assert abs(x_td / x_fd - 1) < 5e-3, (c, x_td, x_fd)


def test_state_space_run_matches_convolution_run():
    m = load("rm3")
    sea = hydro.Jonswap(hs=1.0, tp=9.0, seed=3, n_components=60, omega_range=(0.3, 1.8))
    runs = {r: mfm.simulate(m, sea, duration=300.0, dt=0.1, ramp=30.0, radiation=r)
            for r in ("convolution", "state_space")}
    a, b = (runs[r].q.sel(time=slice(100, None)) for r in ("convolution", "state_space"))
    for c in m.coordinates[1:]:  # surge drifts freely: compare the oscillating coordinates
        rms = float(np.sqrt((a.sel(coordinate=c) ** 2).mean()))
        diff = float(np.sqrt(((a.sel(coordinate=c) - b.sel(coordinate=c)) ** 2).mean()))
        assert diff < 5e-3 * rms, (c, diff, rms)


def test_frequency_response_equals_capytaine_rao():
    # capytaine.post_pro.rao solves the same 6-dof equation about the reference point with its
    # own mass matrix and stiffness: an outside check of the linearisation and the H mapping.
    cpt = pytest.importorskip("capytaine")
    import xarray as xr
    from hydro import bem

    m = load("sphere")
    raw = bem.load(ROOT / "hydro" / "data" / "sphere.nc")
    omega = raw.omega.values[(raw.omega.values > 0.5) & (raw.omega.values < 5.0)][::6]
    mass, c = float(m.mass[0]), np.array([0.0, 0.0, -0.3])   # CoM relative to the reference point
    J = np.asarray(m.inertia[0])
    ch = np.array([[0, -c[2], c[1]], [c[2], 0, -c[0]], [-c[1], c[0], 0]])
    M = np.block([[mass * np.eye(3), -mass * ch], [mass * ch, J - mass * ch @ ch]])
    g, rho, V = 9.81, 1000.0, float(m.hydro.volume[0])
    C = np.asarray(m.hydro.C_wp).copy()
    zb = float(m.hydro.d_cob[0][2] + c[2])
    C[3, 3] += rho * g * V * zb - mass * g * c[2]
    C[4, 4] += rho * g * V * zb - mass * g * c[2]
    dofs = raw.radiating_dof
    ds = raw.sel(omega=omega).assign(
        inertia_matrix=xr.DataArray(M, coords={"influenced_dof": dofs.values, "radiating_dof": dofs.values},
                                    dims=("influenced_dof", "radiating_dof")),
        hydrostatic_stiffness=xr.DataArray(C, coords={"influenced_dof": dofs.values, "radiating_dof": dofs.values},
                                           dims=("influenced_dof", "radiating_dof")))
    ref = cpt.post_pro.rao(ds, wave_direction=0.0).squeeze()
    ours = frequency_response(m, omega)
    for k, dof in ((0, "sphere__Surge"), (2, "sphere__Heave"), (4, "sphere__Pitch")):
        a = ours.xi_rao.sel(hydro_dof=dof).values
        b = ref.sel(radiating_dof=dof).values
        # same data and the same equation: agreement to the interpolation of the database (the
        # frequencies are grid points) and round-off
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-9 * np.abs(b).max())


def test_bad_hydro_inputs(tmp_path):
    text = (CONFIGS / "rm3.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('body = "float"', 'body = "floaty"').replace(
        "../hydro/data/rm3/rm3.out", str(ROOT / "hydro/data/rm3/rm3.out")))
    with pytest.raises(ValueError, match="'floaty'.*available"):
        mfm.load(bad)
    bad.write_text(text.replace("../hydro/data/rm3/rm3.out", str(tmp_path / "none.nc")))
    with pytest.raises(FileNotFoundError, match="mfm hydro"):
        mfm.load(bad)
    m = load("rm3")
    with pytest.raises(ValueError, match="heading"):
        mfm.simulate(m, hydro.Regular(height=1.0, period=8.0, heading=1.0), duration=1.0, dt=0.1)
    with pytest.raises(ValueError, match="radiation="):
        mfm.simulate(m, None, duration=1.0, dt=0.1, radiation="prony")
    with pytest.raises(ValueError, match="omega"):
        frequency_response(m, [10.0])
    dry = load("double_pendulum")
    with pytest.raises(ValueError, match="no hydrodynamics"):
        mfm.simulate(dry, hydro.Regular(height=1.0, period=8.0), duration=1.0, dt=0.1)


def test_drag_decay_is_analytic():
    # heave-only sphere in a model without radiation or water-plane stiffness except drag: with
    # only −½ρC_D A|u|u acting, u(t) = u₀/(1 + k u₀ t/M), k = ½ρC_D A (M includes A∞).
    m = load("sphere")
    spec = m.hydro
    spec2 = HydroSpec(spec.db, spec.body_index, spec.config_names, np.asarray(m.com)[[0]],
                                np.array([[0.0, 0.0, 2.0 * math.pi]]))
    spec2.C_wp = np.zeros_like(spec2.C_wp)
    spec2.volume = np.zeros_like(spec2.volume)
    dry = dataclasses.replace(m, hydro=spec2, gravity=m.gravity * 0.0)
    ds = mfm.simulate(dry, None, duration=5.0, dt=0.005, qd0={"sphere.heave": 1.0}, radiation="none")
    Mtot = float(m.mass[0]) + spec2.added_mass_inf()[2, 2]
    k = 0.5 * 1000.0 * 2.0 * math.pi
    t = ds.time.values
    np.testing.assert_allclose(ds.qd.sel(coordinate="sphere.heave").values, 1.0 / (1.0 + k * t / Mtot), rtol=1e-8)
