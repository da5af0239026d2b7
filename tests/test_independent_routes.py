"""Results that the suite had checked only against the code itself (issue 35 item 7), each given
an independent route here:

(a) derived statistics — q_rms and mean power of the spectral level by Parseval over the
    synthesised series and by a hand sum of the RAOs of mfm.frequency_response; Hs of a
    tabulated spectrum by its closed form; Welch's S_ηη by the variance of the signal;
(b) readers and tables off the shipped shapes — a WAMIT run with ULEN = 2, two bodies and two
    headings written here, its numbers scaled by hand from the manual's definitions; NEMOH's
    radiation zones read back entry by entry; NEMOH's excitation with several headings;
    capytaine hydrostatics of two bodies of different mass; heading interpolation across the
    ±π cut; a rectangular power matrix in cases out of order;
(c) refinements — the parabolic refinement of min |det Λ| against the analytic root and the
    vertex of the parabola through log|ω − ω_n| (computed here); largest_stable_dt against RK4's
    closed-form limit 2√2/ω to 1e-9; the equilibrium's Newton to its analytic rest position to
    round-off; the state-space fits' error measured by a direct numpy evaluation of
    C (iωI − A)⁻¹ B against the database.

The mutants these tests kill are listed in tools/mutation_check.py (section "issue 35 item 7").
"""
from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data" / "bemio"
RHO, G = 1000.0, 9.81


# ============================================================================ (b) readers, tables
# ---------------------------------------------------------------- WAMIT: ULEN = 2, two bodies
_OUT = """ WAMIT synthetic run written by tests/test_independent_routes.py

 Gravity:     9.81000                Length scale:        {L:.5f}
 Water depth:        infinite

 BODY PARAMETERS:

 Body number: N= 1       Total panels:  100    Waterline panels:  10

 XBODY =    0.0000 YBODY =    0.0000 ZBODY =   -0.5000 PHIBODY =   0.0
 Volumes (VOLX,VOLY,VOLZ):           2.00000      2.00000      2.00000
 Center of Buoyancy (Xb,Yb,Zb):     0.000000     0.000000    -0.250000
 Center of Gravity  (Xg,Yg,Zg):     0.000000     0.000000     0.000000

 Body number: N= 2       Total panels:  100    Waterline panels:  10

 XBODY =    3.0000 YBODY =    0.0000 ZBODY =   -1.0000 PHIBODY =   0.0
 Volumes (VOLX,VOLY,VOLZ):           3.00000      3.00000      3.00000
 Center of Buoyancy (Xb,Yb,Zb):     0.000000     0.000000    -0.400000
 Center of Gravity  (Xg,Yg,Zg):     0.000000     0.000000    -0.100000

                            Output from  WAMIT
"""


def _abar(i, j):          # nondimensional Ā_ij, B̄_ij of the synthetic .1 (i, j 1-based modes)
    return 1.0 + 0.1 * i + 0.01 * j, 0.5 + 0.003 * i * j


def _xbar(T, beta, i):     # nondimensional X̄_i (WAMIT's e^{+iωt}) of the synthetic .3
    return complex(0.2 * i + 0.01 * T, 0.05 * i - 0.001 * beta)


def _cbar(i, j):
    return 0.7 + 0.05 * i + 0.002 * j


@pytest.fixture(scope="module")
def wamit_ulen2(tmp_path_factory):
    """A two-body WAMIT run with ULEN = 2, periods 10 s and 5 s (listed long first), headings 90°
    and 0° (90° first), the nondimensional numbers chosen distinct per entry."""
    d = tmp_path_factory.mktemp("wamit")
    L = 2.0
    (d / "run.out").write_text(_OUT.format(L=L))
    rows1 = [" WAMIT Numeric Output -- Filename  run.1"]
    for T in (0.0, 10.0, 5.0):
        for i in range(1, 13):
            for j in range(1, 13):
                a, b = _abar(i, j)
                rows1.append(f"  {T:.6E} {i:5d} {j:5d}  {a:.6E}" + ("" if T == 0 else f"  {b:.6E}"))
    (d / "run.1").write_text("\n".join(rows1) + "\n")
    rows3 = [" WAMIT Numeric Output -- Filename  run.3"]
    for T in (10.0, 5.0):
        for beta in (90.0, 0.0):
            for i in range(1, 13):
                x = _xbar(T, beta, i)
                rows3.append(f"  {T:.6E}  {beta:.6E} {i:5d}  {abs(x):.6E}  {math.degrees(np.angle(x)):.6E}"
                             f"  {x.real:.6E}  {x.imag:.6E}")
    (d / "run.3").write_text("\n".join(rows3) + "\n")
    rowsh = [" WAMIT -- Force Output File -- run.hst"]
    for i in range(1, 13):
        for j in range(1, 13):
            rowsh.append(f"  {i:5d} {j:5d}   {_cbar(i, j):.6E}")
    (d / "run.hst").write_text("\n".join(rowsh) + "\n")
    from hydro.wamit import read_wamit
    return read_wamit(d / "run", rho=RHO, g=G, body_names=["a", "b"]), L


