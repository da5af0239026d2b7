"""The mean wave drift of a model's own motions (issue 53 item 3, a layout of several bodies): the
far-field formula on stored Kochin functions (hydro.drift.far_field_drift) and the model's drift
(mfm.frequency.drift.model_mean_drift) against capytaine 3.0's own chain on the same two bodies
(tools/drift_kochin_check.py: fill_dataset with 0.25° Kochin functions, post_pro.rao,
far_field_mean_drift_force), the total put on the root body with its yaw moved, the mean offset of
a moored layout through mfm.equilibrium(sea=), and the errors."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import hydro
import mfm
from hydro import bem
from hydro.drift import far_field_drift
from hydro.waves import wavenumber

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

DATA = Path(__file__).resolve().parents[1] / "hydro" / "data"
CHECK = DATA / "drift_kochin_check.nc"
MASS = 1000.0 * math.pi * 1.5
# capytaine's yaw takes H′(θ) by central differences on its θ grid (0.25° in the check: relative
# error ~(n dθ)²/6 for the Kochin functions' harmonics n ≲ 10, ≈ 1e-5); ours is the grid's
# Fourier series (no such error): the yaw moments agree to 1e-4, the forces (no derivative) to
# round-off
YAW_RTOL = 1e-4


def _check():
    ds = bem.load(CHECK)
    fin = np.isfinite(ds["omega"].values)
    return ds, fin


def _two_cylinders(order=("A", "B"), **hydro_keys):
    """The check's two cylinders freely floating (6 dofs each), their masses and inertias the
    tool's."""
    bodies = {
        "A": {"name": "A", "mass": MASS, "com": [0.0, 0.0, -0.9],
              "principal_inertia": [3000.0, 4500.0, 2400.0], "joint": {"type": "free"}},
        "B": {"name": "B", "mass": MASS, "com": [3.0, 1.5, -0.9],
              "principal_inertia": [3500.0, 3500.0, 2000.0], "joint": {"type": "free"}},
    }
    return mfm.load({"model": {"name": "two cylinders", "gravity": 9.81},
                     "bodies": [bodies[n] for n in order],
                     "hydro": {"database": str(CHECK), **hydro_keys}})


def test_far_field_drift_against_capytaine_on_given_motions():
    """Random complex motions of both bodies (the tool's, seed 7): surge and sway force of
    far_field_drift on the stored 2° Kochin functions against capytaine's far_field_mean_drift_force
    on its own 0.25° ones, to 1e-12 of the largest (the periodic trapezoid sum is exact for the
    functions' harmonics, far below 90 of them); the yaw moment to YAW_RTOL. Two headings (0, 30°)
    on the grid, three frequencies."""
    ds, fin = _check()
    om = ds["omega"].values[fin]
    beta = ds["wave_direction"].values
    X = ds["motions_random"].values[fin]
    ref = ds["drift_capytaine_random"].values[fin]
    nw, nb, nd = X.shape
    W, B = np.repeat(om, nb), np.tile(beta, nw)
    Hd = ds["kochin_diffraction"].values[fin].reshape(nw * nb, -1)
    Hr = np.repeat(ds["kochin_radiation"].values[fin], nb, axis=0)
    out = far_field_drift(Hd, Hr, X.reshape(-1, nd), W, wavenumber(W, math.inf, 9.81), B,
                          water_depth=math.inf, rho=1000.0, g=9.81).reshape(nw, nb, 3)
    for i, tol in ((0, 1e-12), (1, 1e-12), (2, YAW_RTOL)):
        np.testing.assert_allclose(out[..., i], ref[..., i], rtol=0,
                                   atol=tol * np.abs(ref[..., i]).max())
    # the motions matter: held bodies drift otherwise
    held = far_field_drift(Hd, Hr, 0 * X.reshape(-1, nd), W, wavenumber(W, math.inf, 9.81), B,
                           water_depth=math.inf, rho=1000.0, g=9.81).reshape(nw, nb, 3)
    assert np.abs(held[..., 0] - ref[..., 0]).max() > 0.1 * np.abs(ref[..., 0]).max()


