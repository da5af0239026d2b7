"""The common-pole state-space fit (hydro.statespace, pole_sharing="common"): passive and within its
error, checked independently of the fit's own report; the spectral-clipping passivity enforcement
on a model made non-passive on purpose.

Independent references: the database's own A(ω), B(ω) (M4 111, capytaine); the Hermitian part of
the fitted impedance on a grid 6× denser than (and beyond) the enforcement grid; the realisation
C (iωI − A)⁻¹ B by a dense solve. Fit times are in benchmarks/fit_speed.py (no timed assertion).
"""
from pathlib import Path

import numpy as np
import pytest

import mfm
from hydro import passivity as PV
from hydro import statespace as S
from hydro import vectorfit as VF

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


@pytest.fixture(scope="module")
def m111():
    m = mfm.load(CONFIGS / "m4_111.toml")
    return m, m.hydro.state_space()            # the default fit: common poles, order "auto"


def _hermitian_min(Z, idx, d):
    Zk = Z[:, idx][:, :, idx] / np.outer(d, d)
    return np.linalg.eigvalsh(0.5 * (Zk + np.conj(np.swapaxes(Zk, 1, 2))))[:, 0]


def test_common_fit_is_passive_and_within_its_error(m111):
    m, ss = m111
    rep = ss.report
    assert rep["pole_sharing"] == "common" and rep["stable"]
    db = m.hydro.database()
    dims = ("omega", "influenced_dof", "radiating_dof")
    om = db.omega.values
    A = db.added_mass.transpose(*dims).values
    B = db.radiation_damping.transpose(*dims).values
    idx = [list(ss.dofs).index(k) for k in rep["modelled_dofs"]]
    lo, hi = rep["omega_fit"]
    band = (om >= lo) & (om <= hi)
    # the band error recomputed from the database, about the model's A∞ (symmetrized, as the fit
    # is): measured 0.48 % (order 32, 288 states); 1 % is the brief's ≤ 2 % with room for BLAS
    Z = B + 1j * om[:, None, None] * (A - ss.added_mass_inf[None])
    Z = 0.5 * (Z + np.swapaxes(Z, 1, 2))
    blk = np.ix_(np.flatnonzero(band), idx, idx)
    err = np.linalg.norm((ss.impedance(om) - Z)[blk]) / np.linalg.norm(Z[blk])
    assert err == pytest.approx(rep["overall_error"], rel=1e-9)
    assert err < 0.01
    # passive between and beyond the enforcement grid's points: 3,000 linear points to 2 ω_max and
    # a geometric tail to 1000 ω_max (the enforcement grid: 400 linear to ω_max, 60 geometric to
    # 100 ω_max); the Hermitian part normalised by the band maxima of the diagonals, like the
    # report's. Measured min −1e-15 (round-off at ω → ∞); −1e-6 is the report's passivity_tol
    w_max = om[-1]
    w = np.concatenate([np.linspace(0.0, 2 * w_max, 3000), w_max * np.geomspace(2.0, 1000.0, 300)])
    d = np.sqrt(np.abs(np.diagonal(ss.impedance(om[band]), axis1=1, axis2=2)).max(axis=0))[idx]
    assert _hermitian_min(ss.impedance(w), idx, d).min() > -1e-6
    assert rep["passive"] and rep["passivity_min_eig"] > -1e-6
    # the matrices realise the pole–residue model
    for wk in (0.7 * lo, 0.5 * (lo + hi)):
        Zr = ss.C @ np.linalg.solve(1j * wk * np.eye(ss.A.shape[0]) - ss.A, ss.B)
        np.testing.assert_allclose(Zr, ss.impedance([wk])[0], rtol=1e-8, atol=1e-8 * np.abs(Zr).max())