def test_wamit_ulen_scaling_of_a_second_body_by_hand(wamit_ulen2):
    """The WAMIT manual's dimensional forms written out entry by entry, with the powers of
    ULEN = 2 as literal numbers (k = 3, 4, 5 for A, B; 2, 3 for X; 2, 3, 4 for C): the second
    body's surge (mode 7) is a translation, its roll (mode 10) a rotation — a reader that took
    mode > 3 for a rotation, or the exponents of A for C, is off by a power of 2. The numbers are
    written with 7 significant digits: rtol 1e-6."""
    db, L = wamit_ulen2
    assert L == 2.0
    w = 2 * np.pi / np.array([10.0, 5.0])
    np.testing.assert_allclose(db.omega.values, w, rtol=1e-12)         # sorted ascending
    A, B = db.added_mass.values, db.radiation_damping.values
    # (influenced i, radiating j) 1-based modes → the power of ULEN for A (kg, kg m, kg m²)
    for (i, j, p) in ((7, 7, 8.0), (9, 3, 8.0), (10, 10, 32.0), (10, 3, 16.0), (3, 10, 16.0),
                      (8, 12, 16.0), (12, 11, 32.0), (1, 1, 8.0), (5, 4, 32.0), (4, 9, 16.0)):
        a, b = _abar(i, j)
        for k in range(2):
            assert A[k, i - 1, j - 1] == pytest.approx(RHO * p * a, rel=1e-6), (i, j)
            assert B[k, i - 1, j - 1] == pytest.approx(RHO * w[k] * p * b, rel=1e-6), (i, j)
        assert db.added_mass_inf.values[i - 1, j - 1] == pytest.approx(RHO * p * a, rel=1e-6)
    # excitation: ρ g L² (forces), ρ g L³ (moments), conjugated; headings sorted 0°, 90°
    np.testing.assert_allclose(db.wave_direction.values, [0.0, np.pi / 2])
    X = db.excitation.values
    for i, p in ((7, 4.0), (9, 4.0), (10, 8.0), (11, 8.0), (12, 8.0), (3, 4.0), (5, 8.0)):
        for k, T in enumerate((10.0, 5.0)):
            for h, beta in enumerate((0.0, 90.0)):
                want = RHO * G * p * np.conj(_xbar(T, beta, i))
                assert X[k, h, i - 1] == pytest.approx(want, rel=1e-6), (i, T, beta)
    # hydrostatics: ρ g L² C̄ (33), ρ g L³ (34), ρ g L⁴ (44)
    C = db.hydrostatic_stiffness.values
    for (i, j, p) in ((9, 9, 4.0), (9, 10, 8.0), (10, 10, 16.0), (11, 11, 16.0), (3, 3, 4.0),
                      (4, 5, 16.0)):
        assert C[i - 1, j - 1] == pytest.approx(RHO * G * p * _cbar(i, j), rel=1e-6), (i, j)
    # the water-plane part of body b's 44: minus ρ g V (z_B − z_G), V = 3 L³, z = (−0.4, −0.1) L
    W = db.waterplane_stiffness.values
    want = RHO * G * (16.0 * _cbar(10, 10) - 3.0 * 8.0 * (-0.4 + 0.1) * 2.0)
    assert W[9, 9] == pytest.approx(want, rel=1e-6)
    assert db.displaced_volume.values[1] == pytest.approx(3.0 * 8.0, rel=1e-6)
    np.testing.assert_allclose(db.center_of_buoyancy.values[1], [3.0, 0.0, -1.0 - 0.8], rtol=1e-6)