def test_finite_depth_coefficient_against_capytaine_s_formula():
    """The same stored functions and random motions taken at a finite depth h = 4 m (kh 0.9–3.7:
    only the wavenumber and the energy-flux coefficient c₂ change): far_field_drift's surge and
    sway force against capytaine 3.0's far_field_mean_drift_force on our own 2° grid, wrapped past
    both ends as it asks, to 1e-12 (no derivative in the forces; its H(β) on the grid)."""
    cpt = pytest.importorskip("capytaine")
    import xarray as xr

    ds, fin = _check()
    h, g, rho = 4.0, 9.81, 1000.0
    om = ds["omega"].values[fin]
    beta = ds["wave_direction"].values
    th = ds["theta"].values
    N = th.size
    wrap = np.concatenate([[N - 1], np.arange(N), [0, 1]])
    theta = np.concatenate([[th[0] - 2 * np.pi / N], th, [2 * np.pi, 2 * np.pi + 2 * np.pi / N]])
    Hd = ds["kochin_diffraction"].values[fin]
    Hr = ds["kochin_radiation"].values[fin]
    X = ds["motions_random"].values[fin]
    k = wavenumber(om, h, g)
    dofs = [str(d) for d in ds["radiating_dof"].values]
    data = xr.Dataset(
        {"kochin_diffraction": (("omega", "wave_direction", "theta"), Hd[..., wrap]),
         "kochin_radiation": (("omega", "radiating_dof", "theta"), Hr[..., wrap])},
        coords={"omega": om, "wavenumber": ("omega", k), "water_depth": h, "rho": rho, "g": g,
                "theta": theta, "wave_direction": beta, "radiating_dof": dofs})
    Xda = xr.DataArray(X, dims=("omega", "wave_direction", "radiating_dof"),
                       coords={"omega": om, "wave_direction": beta, "radiating_dof": dofs})
    f = cpt.post_pro.far_field_mean_drift_force(Xda, data)
    nw, nb = len(om), len(beta)
    ours = far_field_drift(Hd.reshape(nw * nb, N),
                           np.repeat(Hr, nb, axis=0), X.reshape(nw * nb, -1), np.repeat(om, nb),
                           np.repeat(k, nb), np.tile(beta, nw), water_depth=h, rho=rho,
                           g=g).reshape(nw, nb, 3)
    for i, name in enumerate(("drift_force_surge", "drift_force_sway")):
        v = f[name].transpose("omega", "wave_direction_k", "wave_direction_l").values
        ref = np.real(np.diagonal(v, axis1=1, axis2=2))
        np.testing.assert_allclose(ours[..., i], ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    deep = far_field_drift(Hd.reshape(nw * nb, N), np.repeat(Hr, nb, axis=0),
                           X.reshape(nw * nb, -1), np.repeat(om, nb), np.repeat(k, nb),
                           np.tile(beta, nw), water_depth=math.inf, rho=rho, g=g)
    assert np.abs(deep[:, 0] - ours[..., 0].ravel()).max() > 1e-3 * np.abs(ours[..., 0]).max()


def test_the_model_s_own_drift_against_capytaine_s_chain():
    """Two cylinders freely floating, an mfm model of them (its own mechanics, its frequency
    response): its RAOs are capytaine's motions with A(ω), B(ω) symmetrised as mfm takes them
    (1e-12), and model_mean_drift the far-field drift capytaine's chain gives for them: surge and
    sway to 1e-12, yaw to YAW_RTOL, the layout's total on body A (the first of equals at the
    root), B's rows 0, heave, roll and pitch 0."""
    ds, fin = _check()
    model = _two_cylinders()
    D = mfm.mean_drift(model)
    ref = ds["drift_capytaine_free_symmetric"].values[fin]
    np.testing.assert_allclose(D["omega"].values, ds["omega"].values[fin])
    for dof, i, tol in (("A__Surge", 0, 1e-12), ("A__Sway", 1, 1e-12), ("A__Yaw", 2, YAW_RTOL)):
        np.testing.assert_allclose(D.sel(influenced_dof=dof).values, ref[..., i], rtol=0,
                                   atol=tol * np.abs(ref[..., i]).max())
    others = [d for d in D["influenced_dof"].values if d not in ("A__Surge", "A__Sway", "A__Yaw")]
    assert np.all(D.sel(influenced_dof=others).values == 0)
    assert D.attrs["dofs"] == "A__Surge, A__Sway, A__Yaw" and "model 'two cylinders'" in \
        D.attrs["motions"]
    x = mfm.frequency_response(model, ds["omega"].values[fin], heading=0.0,
                               joint_reactions=False).xi_rao.values
    want = ds["motions_free_symmetric"].values[fin][:, 0]
    np.testing.assert_allclose(x, want, rtol=0, atol=1e-12 * np.abs(want).max())
    # capytaine's own rao keeps the BEM's asymmetry: a visibly different drift (what the
    # symmetric reference above is for)
    raw = ds["drift_capytaine_free"].values[fin]
    assert 1e-5 < np.abs(raw[..., 0] - ref[..., 0]).max() / np.abs(ref[..., 0]).max() < 0.05


def test_the_total_is_put_on_the_root_body_with_its_yaw_moved():
    """The same bodies given in the order B, A: the total goes on B (the first of equals at the
    root), its yaw moment moved from the Kochin functions' origin to B's reference point
    (3, 1.5): M_B = M_0 − (x_B F_y − y_B F_x), to round-off against the A-first table."""
    a_first = mfm.mean_drift(_two_cylinders(("A", "B")))
    b_first = mfm.mean_drift(_two_cylinders(("B", "A")))
    F = {c: a_first.sel(influenced_dof=f"A__{c}").values for c in ("Surge", "Sway", "Yaw")}
    scale = np.abs(F["Surge"]).max()
    np.testing.assert_allclose(b_first.sel(influenced_dof="B__Surge").values, F["Surge"],
                               rtol=0, atol=1e-12 * scale)
    moved = F["Yaw"] - (3.0 * F["Sway"] - 1.5 * F["Surge"])
    np.testing.assert_allclose(b_first.sel(influenced_dof="B__Yaw").values, moved, rtol=0,
                               atol=1e-12 * np.abs(moved).max())
    assert np.all(b_first.sel(influenced_dof=[f"A__{c}" for c in ("Surge", "Sway", "Yaw")])
                  .values == 0)


def _moored_pair(k=5.0e3, **hydro_keys):
    """B welded to A, A moored in surge by a spring k (and a damper) and free in heave and pitch:
    the layout moves as one body."""
    return mfm.load({
        "model": {"name": "moored pair", "gravity": 9.81},
        "bodies": [{"name": "A", "mass": MASS, "com": [0.0, 0.0, -0.9],
                    "principal_inertia": [3000.0, 4500.0, 2400.0],
                    "joint": {"type": "free", "dofs": ["surge", "heave", "pitch"],
                              "stiffness": [k, 0.0, 0.0], "damping": [1.0e4, 0.0, 0.0]}},
                   {"name": "B", "parent": "A", "mass": MASS, "com": [3.0, 1.5, -0.9],
                    "principal_inertia": [3500.0, 3500.0, 2000.0], "joint": {"type": "fixed"}}],
        "hydro": {"database": str(CHECK), **hydro_keys}})


def test_the_time_domain_takes_the_drift_of_the_model_s_own_motions():
    """[hydro] drift = "mean" on the Kochin database (no mean_drift in it; the config is
    accepted): mfm.simulate records the drift force D a² r(t) on A's surge with D the model's own
    (model_mean_drift at the wave's ω, on the grid) at every sample, to round-off, and 0 on B's
    rows; simulate_batch of two heights records each case's the same (1e-12)."""
    model = _moored_pair(drift="mean")
    a, w = 0.1, 2.2
    D = mfm.mean_drift(model).sel(omega=w, wave_direction=0.0)
    sea = hydro.Regular(height=2 * a, period=2 * math.pi / w)
    run = dict(dt=0.05, ramp=2.0, radiation="none")          # 3 frequencies: no fit
    ds = mfm.simulate(model, sea, duration=4.0, check_stability=False, **run)
    t = ds["time"].values
    F = ds["drift_force"]
    r = hydro.waves.ramp(t, 2.0)
    expect = float(D.sel(influenced_dof="A__Surge")) * a * a * r
    np.testing.assert_allclose(F.sel(hydro_dof="A__Surge").values, expect, rtol=1e-12,
                               atol=1e-12 * abs(expect).max())
    assert np.all(F.sel(hydro_dof=[d for d in F["hydro_dof"].values if d.startswith("B__")])
                  .values == 0)
    b = mfm.simulate_batch(model, [sea, hydro.Regular(height=a, period=2 * math.pi / w)],
                           n_steps=80, outputs=("drift_force",), **run)
    got = b["drift_force"].sel(hydro_dof="A__Surge").values
    np.testing.assert_allclose(got[0], expect[:got.shape[1]], rtol=0,
                               atol=1e-12 * abs(expect).max())
    np.testing.assert_allclose(got[1], expect[:got.shape[1]] / 4, rtol=0,
                               atol=1e-12 * abs(expect).max())


def test_the_mean_offset_of_a_moored_layout():
    """The moored pair (B welded to A, A on a surge spring k): mfm.equilibrium(model, sea=Regular) takes the drift of the model's own
    motions (the database has Kochin functions and no mean_drift) and the surge offset is
    F_x a²/k of model_mean_drift's table at the wave's frequency and heading (1e-9: Newton's
    tolerance); info says which drift; without the sea the layout stays at rest."""
    k = 5.0e3
    model = _moored_pair(k)
    rest, _ = mfm.equilibrium(model)
    a, w = 0.1, 2.2
    q0, info = mfm.equilibrium(model, sea=hydro.Regular(height=2 * a, period=2 * math.pi / w))
    D = mfm.mean_drift(model).sel(omega=w, wave_direction=0.0, influenced_dof="A__Surge")
    i = model.coordinates.index("A.surge")
    assert q0[i] - rest[i] == pytest.approx(float(D) * a * a / k, rel=1e-9)
    assert abs(float(D)) * a * a / k > 1e-3                      # a visible offset
    assert "own motions" in info["mean_drift"] and "moored pair" in info["mean_drift"]


def test_errors():
    """A database without Kochin functions: model_mean_drift says how to make them; one of the two
    variables alone, or directions not uniform, are refused by the database check (every reader);
    [hydro.bem] drift accepts "kochin"."""
    from hydro.database import from_capytaine, validate
    from mfm.io.bemgen import DRIFTS

    sphere = mfm.load(Path(__file__).resolve().parents[1] / "configs" / "sphere.toml")
    with pytest.raises(ValueError, match='drift = "kochin"'):
        mfm.mean_drift(sphere)
    ds, _ = _check()
    db = from_capytaine(ds)
    with pytest.raises(ValueError, match="'kochin_diffraction' without 'kochin_radiation'"):
        validate(db.drop_vars("kochin_radiation"), warn=False)
    bent = db.assign_coords(theta=db["theta"].values ** 1.01)
    with pytest.raises(ValueError, match="uniform directions"):
        validate(bent, warn=False)
    assert "kochin" in DRIFTS


def test_wu_yuan_severe_sea_mean_offset_and_line_tensions():
    """Wu & Yuan model 1 with its hinges locked (the seed's severe sea, H 8.1 m, T 11.4 s, head
    seas), its database's Kochin functions (configs/wu_yuan_m1_drift.toml): the mean drift of the
    moored platform's own motions pushes it down-wave (+x); at the mean position the lines' total
    horizontal pull has changed by minus the drift force (the horizontal balance: nothing else
    acts horizontally at rest; 1e-6 of the force, Newton's tolerance), the up-wave lines (anchors
    at −x) take more tension and the down-wave ones less; mfm.studies.wu_yuan.mean_offset names the
    drift it took."""
    from mfm.studies.wu_yuan import mean_offset

    ds = mean_offset(1, locked=True)
    F = ds["drift_force"].values
    assert F[0] > 0 and abs(F[1]) < 1e-6 * F[0]           # head seas, a layout symmetric in y
    surge = ds["q_mean"].sel(coordinate="platform.surge") - ds["q_rest"].sel(
        coordinate="platform.surge")
    assert float(surge) > 0
    change = ds["mooring_force_mean"].values - ds["mooring_force_rest"].values
    np.testing.assert_allclose(change, -F[:2], rtol=0, atol=1e-6 * F[0])
    print(f"drift {F[0] / 1e3:.1f} kN, offset {float(surge):.3f} m; tensions "
          f"{np.round(ds['tension_rest'].values / 1e3, 1)} -> "
          f"{np.round(ds['tension_mean'].values / 1e3, 1)} kN")
    dT = ds["tension_mean"].values - ds["tension_rest"].values
    assert dT.max() > 0 > dT.min()
    assert "own motions" in ds.attrs["mean_drift"]
