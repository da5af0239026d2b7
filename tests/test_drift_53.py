"""Issue 53 item 3: mean wave drift: the database variable, its WAMIT .8/.9 reader, the load.

The WAMIT reader is checked against capytaine's own .8 writer (capytaine.io.wamit, written from the
WAMIT manual's non-dimensionalisation F/(rho g A^2 L^k), k = 1 forces, 2 moments: another
implementation of the same format), with ULEN = 2 so that the length scaling is exercised.
"""
import shutil
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hydro.database import validate
from hydro.wamit import read_wamit

RM3 = Path(__file__).resolve().parents[1] / "hydro" / "data" / "rm3"
CYLINDER = Path(__file__).resolve().parents[1] / "hydro" / "data" / "drift_cylinder.nc"


def havelock_cylinder_drift(omega, R, rho=1000.0, g=9.81, nmax=60, nth=4096):
    """The mean drift force per unit amplitude squared (N/m^2) on a fixed vertical circular
    cylinder of radius R and infinite draft in deep water, waves along +x (Havelock 1940),
    written here from MacCamy & Fuchs's diffraction potential, independently of any BEM:

        phi = (g/omega) e^{kz} f(theta),  f = sum_n eps_n i^n 2i/(pi kR H_n'(kR)) cos(n theta)

    on r = R (the Wronskian J_n H_n' - J_n' H_n = 2i/(pi kR)), and the near-field (pressure)
    mean force on the body, n the normal out of the body:
        F = -1/4 rho g oint |eta|^2 n dl + 1/4 rho iint |grad phi|^2 n dS,  eta = i omega phi/g,
    with |grad phi|^2 = (|f'|^2/R^2 + k^2 |f|^2) e^{2kz} integrated over z < 0 (1/(2k)):
        F_x = rho R/4 oint [-(k/2)|f|^2 + |f'|^2/(2 k R^2)] cos(theta) dtheta.
    Its limits: 5 pi^2/16 (kR)^3 rho g R for kR -> 0, 2/3 rho g R for kR -> inf (checked below).
    """
    from scipy.special import h1vp

    out = []
    for w in np.atleast_1d(omega):
        k = w * w / g
        th = np.linspace(0.0, 2 * np.pi, nth, endpoint=False)
        n = np.arange(nmax)[:, None]
        c = np.where(n == 0, 1.0, 2.0) * (1j) ** n * 2j / (np.pi * k * R * h1vp(n, k * R))
        f = (g / w) * (c * np.cos(n * th)).sum(0)
        fp = (g / w) * (-c * n * np.sin(n * th)).sum(0)
        integrand = (-(k / 2) * np.abs(f) ** 2 + np.abs(fp) ** 2 / (2 * k * R * R)) * np.cos(th)
        out.append(rho * R / 4 * integrand.mean() * 2 * np.pi)
    return np.array(out)


def test_havelock_limits():
    # the closed form's own limits (Havelock): long waves 5 pi^2/16 (kR)^3, short waves 2/3
    rg = 1000.0 * 9.81
    kR = 0.01
    w = np.sqrt(9.81 * kR)
    assert havelock_cylinder_drift(w, 1.0)[0] / rg == pytest.approx(5 * np.pi ** 2 / 16 * kR ** 3, rel=1e-3)
    w = np.sqrt(9.81 * 40.0)
    assert havelock_cylinder_drift(w, 1.0, nmax=120)[0] / rg == pytest.approx(2 / 3, rel=0.02)