# ---------------------------------------------------------------- NEMOH: zones read back by hand
NEMOH_RM3 = DATA / "nemoh_v2" / "rm3"


def _tec_zones(path):
    """The numeric rows of each zone of a Tecplot file, read here with nothing of hydro.nemoh:
    [(title, array (rows, columns))]."""
    zones = []
    for line in Path(path).read_text().splitlines():
        s = line.strip()
        if s.lower().startswith("zone"):
            zones.append((s, []))
        elif zones and s and not s.startswith('"') and not s.upper().startswith("VARIABLES"):
            zones[-1][1].append([float(v) for v in s.split()])
    return [(t, np.array(r)) for t, r in zones]


def test_nemoh_radiation_zones_read_back_entry_by_entry():
    """RadiationCoefficients.tec: zone j is the motion of dof j (radiating), columns 1 + 2i and
    2 + 2i the force on dof i (influenced). NEMOH's A is not exactly symmetric (the file's
    A_ij − A_ji reach a few % of the diagonal scale on RM3), so a reader that swapped i and j
    differs from the file; the numbers are the file's to its 7 digits: rtol 1e-12 of the value
    read (both go through float())."""
    from hydro.nemoh import read_nemoh

    db = read_nemoh(NEMOH_RM3, estimate_inf=False)
    zones = _tec_zones(NEMOH_RM3 / "Results" / "RadiationCoefficients.tec")
    n = len(zones)
    assert n == 12
    w_file = zones[0][1][:, 0]
    order = np.argsort(w_file)
    np.testing.assert_allclose(db.omega.values, w_file[order], rtol=1e-12)
    A = np.stack([z[:, 1::2] for _, z in zones], axis=2)[order]    # (ω, influenced i, radiating j)
    B = np.stack([z[:, 2::2] for _, z in zones], axis=2)[order]
    scale = np.sqrt(np.outer(np.abs(A).max(0).diagonal(), np.abs(A).max(0).diagonal()))
    # the test can fail: the file's matrix is not symmetric
    assert np.max(np.abs(A - np.swapaxes(A, 1, 2)) / (scale + 1e-300)) > 1e-3
    np.testing.assert_allclose(db.added_mass.values, A, rtol=1e-12, atol=0)
    np.testing.assert_allclose(db.radiation_damping.values, B, rtol=1e-12, atol=0)


def _nemoh_headings(tmp_path, headings_deg):
    """A copy of the RM3 NEMOH v2 run whose ExcitationForce.tec has one zone per heading: zone k
    is zone 0 of the shipped file with |X| × (1 + k) and arg X + 0.3 k (the FK/diffraction
    split removed: it is optional)."""
    run = tmp_path / "rm3"
    shutil.copytree(NEMOH_RM3, run)
    for f in ("FKForce.tec", "DiffractionForce.tec"):
        (run / "Results" / f).unlink()
    cal = (run / "Nemoh.cal").read_text().splitlines()
    k = next(i for i, ln in enumerate(cal) if "Number of wave directions" in ln)
    cal[k] = f"{len(headings_deg)}\t{headings_deg[0]:.1f}\t{headings_deg[-1]:.1f}\t\t! Number of wave directions, Min and Max (degrees)"
    (run / "Nemoh.cal").write_text("\n".join(cal) + "\n")
    f = run / "Results" / "ExcitationForce.tec"
    lines = f.read_text().splitlines()
    z = next(i for i, ln in enumerate(lines) if ln.strip().lower().startswith("zone"))
    head, body = lines[:z], [ln for ln in lines[z + 1:] if ln.strip()]
    rows = np.array([[float(v) for v in ln.split()] for ln in body])
    out = list(head)
    for kk, beta in enumerate(headings_deg):
        out.append(f'Zone t="Diffraction force - beta = {beta:7.3f} deg",I=    {len(rows)},F=POINT')
        r = rows.copy()
        r[:, 1::2] *= 1.0 + kk
        r[:, 2::2] += 0.3 * kk
        out += ["  " + "  ".join(f"{v:.7E}" for v in row) for row in r]
    f.write_text("\n".join(out) + "\n")
    return run, rows