def test_spectral_clipping_makes_a_non_passive_model_passive():
    # 3 × 3 common-pole model: one pair and a real pole per entry; a passive part (positive-real
    # terms with positive semi-definite residue matrices) plus a symmetric perturbation whose
    # Hermitian part is indefinite. Known answer: the enforcement must end with min eig ≥ 0 on its
    # grid and stay close to where it started (a small violation needs a small change)
    rng = np.random.default_rng(3)
    reps = [complex(-0.4, 2.0), complex(-1.5, 0.0)]
    s = np.concatenate([[0.0], 1j * np.linspace(0.2, 6.0, 80)])
    w = np.ones(len(s))
    keys = [(i, j) for i in range(3) for j in range(i, 3)]
    # rank-one residue matrices (⪰ 0, with null directions, as radiation damping of bodies that
    # radiate through few wave modes): any indefinite perturbation then shows
    x, y = rng.normal(size=3), rng.normal(size=3)
    P1, P2 = np.outer(x, x), np.outer(y, y)
    # coefficients of the basis columns: pair (2 real coefficients: Re r, Im r), real pole (1)
    C = np.array([[P1[i, j], 0.0, P2[i, j]] for i, j in keys]).T
    E = rng.normal(size=(3, 3))
    E = 0.5 * (E + E.T)
    C_bad = C + 0.05 * np.array([[E[i, j], 0.3 * E[i, j], -E[i, j]] for i, j in keys]).T
    Pg = VF._basis(1j * PV._passivity_grid(6.0), reps).real

    def lam_min(Cc):
        vals = Pg @ Cc
        H = np.zeros((len(vals), 3, 3))
        for e, (i, j) in enumerate(keys):
            H[:, i, j] = H[:, j, i] = vals[:, e]
        return np.linalg.eigvalsh(H)[:, 0].min()

    assert lam_min(C) >= -1e-12 and lam_min(C_bad) < -0.05        # the premise (measured −0.116)
    C_fix, it = PV._enforce_passivity_common(reps, C_bad, keys, 3, s, w, 6.0)
    # converged (measured 6 iterations; the cap is 40), not stopped at the cap or on stagnation
    assert lam_min(C_fix) >= 0.0 and it < 40
    # the change is smaller than the perturbation (2.2 % of ||C||), not of the model's size:
    # measured 0.6 % of ||C||
    assert np.linalg.norm(C_fix - C_bad) < np.linalg.norm(C_bad - C)


def test_band_target_is_checked(m111):
    m, _ = m111
    with pytest.raises(ValueError, match=r"band_target='database' with pole_sharing='entry'"):
        S.fit_state_space(m.hydro.database(), pole_sharing="entry", band_target="database")
    with pytest.raises(ValueError, match=r"band_target='bem'"):
        S.fit_state_space(m.hydro.database(), pole_sharing="common", band_target="bem")


# ---- the fit's shortcuts against what they replace (issue 34: Wu & Yuan's fit 2.3x faster)

def test_sigma_step_sees_the_functions_only_through_their_gram_matrix(monkeypatch):
    # relaxed VF's σ step on 300 functions against the same step on the 2 n_s rows of the
    # triangle of their QR (_gram_rows: what _vf passes when the functions outnumber them). Known answer: the
    # two are one least-squares problem written twice. Reduced by Householder QR (the step's
    # stable path, forced here), they agree to round-off: measured 2e-14 relative, bound 1e-11.
    # By the Gram matrix's Cholesky factor (the default while well conditioned), each is within
    # that factor's own error of the QR answer: measured 2.7e-9 (all functions) and 4.4e-9 (the
    # triangle), bound 1e-7. Dropping the imaginary parts from the triangle misses by ~1e-1
    rng = np.random.default_rng(7)
    om = np.linspace(0.1, 4.0, 40)
    s = np.concatenate([[0.0], 1j * om])
    true = [complex(-0.3, 1.0), complex(-0.5, 2.5), complex(-0.8, 0.0)]
    Phi_true = VF._basis(s, true)
    F = Phi_true @ rng.normal(size=(Phi_true.shape[1], 300)) \
        + 1e-3 * (rng.normal(size=(len(s), 300)) + 1j * rng.normal(size=(len(s), 300)))
    w = np.concatenate([[10.0], np.where(om < 3.0, 1.0, 0.1)])
    Phi = VF._basis(s, VF._initial_poles(6, 0.1, 4.0))
    Fw = (F * w[:, None]).T
    tri = VF._gram_rows(Fw)
    assert tri.shape == (2 * len(s), len(s))

    def rel(a, b):
        return max(abs(a[0] - b[0]), np.abs(a[1] - b[1]).max()) / np.abs(b[1]).max()

    chol_all, chol_tri = VF._sigma_relaxed(Phi, Fw, w, 300), VF._sigma_relaxed(Phi, tri, w, 300)
    wrong = VF._sigma_relaxed(Phi, np.linalg.qr(Fw.real, mode="r").astype(complex), w, 300)

    def no_cholesky(a):
        raise np.linalg.LinAlgError
    monkeypatch.setattr(np.linalg, "cholesky", no_cholesky)
    qr_all, qr_tri = VF._sigma_relaxed(Phi, Fw, w, 300), VF._sigma_relaxed(Phi, tri, w, 300)
    assert rel(qr_tri, qr_all) < 1e-11
    assert rel(chol_all, qr_all) < 1e-7 and rel(chol_tri, qr_all) < 1e-7
    assert rel(wrong, qr_all) > 1e-3


