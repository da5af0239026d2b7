"""Excitation time series (hydro.excitation) against hand evaluations on synthetic databases."""
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import hydro
import hydro.waves as waves
from hydro.excitation import excitation_coefficients, excitation_dataarray, excitation_time_series
from hydro.waves import Jonswap, Regular, Spreading, WaveComponents, ramp

MODES = ["Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"]
DOFS = [f"float__{m}" for m in MODES] + [f"spar__{m}" for m in MODES]
RNG = np.random.default_rng(123)
# per dof: |X| = (c0 + c1 ω)(1 + d1 β), arg X = p0 + p1 ω + q1 β. |X| bilinear and arg X linear in
# (ω, β): the amplitude/phase interpolation of hydro.excitation reproduces it exactly between
# grid points, so every comparison below is a hand evaluation with rounding-level tolerance.
C0 = RNG.uniform(1e5, 1e6, 12)
C1 = RNG.uniform(-5e4, 5e4, 12)
D1 = RNG.uniform(-0.2, 0.2, 12)
P0 = RNG.uniform(-math.pi, math.pi, 12)
P1 = RNG.uniform(-2.0, 2.0, 12)  # rad per rad/s: 0.2 rad per 0.1 rad/s grid step (< π)
Q1 = RNG.uniform(-1.0, 1.0, 12)


def analytic_X(omega, beta):
    """X(ω, β) complex (..., 12) for broadcastable ω, β."""
    w = np.asarray(omega, float)[..., None]
    b = np.asarray(beta, float)[..., None]
    return (C0 + C1 * w) * (1.0 + D1 * b) * np.exp(1j * (P0 + P1 * w + Q1 * b))


def make_db(omega, beta, X=None, water_depth=math.inf):
    """A tiny database with the project schema's excitation(omega, wave_direction, influenced_dof)."""
    omega, beta = np.asarray(omega, float), np.asarray(beta, float)
    if X is None:
        X = analytic_X(omega[:, None], beta[None, :])
    return xr.Dataset(
        {"excitation": (("omega", "wave_direction", "influenced_dof"), X.astype(np.complex128))},
        coords={"omega": omega, "wave_direction": beta, "influenced_dof": DOFS,
                "radiating_dof": DOFS, "body": ["float", "spar"], "axis": ["x", "y", "z"]},
        attrs={"rho": 1025.0, "g": 9.81, "water_depth": water_depth, "convention": "exp(-i omega t)",
               "source": "test synthetic"},
    )


OMEGA = np.arange(0.2, 3.01, 0.1)
BETA = np.deg2rad(np.arange(-90.0, 90.1, 10.0))


def test_regular_wave_exact():
    db = make_db(OMEGA, BETA)
    t = np.linspace(0.0, 30.0, 301)
    for T, phi, beta in [(2 * math.pi / 1.0, 0.0, 0.0), (7.3, 0.0, 0.0), (5.1, 0.7, math.radians(23.0))]:
        wave = Regular(2.5, T, heading=beta, phase=phi)
        a, w = 1.25, 2 * math.pi / T
        X = analytic_X(w, beta)
        F = excitation_time_series(db, wave.components(), t)
        hand = a * np.abs(X) * np.cos(w * t[:, None] - np.angle(X) - phi)
        np.testing.assert_allclose(F, hand, rtol=0, atol=1e-9 * a * np.abs(X).max())


def test_heading_interpolation_linear_between_two_headings():
    b0, b1 = 0.0, math.radians(40.0)
    db = make_db(OMEGA, [b0, b1])
    w = 1.0  # on the grid: isolates the heading interpolation
    Xa, Xb = analytic_X(w, b0), analytic_X(w, b1)
    for s in [0.0, 0.25, 0.5, 0.9, 1.0]:
        beta = b0 + s * (b1 - b0)
        c = Regular(1.0, 2 * math.pi / w, heading=beta).components()
        X = excitation_coefficients(db, c)[0]
        # |X| and arg X linear in β between the two database headings
        np.testing.assert_allclose(np.abs(X), (1 - s) * np.abs(Xa) + s * np.abs(Xb), rtol=1e-12)
        dphi = np.angle(Xb / Xa)
        np.testing.assert_allclose(np.angle(X / Xa), s * dphi, atol=1e-12)
    # a heading given as β + 2π maps into the range
    c = Regular(1.0, 2 * math.pi / w, heading=b1 / 2 + 2 * math.pi).components()
    np.testing.assert_allclose(excitation_coefficients(db, c)[0], analytic_X(w, b1 / 2), rtol=1e-12)