def test_nemoh_excitation_of_three_headings_by_hand(tmp_path):
    """Three headings (0°, 45°, 90°), each zone of the file a known multiple of the shipped one:
    X[ω, β_k, i] = (1 + k) |X₀| e^{i(arg X₀ + 0.3 k)} at the file's ω (sorted ascending). The
    file holds 8 digits (written here with %.7E): rtol 1e-6."""
    from hydro.nemoh import read_nemoh

    run, rows = _nemoh_headings(tmp_path, [0.0, 45.0, 90.0])
    db = read_nemoh(run, estimate_inf=False)
    np.testing.assert_allclose(db.wave_direction.values, np.radians([0.0, 45.0, 90.0]), rtol=1e-12)
    order = np.argsort(rows[:, 0])
    X0 = (rows[:, 1::2] * np.exp(1j * rows[:, 2::2]))[order]
    for k in range(3):
        want = (1.0 + k) * X0 * np.exp(0.3j * k)
        np.testing.assert_allclose(db.excitation.values[:, k, :], want, rtol=1e-6,
                                   atol=1e-6 * np.abs(X0).max())


# ------------------------------------------------- capytaine: two bodies, rotation centres given
CAPY_RM3 = DATA / "capytaine_2.3.1" / "rm3" / "rm3_hydrodynamics.nc"


def _hydrostatics_dat(path):
    """(z_B, z_G, V) of a NEMOH-format Hydrostatics.dat, read here by position."""
    lines = [ln for ln in Path(path).read_text().splitlines() if ln.strip()]
    # "XF = -1.2927 - XG = -0.7200": the two numbers after the '=' signs
    zf, zg = (float(part.split()[0]) for part in lines[2].split("=")[1:3])
    V = float(lines[3].split("=")[1])
    return zf, zg, V


def test_capytaine_two_bodies_of_different_mass_about_their_rotation_centres(tmp_path):
    """capytaine's rigid-body stiffness about a rotation centre c holds in 44/55
    ρ g V (z_B − z_c) − m g (z_G − z_c) (module docstring of hydro.formats); with c ≠ G that is
    the mass of each body (725.8 t and 886.7 t in RM3's inertia_matrix), at its own centre. The
    water-plane 44 written out by hand from the file: C44 − ρgV(z_B − z_c) + m g (z_G − z_c)
    (x_c = y_c = 0 = x_G, y_G: no transfer of the water-plane moments). The file's numbers and
    the .dat's 5 digits enter both sides alike: rtol 1e-9 (round-off of the subtraction)."""
    import xarray as xr
    from hydro.prepare import open_any_database

    ds = xr.load_dataset(CAPY_RM3)
    d = tmp_path / "capy"
    d.mkdir()
    for f in CAPY_RM3.parent.glob("*.dat"):
        shutil.copyfile(f, d / f.name)
    rc = np.array([[0.0, 0.0, -0.42], [0.0, 0.0, -23.29]])     # 0.3 m above, 2 m below G
    ds["rotation_center"] = (("rc_body", "rc_axis"), rc)
    ds.to_netcdf(d / "hydro.nc")
    db = open_any_database(d / "hydro.nc", names=["float", "spar"])
    np.testing.assert_allclose(db.reference_point.values, rc, rtol=0, atol=0)
    C = ds.hydrostatic_stiffness.transpose("influenced_dof", "radiating_dof").values
    Mi = ds.inertia_matrix.transpose("influenced_dof", "radiating_dof").values
    rho, g = float(ds.rho), float(ds.g)
    assert abs(Mi[0, 0] / Mi[6, 6] - 1) > 0.1          # the bodies differ in mass
    for b in range(2):
        zB, zG, V = _hydrostatics_dat(d / f"Hydrostatics_{b}.dat")
        o, zc, m = 6 * b, rc[b, 2], Mi[6 * b, 6 * b]
        for k in (3, 4):                                # roll, pitch
            want = C[o + k, o + k] - rho * g * V * (zB - zc) + m * g * (zG - zc)
            assert db.waterplane_stiffness.values[o + k, o + k] == pytest.approx(want, rel=1e-9), (b, k)
        assert db.waterplane_stiffness.values[o + 2, o + 2] == pytest.approx(C[o + 2, o + 2], rel=1e-12)