def test_capytaine_far_field_drift_against_havelock():
    """hydro.bem.solve(drift="fixed") (capytaine 3.0's far field, via tools/drift_cylinder.py) on
    a cylinder of 8 m draft (e^{-2kd} <= 1.5e-3: infinite here) against Havelock's closed form.
    Tolerance 6 %: capytaine converges slowly in panel size (measured with the same tool: +5.6 %
    at dx 0.25 m, +4.6 % at 0.18 m at omega 2 rad/s, kR 0.41, where the drift grows as (kR)^3 and
    magnifies the mesh's error; +2.9, +0.9, -0.1 % at kR 0.64, 0.92, 1.25 at dx 0.18 m)."""
    from hydro.prepare import open_any_database

    db = open_any_database(CYLINDER)
    D = db["mean_drift"]
    assert D.attrs["motions"] == "fixed" and "far field" in D.attrs["method"]
    om = db["omega"].values
    ref = havelock_cylinder_drift(om, 1.0, rho=db.attrs["rho"], g=db.attrs["g"])
    head = D.sel(wave_direction=0.0)
    np.testing.assert_allclose(head.sel(influenced_dof="cylinder__Surge").values, ref, rtol=0.06)
    # waves towards +y push the body towards +y by the same amount (an axisymmetric body)
    beam = D.sel(wave_direction=np.pi / 2)
    np.testing.assert_allclose(beam.sel(influenced_dof="cylinder__Sway").values,
                               head.sel(influenced_dof="cylinder__Surge").values, rtol=1e-6)
    scale = float(np.max(np.abs(ref)))
    for dof, da in (("cylinder__Sway", head), ("cylinder__Surge", beam), ("cylinder__Yaw", head)):
        assert np.all(np.abs(da.sel(influenced_dof=dof).values) < 1e-6 * scale), dof
    assert np.all(D.sel(influenced_dof=["cylinder__Heave", "cylinder__Roll", "cylinder__Pitch"]).values == 0)


def _rm3_copy(tmp_path, ulen=None):
    for ext in ("1", "3", "hst", "out"):
        shutil.copy(RM3 / f"rm3.{ext}", tmp_path / f"rm3.{ext}")
    if ulen is not None:
        out = tmp_path / "rm3.out"
        text = out.read_text()
        assert "Length scale:        1.00000" in text
        out.write_text(text.replace("Length scale:        1.00000", f"Length scale:        {ulen:.5f}"))
    return tmp_path / "rm3"


def _capytaine_drift_file(path, omega, heads, values, *, rho, g, L):
    """Write `values` (n_ω, n_β, 3: surge, sway, yaw; N/m², N m/m²) with capytaine's WAMIT writer."""
    wamit = pytest.importorskip("capytaine.io.wamit")
    da = xr.DataArray(values.astype(complex)[:, :, :, None] * np.eye(len(heads))[None, :, None, :],
                      dims=("omega", "wave_direction_k", "influenced_dof", "wave_direction_l"),
                      coords={"omega": omega, "wave_direction_k": heads, "wave_direction_l": heads,
                              "influenced_dof": ["Surge", "Sway", "Yaw"], "rho": rho, "g": g,
                              "period": ("omega", 2 * np.pi / omega)})
    da = da.transpose("influenced_dof", "omega", "wave_direction_k", "wave_direction_l")
    wamit._export_wamit_mean_drift(da, str(path), length_scale=L)


def test_wamit_drift_file_read_as_capytaine_writes_it(tmp_path):
    stem = _rm3_copy(tmp_path, ulen=2.0)
    base = read_wamit(stem, body_names=["float", "spar"])
    assert "mean_drift" not in base                   # no .8/.9: a database without drift is valid
    om, beta = base["omega"].values, base["wave_direction"].values
    rng = np.random.default_rng(53)
    vals = rng.normal(size=(len(om), len(beta), 3)) * np.array([1e3, 1e3, 1e4])
    rho, g = float(base.attrs["rho"]), float(base.attrs["g"])
    # WAMIT's .9 (pressure) has the layout of the .8; capytaine writes modes 1, 2, 6 of body 1
    _capytaine_drift_file(tmp_path / "rm3.9", om, beta, vals, rho=rho, g=g, L=2.0)
    db = read_wamit(stem, body_names=["float", "spar"])
    validate(db, warn=False)
    D = db["mean_drift"]
    assert D.dims == ("omega", "wave_direction", "influenced_dof")
    got = D.sel(influenced_dof=["float__Surge", "float__Sway", "float__Yaw"]).values
    # the file holds 6 significant digits (%12.6e)
    np.testing.assert_allclose(got, vals, rtol=2e-6, atol=0)
    others = D.drop_sel(influenced_dof=["float__Surge", "float__Sway", "float__Yaw"]).values
    assert np.all(others == 0.0)
    assert D.attrs["dofs"] == "float__Surge, float__Sway, float__Yaw"
    assert "near field" in D.attrs["method"]
    # a multi-body .8 (all bodies together) cannot be split: refused when asked for, skipped by auto
    shutil.copy(tmp_path / "rm3.9", tmp_path / "rm3.8")
    with pytest.raises(ValueError, match="cannot be split"):
        read_wamit(stem, body_names=["float", "spar"], drift="momentum")
    assert "near field" in read_wamit(stem, body_names=["float", "spar"])["mean_drift"].attrs["method"]
    assert "mean_drift" not in read_wamit(stem, body_names=["float", "spar"], drift=None)
    with pytest.raises(ValueError, match="drift='far'"):
        read_wamit(stem, drift="far")