def test_eigenpairs_under_the_floor_are_those_of_the_full_decomposition():
    # _below (a Cholesky test, then dsyevr on a range) against numpy's full eigh, on matrices of
    # known spectra: clusters of near-null eigenvalues as the passivity enforcement meets them,
    # points with none under their floor, and points with all of them under it. What enters the
    # enforcement is Σ (δ − λ) v vᵀ over those eigenpairs: compared to 1e-12 of the spectrum's
    # size (measured ~1e-15; LAPACK's eigenvectors of a cluster differ, their projector does not)
    rng = np.random.default_rng(11)
    n, n_g = 12, 40
    H = np.empty((n_g, n, n))
    for k in range(n_g):
        Q, _ = np.linalg.qr(rng.normal(size=(n, n)))
        lam = np.sort(np.concatenate([rng.uniform(-1.0, 3.0, n - 4), 1e-9 * rng.normal(size=4)]))
        if k % 5 == 0:
            lam = np.abs(lam) + 0.5                           # nothing under the floor
        if k % 7 == 3:
            lam = lam - 10.0                                  # everything under it
        H[k] = (Q * lam) @ Q.T
        H[k] = 0.5 * (H[k] + H[k].T)
    delta = 1e-3 * np.abs(np.linalg.eigvalsh(H)).max(axis=1)
    at, lam, V = PV._below(H, delta)
    full_l, full_v = np.linalg.eigh(H)
    expect = [k for k in range(n_g) if full_l[k, 0] <= delta[k]]
    assert list(at) == expect and 0 < len(expect) < n_g
    for q, k in enumerate(at):
        lift = np.maximum(delta[k] - lam[q], 0.0)
        full_lift = np.maximum(delta[k] - full_l[k], 0.0)
        dH = (V[q] * lift) @ V[q].T
        full_dH = (full_v[k] * full_lift) @ full_v[k].T
        assert np.abs(dH - full_dH).max() < 1e-12 * np.abs(full_l[k]).max()
        assert lam[q, 0] == pytest.approx(full_l[k, 0], abs=1e-12 * np.abs(full_l[k]).max())


def test_max_real_eig_block_by_block_equals_the_whole_matrix():
    # random block-diagonal matrices of 1 × 1 and 2 × 2 blocks (as _realise makes), some with an
    # entry outside the blocks (which must send them to the whole decomposition): the largest real
    # part equal to numpy's eigvals of the whole matrix to round-off
    rng = np.random.default_rng(5)
    for trial in range(300):
        n = int(rng.integers(1, 12))
        A = np.zeros((n, n))
        k = 0
        while k < n:
            if k + 1 < n and rng.random() < 0.5:
                A[k:k + 2, k:k + 2] = rng.normal(size=(2, 2))
                k += 2
            else:
                A[k, k] = rng.normal()
                k += 1
        if trial % 3 == 0:
            i, j = rng.integers(0, n, 2)
            A[i, j] += rng.normal()
        whole = float(np.max(np.linalg.eigvals(A).real))
        assert S._max_real_eig(A) == pytest.approx(whole, abs=1e-12 * max(1.0, abs(whole)))
    assert S._max_real_eig(np.zeros((0, 0))) == -np.inf


def test_the_fit_says_how_far_it_is(m111):
    # under hydro.phases.reporting the fit names each order it tries and each passivity
    # iteration, in order (what `mfm simulate`'s bar shows while a minute's fit runs)
    from hydro import phases

    m, ss = m111
    said = []
    with phases.reporting(said.append):
        S.fit_state_space(m.hydro.database(), pole_sharing="common", omega_fit=m.hydro.wave_band(),
                          dofs=tuple(m.hydro.dofs[k] for k in m.hydro.moving))
    orders = [w for w in said if "order" in w]
    assert orders[0] == "state-space fit: order 8 (1 of at most 9)"
    # the default fit of M4 111 is order 32 (the 7th): the orders stop there
    assert orders[-1] == "state-space fit: order 32 (7 of at most 9)" and len(orders) == 7
    iterations = [w for w in said if "passivity, iteration" in w]
    assert iterations[0] == "state-space fit: passivity, iteration 1 of at most 40"
    assert len(iterations) == ss.report["passivity_enforcement_iterations"] + 1
    assert said.index(orders[-1]) < said.index(iterations[0])
    assert said[-1].startswith("state-space fit: its realisation and report")
    said.clear()
    S.fit_state_space(m.hydro.database(), pole_sharing="common", order=8)
    assert said == []                                       # nobody listening: nothing said