# ---------------------------------------------------------- excitation between distant headings
def _excitation_db(omega, beta, X):
    import xarray as xr

    dofs = [f"b__{m}" for m in ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")]
    return xr.Dataset(
        {"excitation": (("omega", "wave_direction", "influenced_dof"), np.asarray(X, complex))},
        coords={"omega": omega, "wave_direction": beta, "influenced_dof": dofs},
        attrs={"rho": RHO, "g": G, "water_depth": math.inf})


def test_heading_interpolation_takes_the_short_way_across_the_cut():
    """Two headings 0° and 90° whose X are e^{3i} and e^{−3i} (6 rad apart the long way,
    2π − 6 = 0.283 rad the short way, across ±π). Halfway, 45°, the polar interpolation of the
    module docstring gives |X| = 1 and arg X = 3 + ½(2π − 6) = π: X = −1 exactly (+1 by the long
    arc). Frequencies on the grid isolate the heading. Tolerance 1e-12: round-off of exp/angle."""
    from hydro.excitation import excitation_coefficients
    from hydro.waves import Regular

    omega = np.array([0.5, 1.0])
    X = np.empty((2, 2, 6), complex)
    X[:, 0], X[:, 1] = np.exp(3j), np.exp(-3j)
    db = _excitation_db(omega, np.radians([0.0, 90.0]), X)
    for heading, want in ((math.radians(45.0), -1.0), (math.radians(22.5), np.exp(1j * (3 + 0.25 * (2 * np.pi - 6)))),
                          (0.0, np.exp(3j)), (math.radians(90.0), np.exp(-3j))):
        c = Regular(0.1, 2 * np.pi / 1.0, heading=heading).components()
        np.testing.assert_allclose(excitation_coefficients(db, c)[0], np.full(6, want), rtol=0, atol=1e-12)


def test_two_headings_are_not_a_full_circle():
    """A database of 0° and 180° covers half the directions: 270° is outside it (the 2π
    wrap-around is taken only when the headings' spacing covers the circle, which needs three or
    more), an error naming the range — not an interpolation between 180° and 360°."""
    from hydro.excitation import excitation_coefficients
    from hydro.waves import Regular

    omega = np.array([0.5, 1.0])
    X = np.ones((2, 2, 6), complex)
    X[:, 1] = 2.0
    db = _excitation_db(omega, np.radians([0.0, 180.0]), X)
    c = Regular(0.1, 2 * np.pi, heading=math.radians(270.0)).components()
    with pytest.raises(ValueError, match="outside the database's wave_direction range"):
        excitation_coefficients(db, c)
    # inside: linear in |X| (1 → 2), the phase 0
    c = Regular(0.1, 2 * np.pi, heading=math.radians(45.0)).components()
    np.testing.assert_allclose(excitation_coefficients(db, c)[0], np.full(6, 1.25), rtol=1e-14)


# ================================================================== (a) derived statistics
def test_user_spectrum_hs_is_the_area_of_its_table():
    """A triangle S = 0, 2, 0 m² s/rad at ω = 0.5, 1, 2 rad/s (uneven spacing): the table is
    linear between its points (UserSpectrum interpolates linearly), so ∫S dω is the triangle's
    area ½ · 1.5 · 2 = 1.5 m² exactly and Hs = 4√1.5 (rectangles would give 1.0 or 0.5).
    Tolerance 1e-14: two additions."""
    from hydro.waves import UserSpectrum

    sea = UserSpectrum(omega=np.array([0.5, 1.0, 2.0]), S=np.array([0.0, 2.0, 0.0]))
    assert sea.hs == pytest.approx(4.0 * math.sqrt(1.5), rel=1e-14)
    # and a ramp up to a plateau: 0.5 · 1 · 1 + 1 · 2 = 2.5
    sea = UserSpectrum(omega=np.array([1.0, 2.0, 4.0]), S=np.array([0.0, 1.0, 1.0]))
    assert sea.hs == pytest.approx(4.0 * math.sqrt(2.5), rel=1e-14)


def test_welch_elevation_spectrum_integrates_to_its_variance():
    """spectral_rao's S_ηη is per rad/s (module docstring of mfm.studies.wec): ∫S_ηη dω is the
    variance of η (Parseval). η: three harmonics of amplitudes 1, 0.5, 0.3 m (variance
    ½ Σ a² = 0.67 m²) over 600 s at 0.05 s. Welch with 40 s Hann segments and half overlap
    keeps the power of a harmonic with many cycles per segment to within the windowed
    segment's end effects, O(1/(ω T_seg)) < 0.3 % here; the per-Hz spectrum is 2π larger."""
    from mfm.studies import wec

    dt = 0.05
    t = np.arange(0.0, 600.0, dt)
    amps, omegas, phases = (1.0, 0.5, 0.3), (0.9, 1.7, 2.6), (0.3, 1.1, 2.0)
    eta = sum(a * np.cos(w * t + p) for a, w, p in zip(amps, omegas, phases))
    om, rao, S_ee = wec.spectral_rao(t, 0.5 * eta, eta, segment=40.0)
    assert np.trapezoid(S_ee, om) == pytest.approx(0.5 * sum(a * a for a in amps), rel=0.01)
    np.testing.assert_allclose(rao[(om > 0.7) & (om < 2.8) & (S_ee > 1e-3 * S_ee.max())], 0.5, rtol=1e-9)


# ========================================================================= (c) refinements
# the undamped mass–spring of test_frequency_extras' minimum of |det Λ(ω)| (damping 0)
from test_frequency_extras import MSD  # noqa: E402


def test_min_det_refinement_against_the_analytic_root(tmp_path):
    """min |det Λ(ω)| of an undamped mass–spring (Λ = k − m ω², root ω_n = √(k/m) = 2 rad/s) on
    grids of step h = 0.01 rad/s placed so that the root lies δ h past the nearest grid point.
    Near the root |det| = m |ω − ω_n| (ω + ω_n) ≈ 2 m ω_n |ω − ω_n|: the parabola through
    log|det| at the three points nearest the root has its vertex at
        ½ h ln((1 + δ)/(1 − δ)) / ln((1 − δ²)/δ²)    past the nearest point
    (computed here by hand from that V shape; the factor ω + ω_n changes the slopes by h/(2 ω_n),
    2.5e-3: 1e-4 h on the vertex). δ = 0.3: 0.134 h, an error of 0.166 h — nearer than the grid
    point (0.3 h) and than a vertex on the wrong side (0.434 h). Tolerance 0.01 h."""
    import mfm

    m, k = 3.0, 12.0
    wn = math.sqrt(k / m)
    p = tmp_path / "ms.toml"
    p.write_text(MSD.format(m=m, k=k, c=0.0))
    model = mfm.load(p)
    h = 0.01
    for delta in (0.3, -0.3, 0.2):
        grid = wn - delta * h + h * np.arange(-40, 41)      # grid[40] = ω_n − δ h
        nf = mfm.natural_frequencies(model, omega_grid=grid)
        (got,) = nf.min_det.values
        d = abs(delta)
        vertex = 0.5 * math.log((1 + d) / (1 - d)) / math.log((1 - d * d) / (d * d))
        want = grid[40] + math.copysign(vertex, delta) * h
        assert got == pytest.approx(want, abs=0.01 * h), (delta, got - wn)
        assert abs(got - wn) < abs(grid[40] - wn) - 0.05 * h     # the refinement helps (≥ 0.06 h)


def test_largest_stable_dt_of_rk4_to_its_closed_form():
    """RK4's amplification on ẍ = −ω² x is R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 at z = ±iωdt:
    |R(iy)|² = 1 − y⁶/72 + y⁸/576, which is 1 again at y = √8 = 2√2 (exactly: y² = 8). So the
    largest stable dt is 2√2/ω. The bisection's own tolerance: it stops at 1e-12 relative, and
    ρ > 1 + tol (1e-9) is met d|R|/dy = (2√2)⁵/72 ≈ 2.5 past the limit: 4e-10 in y. Tolerance
    1e-9 relative (the grid of 64 steps alone would give 3 %, a 20-halving bisection 1e-7)."""
    from mfm.studies import stability as st

    for w in (1.0, 3.7):
        dt = st.largest_stable_dt("rk4", 1.0, 0.0, w * w)
        assert dt == pytest.approx(2 * math.sqrt(2) / w, rel=1e-9)


def test_equilibrium_newton_to_the_analytic_angle():
    """A pendulum (point mass 2 kg on a 1.5 m arm) under a hinge torque τ = 0.8 m g L rests at
    sin θ = τ/(m g L): θ = asin 0.8. From θ = 0 Newton's errors go 0.13, 1e-2, 8e-5, 4e-9, 1e-17:
    the equilibrium's stop at a residual below 1e-10 of the weight means |θ − θ*| ≤ 1e-10 m g /
    (m g L cos θ*) = 1.1e-10 rad (a stop at 1e-6 of it would leave the 4e-9 of the fourth step)."""
    import jax.numpy as jnp

    import mfm
    from mfm.io.config import parse_config
    from mfm.loads import JointLoad

    m, L, g = 2.0, 1.5, 9.81
    bodies = [{"name": "bob", "mass": m, "com": [0, 0, -L], "principal_inertia": [1e-6] * 3,
               "joint": {"type": "revolute", "axis": [0, 1, 0], "point": [0, 0, 0]}}]
    model = mfm.compile_tree(parse_config({"model": {"gravity": g}, "bodies": bodies})[1],
                             name="pendulum", gravity=g)
    q0, info = mfm.equilibrium(model, loads=(JointLoad(values=jnp.asarray([0.8 * m * g * L])),))
    # hanging from the hinge, the torque balances m g L sin θ (either sense of the axis: |θ|)
    assert abs(float(q0[0])) == pytest.approx(math.asin(0.8), abs=2e-10), (info, float(q0[0]))
    assert info["iterations"] >= 4              # the test needs Newton's steps: it starts at 0


# ----------------------------------------------------- a power matrix of 2 Hs × 3 Tp, out of order
def test_power_matrix_of_a_rectangular_sweep_in_any_case_order():
    """plot_batch's power matrix: Hs (rows) × Tp (columns), each cell the mean over the kept steps
    of the case with that (Hs, Tp), summed over the PTOs. Cases here run Tp-major and shuffled,
    2 Hs × 3 Tp, P = 100 Hs + Tp + 0.5 (two PTOs of ½ and ½ + the rest): the cell (i, j) must be
    100 H_i + T_j + 0.5 exactly whatever the case order (a reshape of the case list would put
    them in the wrong cells)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import xarray as xr

    from mfm.io.plotting import plot_batch

    H, T = np.array([1.0, 2.0]), np.array([6.0, 8.0, 10.0])
    cases = [(h, t) for t in T for h in H]
    cases = [cases[k] for k in (3, 0, 5, 1, 4, 2)]
    hs = np.array([c[0] for c in cases])
    tp = np.array([c[1] for c in cases])
    P = 100 * hs + tp
    n_step = 10
    power = np.empty((len(cases), n_step, 2))
    power[:, :, 0] = 0.5
    power[:, :, 1] = P[:, None]
    power[:, : n_step // 2, 1] = -1e6            # the discarded first half
    ds = xr.Dataset({"pto_power": (("case", "step", "pto"), power)},
                    coords={"hs": ("case", hs), "tp": ("case", tp), "pto": ["a", "b"]})
    fig = plot_batch(ds, discard=0.5)
    try:
        M = np.asarray(fig.axes[0].collections[0].get_array()).reshape(len(H), len(T))
    finally:
        plt.close(fig)
    np.testing.assert_array_equal(M, 100 * H[:, None] + T[None, :] + 0.5)


def test_reduce_errors_are_against_the_total_power():
    """reduce's errors (mfm.studies.fidelity, docstring of reduce): each PTO's mean power against
    the total mean power of the reference, each standard deviation against its own. By hand:
    PTO a 1.0 → 1.1 W and b 10 → 9 W of a total 11 W: 0.1/11 and 1/11; std 0.4 → 0.5: 0.25."""
    from mfm.studies.fidelity import _errors

    ref = {"pto_power[a]": 1.0, "pto_power[b]": 10.0, "std[x]": 0.4}
    got = _errors({"pto_power[a]": 1.1, "pto_power[b]": 9.0, "std[x]": 0.5}, ref)
    assert got == pytest.approx({"pto_power[a]": 0.1 / 11, "pto_power[b]": 1.0 / 11, "std[x]": 0.25},
                                rel=1e-12)