def test_wamit_drift_file_damaged(tmp_path):
    stem = _rm3_copy(tmp_path)
    base = read_wamit(stem, body_names=["float", "spar"])
    om, beta = base["omega"].values, base["wave_direction"].values
    _capytaine_drift_file(tmp_path / "rm3.9", om, beta, np.ones((len(om), len(beta), 3)),
                          rho=1000.0, g=9.81, L=1.0)
    lines = (tmp_path / "rm3.9").read_text().splitlines()
    (tmp_path / "rm3.9").write_text("\n".join(lines[:-1]) + "\n")        # one mode cut off
    with pytest.raises(ValueError, match="truncated or damaged"):
        read_wamit(stem)
    (tmp_path / "rm3.9").write_text("\n".join(lines[3:]) + "\n")          # first frequency short
    with pytest.raises(ValueError, match="rm3.9"):
        read_wamit(stem)


def test_database_mean_drift_must_be_real_and_finite(tmp_path):
    db = read_wamit(_rm3_copy(tmp_path), body_names=["float", "spar"])
    D = np.zeros(db["excitation"].shape)
    bad = db.assign(mean_drift=(db["excitation"].dims, D + 1j))
    with pytest.raises(ValueError, match="'mean_drift' must be real"):
        validate(bad, warn=False)
    D[1, 0, 0] = np.nan
    with pytest.raises(ValueError, match="'mean_drift' has 1 non-finite"):
        validate(db.assign(mean_drift=(db["excitation"].dims, D)), warn=False)
    with pytest.raises(ValueError, match="mean_drift"):
        validate(db.assign(mean_drift=(("omega", "influenced_dof", "wave_direction"),
                                       np.zeros(D.shape).transpose(0, 2, 1))), warn=False)


def test_mfm_hydro_drift_setting():
    """[hydro.bem] drift: checked, resolved to hydro.bem.solve's arguments (no solve here)."""
    from mfm.errors import ConfigError
    from mfm.io import bemgen

    root = Path(__file__).resolve().parents[1] / "configs"
    specs, kw, _ = bemgen.config_bem_inputs(root / "wu_yuan_wec.toml")
    assert "drift" not in kw                       # absent: no drift, the up-to-date key unchanged
    key = bemgen.bem_inputs_key(specs, kw)
    specs, kw, _ = bemgen.config_bem_inputs(root / "wu_yuan_wec.toml", overrides={"drift": "free"})
    import mfm

    body = next(b for b in mfm.io.config.load_config(root / "wu_yuan_wec.toml")[1]
                if b.name == specs[0]["name"])
    assert kw["drift"] == "free" and kw["drift_inertia"]["mass"] == pytest.approx(body.mass)
    np.testing.assert_allclose(kw["drift_inertia"]["inertia"], body.inertia)
    assert bemgen.bem_inputs_key(specs, kw) != key   # the mass is an input of the free drift
    with pytest.raises(ConfigError, match=r"hydro.bem.drift: 'yes'.*accepted"):
        bemgen.config_bem_inputs(root / "wu_yuan_wec.toml", overrides={"drift": "yes"})
    with pytest.raises(ConfigError, match="3 wet bodies"):
        bemgen.config_bem_inputs(root / "m4_111.toml", overrides={"drift": "fixed"})


def test_rigid_mass_matrix_kinetic_energy():
    """The mass matrix about a reference point against the kinetic energy of the same motion
    computed at the centre of mass: T = 1/2 m |v + w x r|^2 + 1/2 w.J w, r = com - ref."""
    from hydro.bem import rigid_mass_matrix

    rng = np.random.default_rng(3)
    m, com, ref = 812.0, np.array([0.3, -0.2, -0.7]), np.array([0.1, 0.4, -0.2])
    A = rng.normal(size=(3, 3))
    J = A @ A.T + 50 * np.eye(3)
    M = rigid_mass_matrix(m, com, J, ref)
    for _ in range(3):
        v, w = rng.normal(size=3), rng.normal(size=3)
        vg = v + np.cross(w, com - ref)
        T = 0.5 * m * vg @ vg + 0.5 * w @ J @ w
        q = np.concatenate([v, w])
        assert 0.5 * q @ M @ q == pytest.approx(T, rel=1e-12)
    np.testing.assert_allclose(M, M.T, atol=1e-12)