def test_periodic_heading_wraps_around():
    beta = np.deg2rad(np.arange(0.0, 360.0, 30.0))
    X = analytic_X(OMEGA[:, None], np.cos(beta)[None, :])  # any values; periodic in β
    db = make_db(OMEGA, beta, X=X)
    w = OMEGA[7]
    x330, x0 = X[7, 11], X[7, 0]
    for heading in [math.radians(345.0), math.radians(-15.0)]:
        got = excitation_coefficients(db, Regular(1.0, 2 * math.pi / w, heading=heading).components())[0]
        hand = 0.5 * (np.abs(x330) + np.abs(x0)) * np.exp(1j * (np.angle(x330) + 0.5 * np.angle(x0 / x330)))
        np.testing.assert_allclose(got, hand, rtol=1e-12)
    # a database with a duplicated end (−180° and 180°) is periodic too
    beta2 = np.deg2rad(np.arange(-180.0, 180.1, 45.0))
    db2 = make_db(OMEGA, beta2, X=analytic_X(OMEGA[:, None], np.sin(beta2)[None, :]))
    got = excitation_coefficients(db2, Regular(1.0, 2 * math.pi / w, heading=math.radians(170.0)).components())[0]
    assert np.all(np.isfinite(got))


def test_irregular_spread_sea_equals_hand_sum():
    db = make_db(OMEGA, BETA)
    sea = Jonswap(hs=2.0, tp=6.0, n_components=80, omega_range=(0.3, 2.9), seed=9, heading=0.2,
                  spreading=Spreading(20.0))
    c = sea.components()
    assert np.ptp(c.heading) > 0.3
    t = np.linspace(0.0, 100.0, 501)
    F = excitation_time_series(db, c, t)
    X = analytic_X(c.omega, c.heading)  # (n, 12), exact at off-grid ω and β
    hand = np.zeros_like(F)
    for j in range(len(c)):  # independent loop form of Re Σ a e^{iφ} X e^{−iωt}
        hand += c.amplitude[j] * np.abs(X[j]) * np.cos(c.omega[j] * t[:, None] - np.angle(X[j]) - c.phase[j])
    scale = np.abs(hand).max()
    np.testing.assert_allclose(F, hand, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(excitation_coefficients(db, c), X, rtol=1e-11)

    # ramp, dof selection, chunking and the xarray form agree with the plain result
    Fr = excitation_time_series(db, c, t, ramp_duration=20.0, dofs=["spar__Heave", "float__Pitch"])
    np.testing.assert_allclose(Fr, ramp(t, 20.0)[:, None] * F[:, [8, 4]], rtol=0, atol=1e-12 * scale)
    da = excitation_dataarray(db, c, t, dofs=["spar__Heave"])
    assert da.dims == ("time", "influenced_dof") and da.shape == (501, 1)
    np.testing.assert_allclose(da.sel(influenced_dof="spar__Heave").values, F[:, 8], atol=1e-12 * scale)
    old = waves._CHUNK_ENTRIES
    try:
        waves._CHUNK_ENTRIES = 500  # 6 time steps per chunk
        np.testing.assert_allclose(excitation_time_series(db, c, t), F, rtol=0, atol=1e-12 * scale)
    finally:
        waves._CHUNK_ENTRIES = old


def test_split_complex_storage_is_merged():
    db = make_db(OMEGA, BETA)
    ex = db["excitation"]
    split = xr.concat([ex.real, ex.imag], dim=xr.DataArray(["re", "im"], dims="complex", name="complex"))
    db2 = db.drop_vars("excitation").assign(excitation=split.transpose("omega", "complex", "wave_direction", "influenced_dof"))
    c = Jonswap(hs=1.0, tp=6.0, n_components=20, omega_range=(0.3, 2.0)).components()
    np.testing.assert_array_equal(excitation_coefficients(db2, c), excitation_coefficients(db, c))


def test_frequency_outside_grid():
    db = make_db(OMEGA, BETA)
    with pytest.raises(ValueError, match=r"frequency 4 rad/s.*\[0\.2, 3\] rad/s"):
        # 0.1 m: below breaking at that period (0.55 m), so the frequency is what is refused
        excitation_coefficients(db, Regular(0.1, 2 * math.pi / 4.0).components())
    # a component with negligible energy outside the grid is dropped with a warning
    comps = WaveComponents(omega=[1.0, 1.5, 3.5], amplitude=[1.0, 0.5, 1e-3], phase=[0.0, 1.0, 2.0],
                           heading=[0.0, 0.0, 0.0], wavenumber=[0.1, 0.23, 1.25])
    with pytest.warns(UserWarning, match=r"dropped 1 wave component.*fraction 8e-07"):
        X = excitation_coefficients(db, comps)
    np.testing.assert_array_equal(X[2], 0.0)
    np.testing.assert_allclose(X[:2], analytic_X(np.array([1.0, 1.5]), 0.0), rtol=1e-12)
    # ... but not when the energy fraction exceeds the tolerance
    with pytest.raises(ValueError, match="3.5 rad/s"):
        excitation_coefficients(db, comps, drop_energy_fraction=1e-7)


def test_frequency_at_a_rounded_grid_end():
    """A config lists its BEM frequencies with six decimals (2π/5 s as 0.523599): 2π/5 itself lies
    4e-7 beyond that end and is read as the end (GRID_RTOL = 1e-6); 2e-6 beyond is refused."""
    db = make_db(np.array([0.2, 1.0, 2 * math.pi / 5.0]).round(6), BETA)
    hi = float(db.omega[-1])
    X = excitation_coefficients(db, Regular(1.0, 5.0).components())
    np.testing.assert_allclose(X[0], excitation_coefficients(db, Regular(1.0, 2 * math.pi / hi).components())[0],
                               rtol=1e-12)
    with pytest.raises(ValueError, match="outside the database's omega grid"):
        excitation_coefficients(db, Regular(1.0, 2 * math.pi / (hi * (1 + 2e-6))).components())


def test_heading_outside_range():
    db = make_db(OMEGA, np.deg2rad([0.0, 20.0, 40.0]))
    with pytest.raises(ValueError, match=r"heading 1\.5708 rad \(90°\).*\[0, 0\.698132\] rad"):
        excitation_coefficients(db, Regular(1.0, 6.0, heading=math.pi / 2).components())
    with pytest.raises(ValueError, match="heading"):
        excitation_coefficients(db, Regular(1.0, 6.0, heading=-0.01).components())
    # single-heading database: only that heading (mod 2π) is accepted
    db1 = make_db(OMEGA, [0.0])
    ok = excitation_coefficients(db1, Regular(1.0, 6.0, heading=2 * math.pi).components())
    np.testing.assert_allclose(ok[0], analytic_X(2 * math.pi / 6.0, 0.0), rtol=1e-12)
    with pytest.raises(ValueError, match="heading"):
        excitation_coefficients(db1, Regular(1.0, 6.0, heading=0.1).components())


def test_argument_errors_and_depth_warning():
    db = make_db(OMEGA, BETA)
    c = Regular(1.0, 6.0).components()
    with pytest.raises(ValueError, match="not in the database's influenced_dof"):
        excitation_time_series(db, c, [0.0, 1.0], dofs=["float__Heav"])
    with pytest.raises(TypeError, match="components"):
        excitation_time_series(db, Regular(1.0, 6.0), [0.0])
    with pytest.raises(KeyError, match="excitation"):
        excitation_coefficients(db.drop_vars("excitation"), c)
    with pytest.warns(UserWarning, match="water_depth"):
        excitation_coefficients(make_db(OMEGA, BETA, water_depth=30.0), c)


RM3 = Path(hydro.__file__).parent / "data" / "rm3"


def test_rm3_regular_wave_against_raw_wamit_file():
    from hydro.wamit import read_wamit

    db = read_wamit(RM3 / "rm3", body_names=["float", "spar"])
    rho, g = db.attrs["rho"], db.attrs["g"]
    # hand evaluation from the raw .3 rows: period, heading, i, |X̄|, phase (deg), Re, Im, in
    # WAMIT's e^{+iωt} convention: F_i(t) = ρ g a L^m |X̄_i| cos(ωt + phase_i) (ULEN = 1)
    raw = np.loadtxt(RM3 / "rm3.3", skiprows=1)
    raw_omega = 2 * np.pi / raw[:, 0]
    t = np.linspace(0.0, 40.0, 401)
    H = 2.5
    for T in [8.0, 2 * np.pi / 0.8]:  # between grid points (0.78, 0.80 rad/s), and on one
        w = 2 * np.pi / T
        wgrid = np.unique(raw_omega)
        lo, hi = wgrid[wgrid <= w + 1e-9].max(), wgrid[wgrid >= w - 1e-9].min()
        s = 0.0 if hi == lo else (w - lo) / (hi - lo)
        F = excitation_time_series(db, Regular(H, T).components(), t)
        for i in range(1, 13):
            r0 = raw[(np.abs(raw_omega - lo) < 1e-12) & (raw[:, 2] == i)][0]
            r1 = raw[(np.abs(raw_omega - hi) < 1e-12) & (raw[:, 2] == i)][0]
            mod = (1 - s) * r0[3] + s * r1[3]
            pha = np.deg2rad(r0[4] + s * ((r1[4] - r0[4] + 180.0) % 360.0 - 180.0))
            hand = rho * g * (H / 2) * mod * np.cos(w * t + pha)
            scale = rho * g * (H / 2) * max(r0[3], r1[3])
            # rounding of the 7-digit file values and of ω = 2π/period: 1e-6 of the amplitude
            np.testing.assert_allclose(F[:, i - 1], hand, rtol=0, atol=1e-6 * scale + 1e-9, err_msg=f"mode {i}")


def test_polar_form_equals_the_two_step_interpolation_on_any_table():
    """ExcitationTable interpolates from each ω interval's polar form made once and steps in β
    from the polar values themselves; the definition (module docstring) is _interp_polar in ω at
    both headings, then in β, through complex values. On a table of random X (phases over the
    whole circle, zeros included, several headings) and random components the two agree to the
    round trip through complex numbers (a few ε of |X|): 1e-13 of max|X|."""
    from hydro.excitation import ExcitationTable, _bracket, _interp_polar

    rng = np.random.default_rng(7)
    X = (rng.uniform(0.0, 1e6, (len(OMEGA), len(BETA), 12))
         * np.exp(1j * rng.uniform(-math.pi, math.pi, (len(OMEGA), len(BETA), 12))))
    X[3, 2, :4] = 0.0                                   # a zero end takes the other's phase
    db = make_db(OMEGA, BETA, X=X)
    comps = WaveComponents(omega=rng.uniform(0.2, 3.0, 400), amplitude=np.ones(400),
                           phase=np.zeros(400), heading=rng.uniform(-1.5, 1.5, 400),
                           wavenumber=np.ones(400))
    got = ExcitationTable(db).coefficients(comps)
    i0, i1, sw = _bracket(OMEGA, comps.omega)
    k0, k1, sb = _bracket(BETA, comps.heading)
    y0 = _interp_polar(X[i0, k0], X[i1, k0], sw[:, None])
    y1 = _interp_polar(X[i0, k1], X[i1, k1], sw[:, None])
    want = _interp_polar(y0, y1, sb[:, None])
    assert np.abs(got - want).max() <= 1e-13 * np.abs(X).max()