# ------------------------------------------------------------------------------ the load
def _drift_db():
    from hydro.prepare import open_any_database

    return open_any_database(CYLINDER)


def test_newman_mean_and_difference_frequencies():
    """Newman's slow drift of a JONSWAP sea whose frequencies repeat (multiples of 2 pi/T_r):
    over one repeat period the cross terms average out exactly, so its mean is the spectrum's
    mean drift sum_j D_j a_j^2 to round-off; its spectrum lies at the difference frequencies
    |w_j - w_l| <= w_max - w_min (no sum frequency: nothing near 2 w_p); "mean" is that constant."""
    import hydro
    from hydro.drift import drift_time_series, mean_drift_of

    db = _drift_db()
    Tr = 200.0
    sea = hydro.Jonswap(hs=1.0, tp=2 * np.pi / 2.6, omega_range=(2.05, 3.45), repeat_period=Tr,
                        frequency_jitter=0.0, seed=4)
    with pytest.warns(hydro.waves.SeaStateWarning, match="omega_range"):   # the band is cut
        comps = sea.components()                                           # to the database's
    assert comps.repeat_period == pytest.approx(Tr)
    n = 8192
    t = Tr * np.arange(n) / n
    F = drift_time_series(db, comps, t, mode="newman")
    mean = mean_drift_of(db, comps)
    surge = 0
    assert mean[surge] > 0
    assert F[:, surge].mean() == pytest.approx(mean[surge], rel=1e-10)
    F_mean = drift_time_series(db, comps, t, mode="mean")
    np.testing.assert_allclose(F_mean, np.broadcast_to(mean, F_mean.shape), rtol=1e-13)
    spec = np.abs(np.fft.rfft(F[:, surge] - F[:, surge].mean())) ** 2
    w = 2 * np.pi * np.fft.rfftfreq(n, Tr / n)
    band = comps.omega.max() - comps.omega.min()
    assert spec[w > band + 1e-9].sum() < 1e-20 * spec.sum()
    assert spec.sum() > 0                                          # it does vary slowly
    # heave, roll, pitch: 0 in the database, 0 here
    assert np.all(F[:, 2:5] == 0)


def test_regular_wave_newman_is_the_mean_drift():
    import hydro
    from hydro.drift import drift_time_series

    db = _drift_db()
    a = 0.3
    comps = hydro.Regular(height=2 * a, period=2 * np.pi / 2.5).components()
    D = float(db["mean_drift"].sel(omega=2.5, wave_direction=0.0, influenced_dof="cylinder__Surge"))
    t = np.linspace(0.0, 10.0, 101)
    for mode in ("mean", "newman"):
        F = drift_time_series(db, comps, t, mode=mode)
        np.testing.assert_allclose(F[:, 0], D * a * a, rtol=1e-13)
    # between the database's frequencies: linear interpolation of D
    comps = hydro.Regular(height=2 * a, period=2 * np.pi / 2.75).components()
    Dm = db["mean_drift"].sel(wave_direction=0.0, influenced_dof="cylinder__Surge")
    expected = 0.5 * (float(Dm.sel(omega=2.5)) + float(Dm.sel(omega=3.0))) * a * a
    assert drift_time_series(db, comps, t, mode="mean")[0, 0] == pytest.approx(expected, rel=1e-12)
    with pytest.raises(ValueError, match="drift mode 'slow'"):
        drift_time_series(db, comps, t, mode="slow")
    with pytest.raises(KeyError, match="mean drift force per unit wave amplitude squared"):
        drift_time_series(db.drop_vars("mean_drift"), comps, t, mode="mean")


def _moored_cylinder(drift, k=2.0e4, c=6.3e4, database=CYLINDER):
    """The drift check's cylinder (R 1 m, draft 8 m, its own mass) free in surge on a spring k
    (N/m) and a damper c (N s/m): with its added mass (~ the same again) omega_n ~ 0.63 rad/s and
    c about critical. ``database``: the drift check's file, or a copy of it."""
    import mfm

    m = 1000.0 * np.pi * 8.0
    cfg = {"model": {"name": "moored cylinder", "gravity": 9.81},
           "bodies": [{"name": "cylinder", "mass": m, "com": [0.0, 0.0, 0.0],
                       "principal_inertia": [1e5, 1e5, 1e4],
                       "joint": {"type": "free", "dofs": ["surge"], "stiffness": [k],
                                 "damping": [c]}}],
           "hydro": {"database": str(database), "drift": drift}}
    return mfm.load(cfg)


def test_regular_wave_mean_drift_force_and_offset():
    """[hydro] drift = "mean" in a regular wave (a 0.2, omega 2.5 rad/s) through mfm.simulate:
    the recorded drift_force is D a^2 r(t) at every sample (to round-off: a constant table times
    the excitation's ramp), its mean over whole periods after the ramp D a^2; and the moored
    body's mean offset over the last 8 periods, less the same run's without drift (the model is
    linear: the difference is the response to the drift force alone, the wave-frequency motion and
    its windowing error cancel), is D a^2 / k. Tolerance 1e-3: the step response's slow tail
    through the radiation memory (measured: +2e-4 of the offset 40 s after the ramp, +2e-5 after
    70 s; the mass-spring transient itself is down to e^{-25})."""
    import hydro
    import mfm
    from hydro.waves import ramp

    a, w, k = 0.2, 2.5, 2.0e4
    sea = hydro.Regular(height=2 * a, period=2 * np.pi / w)
    D = float(_drift_db()["mean_drift"].sel(omega=w, wave_direction=0.0,
                                            influenced_dof="cylinder__Surge"))
    dt, T_ramp, duration = 0.05, 10.0, 50.0
    runs = {d: mfm.simulate(_moored_cylinder(d, k=k), sea, duration=duration, dt=dt, ramp=T_ramp,
                            check_stability=False) for d in ("mean", "off")}
    res = runs["mean"]
    F = res["drift_force"].sel(hydro_dof="cylinder__Surge").values
    t = res["time"].values
    np.testing.assert_allclose(F, D * a * a * ramp(t, T_ramp), rtol=1e-12, atol=1e-12 * D * a * a)
    per = int(round(2 * np.pi / w / dt))
    after = F[t >= T_ramp]
    assert after[: per * (after.size // per)].mean() == pytest.approx(D * a * a, rel=1e-12)
    assert "drift_force" not in runs["off"]
    last = t >= duration - 8 * 2 * np.pi / w
    offset = (res.q.values[last, 0] - runs["off"].q.values[last, 0]).mean()
    assert offset == pytest.approx(D * a * a / k, rel=1e-3)
    assert offset > 0                                          # pushed along the waves


def test_drift_is_above_linear_for_reduce():
    """mfm.reduce's reference: a model with drift is above linear; its linear water has none."""
    from mfm.studies.fidelity import above_linear, linear_water

    model = _moored_cylinder("newman")
    assert above_linear(model) and model.hydro.drift == "newman"
    lin = linear_water(model)
    assert not above_linear(lin) and getattr(lin.hydro, "drift", "off") == "off"
    assert not above_linear(_moored_cylinder("off"))


@pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")
def test_drift_setting_errors():
    import mfm
    from mfm.errors import ConfigError

    with pytest.raises(ConfigError, match="hydro.drift: 'slow'"):
        _moored_cylinder("slow")
    cfg = {"model": {"name": "x"},
           "bodies": [{"name": "float", "mass": 727010.0, "com": [0.0, 0.0, -0.72],
                       "principal_inertia": [2e7, 2e7, 3.7e7],
                       "joint": {"type": "free", "dofs": ["heave"]}}],
           "hydro": {"database": str(RM3 / "rm3.out"), "names": ["float", "spar"], "drift": "mean"}}
    with pytest.raises(ConfigError, match="needs the database's mean_drift"):
        mfm.load(cfg)


def test_free_drift_against_capytaines_own_pipeline():
    """hydro.bem.solve(drift="free") of a cylinder off the origin (reference point (2, 1) m,
    unequal roll and pitch inertias, headings 0 and 30 degrees) against capytaine 3.0's own chain
    on the same body (tools/drift_free_check.py: fill_dataset with theta, post_pro.rao,
    far_field_mean_drift_force): the same numbers to round-off (1e-9 of the largest: the same
    operations in another order), the yaw moment after moving capytaine's, about the origin, to
    the reference point: M_r = M_0 - (x_r F_y - y_r F_x)."""
    from hydro import bem

    ds = bem.load(Path(__file__).resolve().parents[1] / "hydro" / "data" / "drift_free_check.nc")
    fin = np.isfinite(ds["omega"].values)
    ours = ds["mean_drift"].values[fin]
    ref = ds["mean_drift_capytaine"].values[fin]
    assert "free" in ds["mean_drift"].attrs["motions"]
    scale = np.max(np.abs(ref[..., :2]))
    np.testing.assert_allclose(ours[..., :2], ref[..., :2], rtol=0, atol=1e-9 * scale)
    x_r, y_r = ds["reference_point"].values[0, :2]
    moved = ref[..., 5] - (x_r * ref[..., 1] - y_r * ref[..., 0])
    np.testing.assert_allclose(ours[..., 5], moved, rtol=0, atol=1e-9 * np.max(np.abs(moved)))
    assert np.max(np.abs(ours[..., 5])) < 0.2 * np.max(np.abs(ref[..., 5]))   # the move matters
    assert np.all(ours[..., 2:5] == 0)


def test_mfm_info_says_the_drift(tmp_path, capsys):
    from mfm_cli import main

    cfg = tmp_path / "moored.toml"
    cfg.write_text(f"""[model]
name = "moored cylinder"
[hydro]
database = "{CYLINDER}"
drift = "newman"
[[bodies]]
name = "cylinder"
mass = 25132.74
com = [0.0, 0.0, 0.0]
principal_inertia = [1e5, 1e5, 1e4]
[bodies.joint]
type = "free"
dofs = ["surge"]
stiffness = [2e4]
""")
    assert main(["info", str(cfg), "--no-restoring"]) == 0
    out = capsys.readouterr().out
    assert "mean wave drift: far field" in out and "motions fixed" in out
    assert "applied ([hydro] drift = 'newman')" in out


def _rm3_float_alone(tmp_path):
    """RM3's WAMIT set cut to its first body (the float): the .out's first body block, the .1,
    .3 and .hst rows of modes 1-6 (a single-body set, where WAMIT's .8 is the body's own drift)."""
    text = (RM3 / "rm3.out").read_text()
    head, first = text.split("Body number: N=")[:2]
    (tmp_path / "f.out").write_text(head + "Body number: N=" + first)
    for ext, cols in (("1", slice(1, 3)), ("3", slice(2, 3)), ("hst", slice(0, 2))):
        keep = []
        for line in (RM3 / f"rm3.{ext}").read_text().splitlines():
            parts = line.split()
            try:
                modes = [int(p) for p in parts[cols]]
                assert modes
            except (ValueError, AssertionError):
                keep.append(line)                          # the header
                continue
            if max(modes) <= 6:
                keep.append(line)
        (tmp_path / f"f.{ext}").write_text("\n".join(keep) + "\n")
    return tmp_path / "f"


def test_wamit_single_body_momentum_drift(tmp_path):
    """A single body's .8 (far field) is read by "auto" before its .9; "pressure" reads the .9."""
    stem = _rm3_float_alone(tmp_path)
    base = read_wamit(stem, body_names=["float"])
    assert base.sizes["influenced_dof"] == 6
    om, beta = base["omega"].values, base["wave_direction"].values
    rho, g = float(base.attrs["rho"]), float(base.attrs["g"])
    far = np.random.default_rng(8).normal(size=(len(om), len(beta), 3)) * 1e3
    _capytaine_drift_file(tmp_path / "f.8", om, beta, far, rho=rho, g=g, L=1.0)
    _capytaine_drift_file(tmp_path / "f.9", om, beta, 2 * far, rho=rho, g=g, L=1.0)
    db = validate(read_wamit(stem, body_names=["float"]), warn=False)
    assert "far field" in db["mean_drift"].attrs["method"]
    np.testing.assert_allclose(db["mean_drift"].sel(influenced_dof=["float__Surge", "float__Sway",
                                                                    "float__Yaw"]).values,
                               far, rtol=2e-6)
    near = read_wamit(stem, body_names=["float"], drift="pressure")["mean_drift"]
    assert "near field" in near.attrs["method"]
    np.testing.assert_allclose(near.sel(influenced_dof="float__Surge").values, 2 * far[..., 0],
                               rtol=2e-6)
    (tmp_path / "f.9").unlink()
    with pytest.raises(FileNotFoundError, match="drift='pressure' needs the WAMIT .9"):
        read_wamit(stem, drift="pressure")


def test_newman_through_the_water_is_the_hydro_series():
    """[hydro] drift = "newman" in an irregular sea through mfm.simulate: the recorded drift_force
    at the samples is hydro.drift.drift_time_series of the same components at those times (the
    table is sampled on the run's stages: the samples fall on it, to round-off)."""
    import hydro
    import mfm
    from hydro.drift import drift_time_series

    sea = hydro.Jonswap(hs=0.3, tp=2 * np.pi / 2.6, omega_range=(2.05, 3.45), seed=2)
    model = _moored_cylinder("newman")
    with pytest.warns(hydro.waves.SeaStateWarning, match="omega_range"):
        res = mfm.simulate(model, sea, duration=10.0, dt=0.05, ramp=2.0, check_stability=False)
        comps = sea.components(water_depth=model.hydro.water_depth, g=model.hydro.g)
    t = res["time"].values
    F = drift_time_series(model.hydro.database(), comps, t, mode="newman", ramp_duration=2.0)
    got = res["drift_force"].values
    np.testing.assert_allclose(got, F, rtol=0, atol=1e-10 * np.abs(F).max())
    assert np.ptp(got[t > 2.0, 0]) > 0.1 * np.abs(got[t > 2.0, 0]).mean()     # it varies


def test_equilibrium_in_a_sea_is_the_mean_offset(tmp_path):
    """mfm.equilibrium(model, sea=...) balances the mean drift force sum_j D_j a_j^2 at rest: the
    moored cylinder's surge offset is D a^2 / k to round-off (a linear spring; the water at rest
    has no surge stiffness), whether [hydro] drift is on or off; the time domain's mean offset
    is the same D a^2 / k (test_regular_wave_mean_drift_force_and_offset, 1e-3). A JONSWAP's is
    its components' sum over k. Still water (no sea) leaves it at rest; a database without
    mean_drift is refused, naming it; a model without water says so."""
    import hydro
    import mfm
    from hydro.drift import mean_drift_of

    a, w, k = 0.2, 2.5, 2.0e4
    D = float(_drift_db()["mean_drift"].sel(omega=w, wave_direction=0.0,
                                            influenced_dof="cylinder__Surge"))
    sea = hydro.Regular(height=2 * a, period=2 * np.pi / w)
    for drift in ("off", "mean"):
        model = _moored_cylinder(drift, k=k)
        q0, info = mfm.equilibrium(model, sea=sea)
        assert q0[0] == pytest.approx(D * a * a / k, rel=1e-9), drift
        assert q0[0] > 0                                       # pushed along the waves
        assert abs(mfm.equilibrium(model)[0][0]) < 1e-12
    jonswap = hydro.Jonswap(hs=0.5, tp=2 * np.pi / 2.6, omega_range=(2.05, 3.45), seed=2)
    with pytest.warns(hydro.waves.SeaStateWarning, match="omega_range"):
        comps = jonswap.components()
        q0, _ = mfm.equilibrium(_moored_cylinder("off", k=k), sea=jonswap)
    total = float(mean_drift_of(_drift_db(), comps)[0])
    assert total > 0 and q0[0] == pytest.approx(total / k, rel=1e-9)
    bare = tmp_path / "no_drift.nc"
    from hydro.database import to_netcdf
    from hydro.prepare import open_any_database

    to_netcdf(open_any_database(CYLINDER).drop_vars("mean_drift"), bare)
    model2 = _moored_cylinder("off", k=k, database=bare)
    with pytest.raises(ValueError, match=r"mfm.equilibrium\(sea=...\) needs the database's "
                                         r"mean_drift .*no_drift.nc"):
        mfm.equilibrium(model2, sea=sea)
    dry = mfm.load({"model": {"name": "dry", "gravity": 9.81},
                    "bodies": [{"name": "b", "mass": 1.0, "com": [0.0, 0.0, 0.0],
                                "principal_inertia": [1.0, 1.0, 1.0],
                                "joint": {"type": "free", "dofs": ["surge"], "stiffness": [1.0]}}]})
    with pytest.raises(ValueError, match=r"no load of the model carries a mean wave drift"):
        mfm.equilibrium(dry, sea=sea)
