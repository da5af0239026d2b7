"""Passivity enforcement of fitted radiation impedances, for :mod:`hydro.statespace`.

A radiation impedance K(iω) is passive when its Hermitian part is positive semi-definite at every
ω (the bodies cannot draw energy from the radiated waves). A fit of BEM data need not be; these
functions perturb the fitted residues, poles fixed, until it is on a grid of ω from 0 to
100 ω_max (:func:`_passivity_grid`): one constraint per violation for per-entry fits
(:func:`_enforce_passivity`), spectral clipping for a common pole set
(:func:`_enforce_passivity_common`). The functions here are the package's internals:
:func:`hydro.statespace.fit_state_space` is the front door.
"""
from __future__ import annotations

import numpy as np

from .phases import say
from .vectorfit import _basis

def _passivity_grid(w_max):
    """ω grid (rad/s) for passivity checks: 0, geometric near 0, linear to ω_max, geometric to
    100 ω_max (Re K̂ of a strictly proper model decays as ω⁻², its sign settles there)."""
    return np.unique(np.concatenate([[0.0], w_max * np.geomspace(1e-5, 1.0, 60),
                                     np.linspace(0.0, w_max, 400), w_max * np.geomspace(1.0, 100.0, 60)]))


def _enforce_passivity(fits, done, nd, dpk, dof_ok, s_fit, w_fit, w_max, max_iter=60,
                       margin=1e-6):
    """Residue perturbation making D Re K̂(iω) D ⪰ 0 on a grid (fits modified in place).

    Each violation (local minimum ω_k of the smallest eigenvalue λ < 0, eigenvector v) adds the linear constraint
    Σ_e v_i v_j (2 − δ_ij) D_i D_j Re Φ_e(iω_k) c_e ≥ margin (kept in later iterations); the
    coefficients are those of least weighted change Σ_e ||√w D_i D_j Φ_e Δc_e||² on the fit grid
    subject to all constraints so far (least-distance programming via NNLS, Lawson & Hanson
    1974, ch. 23).
    Returns the number of iterations used.
    """
    D = 1.0 / np.sqrt(np.where(dof_ok, dpk, np.inf))
    from scipy.linalg import solve_triangular
    from scipy.optimize import nnls     # here, not at the top: ~0.4 s of every import of mfm

    ok = np.asarray(dof_ok, bool)
    grid = _passivity_grid(w_max)
    keys = list(done)
    # entries with one common pole set (pole_sharing="common") share their bases
    basis_of = {}

    def bases(poles):
        if id(poles) not in basis_of:
            Pf = _basis(s_fit, poles) * np.sqrt(w_fit)[:, None]
            basis_of[id(poles)] = (_basis(1j * grid, poles),
                                   np.linalg.inv(np.linalg.qr(np.vstack([Pf.real, Pf.imag]), mode="r")))
        return basis_of[id(poles)]

    phis = [bases(fits[done[k]][0])[0] for k in keys]
    sizes = [ph.shape[1] for ph in phis]
    offs = np.concatenate([[0], np.cumsum(sizes)])
    # metric of least change: the weighted fit residual, ||P_e Δc_e|| with P_e = R_e-factor of
    # the weighted basis on the fit grid (scaled by D_i D_j); Δc = R⁻¹ y with y the minimum-norm
    # solution. R⁻¹ is block diagonal: kept per entry
    Rinv = [bases(fits[done[(i, j)]][0])[1] / (D[i] * D[j]) for (i, j) in keys]
    sls = [slice(offs[e], offs[e + 1]) for e in range(len(keys))]
    c0 = np.concatenate([fits[done[k]][1] for k in keys])
    rows, rhs = [], []
    for it in range(max_iter):
        c = c0.copy()
        if rows:
            # min ||y||, y = R Δc, s.t. M y ≥ δ (M = G R⁻¹): least-distance programming through
            # its dual, min μᵀ(M Mᵀ)μ − 2δᵀμ over μ ≥ 0, y = Mᵀμ; an NNLS in the n_c
            # constraint multipliers (n_c ≪ the 12,000 coefficients of M4 134's common fit)
            G = np.array(rows)
            M = np.concatenate([G[:, sl] @ Ri for sl, Ri in zip(sls, Rinv)], axis=1)
            delta = np.array(rhs) - np.array(rows) @ c0
            sc = np.linalg.norm(M, axis=1)
            Ms, ds = M / sc[:, None], delta / sc
            Gm = Ms @ Ms.T
            L = np.linalg.cholesky(Gm + 1e-12 * np.trace(Gm) / len(Gm) * np.eye(len(Gm)))
            mu, _ = nnls(L.T, solve_triangular(L, ds, lower=True), maxiter=50 * len(Gm))
            y = Ms.T @ mu
            if np.min(Ms @ y - ds) < -1e-6 * max(1.0, float(np.abs(ds).max())):
                raise RuntimeError("passivity enforcement: the constraints are incompatible")
            c = c0 + np.concatenate([Ri @ y[sl] for sl, Ri in zip(sls, Rinv)])
        for e, k in enumerate(keys):
            fits[done[k]] = (fits[done[k]][0], c[offs[e]:offs[e + 1]])
        H = np.zeros((len(grid), nd, nd))
        for e, (i, j) in enumerate(keys):
            val = (phis[e] @ fits[done[(i, j)]][1]).real * D[i] * D[j]
            H[:, i, j] = val
            H[:, j, i] = val
        Hk = H[:, ok][:, :, ok]                 # dropped dofs (e.g. yaw) have no model: H ≡ 0
        lam, Vk = np.linalg.eigh(Hk)
        V = np.zeros((len(grid), nd, Vk.shape[2]))
        V[:, ok, :] = Vk
        neg = lam[:, 0] < -1e-12
        if not neg.any():
            return it
        # new constraints (kept for all later iterations) at the local minima of each violated
        # interval: vᵀ H(ω_k) v ≥ margin for the most negative eigenpair there
        idx = [k for k in np.flatnonzero(neg)
               if (k == 0 or lam[k, 0] <= lam[k - 1, 0]) and (k == len(grid) - 1 or lam[k, 0] <= lam[k + 1, 0])]
        for k in idx:
            for m in (0,):                       # the most negative eigenpair (others follow)
                v = V[k, :, m]
                g = np.zeros(offs[-1])
                for e, (i, j) in enumerate(keys):
                    g[offs[e]:offs[e + 1]] = ((2.0 - (i == j)) * v[i] * v[j] * D[i] * D[j]
                                             * phis[e][k].real)
                rows.append(g)
                rhs.append(margin)
    return max_iter


def _enforce_passivity_common(poles, C, keys, nk, s_fit, w_fit, w_max, max_iter=40, rel=1e-3,
                              rho=100.0):
    """Residue perturbation of a common-pole model until its normalised Hermitian part
    H(ω) = Σ_m Re φ_m(iω) C_m is ⪰ 0 at every point of :func:`_passivity_grid` (C_m: the
    symmetric nk × nk matrix of coefficient m; ``C`` (n_c, n_keys) holds one column per distinct
    entry ``keys`` (i ≤ j, indices into the nk modelled dofs)). Returns (C + ΔC, iterations).

    Each iteration clips the spectrum of H(ω_k) at every grid point from below at
    δ_k = ``rel`` · max|λ(ω_k)| (the least Frobenius change to a matrix ⪰ δ_k I:
    ΔH_k = V diag(max(δ_k − λ, 0)) Vᵀ) and fits that change with the poles fixed:

        min_ΔC  Σ_s ||w_s Φ(s_s) ΔC_e||²  +  ρ Σ_k ||Re Φ(iω_k) ΔC_e − ΔH_k,e||² / max|λ(ω_k)|²

    summed over the entries e (the first term: the change of the weighted fit; the second, each
    grid point relative to its own scale, so the ω⁻² tail counts like the band). One QR of the
    stacked basis serves every iteration and every entry (all share the poles): an iteration is
    an eigendecomposition per grid point and a triangular solve with n_keys right-hand sides.
    Clipping all negative (and near-null) eigenvalues together, not one eigenvector per
    violation, is what makes it converge when many eigenvalues are near zero (M4 134: 24 dofs,
    up to 11 negative eigenvalues at one ω before enforcement; 8 iterations, 0.3 s).
    Stops when min λ ≥ 0 at every grid point; else, when min λ has not risen for 10 iterations
    (data too sparse for the order, e.g. a 10-frequency database: the fit swings between its
    points) or after ``max_iter``, it returns the iterate of largest min λ.

    Only the eigenpairs below δ_k enter ΔH_k, so after the first iteration each grid point is
    decomposed no further than that (:func:`_below`): a Cholesky factor of H − δ_k I says when
    there are none, and LAPACK's dsyevr finds those there are. Wu & Yuan (75 dofs, 518 grid
    points, 40 iterations): 4x less time than full eigendecompositions.
    """
    from scipy.linalg import solve_triangular

    grid = _passivity_grid(w_max)
    Pg = _basis(1j * grid, poles).real                                   # (n_g, n_c)
    Pf = _basis(s_fit, poles) * w_fit[:, None]
    Pf = np.vstack([Pf.real, Pf.imag])
    I, J = np.array([k[0] for k in keys]), np.array([k[1] for k in keys])
    # the keys' places in a flattened nk × nk matrix: one fancy index on one axis, not two
    ij, ji = I * nk + J, J * nk + I

    # one array for every iteration's matrices: each writes the same places, the others stay 0
    # (a new 20 MB array each time was a third of an iteration's time, in page faults)
    H = np.zeros((len(grid), nk * nk))

    def hermitian(Cc):
        vals = Pg @ Cc                                                    # (n_g, n_keys)
        H[:, ij] = vals
        H[:, ji] = vals
        return H.reshape(len(grid), nk, nk)

    Cc = np.array(C, dtype=float)
    lam, V = np.linalg.eigh(hermitian(Cc))
    scale = np.abs(lam).max(axis=1)
    scale = np.maximum(scale, 1e-12 * scale.max() + 1e-300)
    gw = np.sqrt(rho) / scale
    M = np.vstack([Pf, Pg * gw[:, None]])
    sc = np.linalg.norm(M, axis=0)
    sc[sc == 0] = 1.0
    Q, Rm = np.linalg.qr(M / sc)
    Qg = Q[len(Pf):]                                                     # rows of the grid
    delta = rel * scale                                                  # (n_g,) the floors
    at = np.arange(len(grid))                                            # the points to lift
    best = (lam[:, 0].min(), Cc, 0)
    for it in range(max_iter):
        say(f"state-space fit: passivity, iteration {it + 1} of at most {max_iter}")
        if it:
            at, lam, V = _below(hermitian(Cc), delta)
        # the least eigenvalue over the grid: at a point left out it exceeds δ_k > 0, so when it
        # is negative it lies among the points kept
        low = lam[:, 0].min() if len(at) else np.inf
        if low >= 0.0:
            return Cc, it
        if low > best[0]:
            best = (low, Cc, it)
        elif it - best[2] >= 10:
            return best[1], it
        lift = np.maximum(delta[at, None] - lam, 0.0)                    # (n_at, n_eig)
        # V diag(lift) Vᵀ per grid point as a batched product (BLAS): numpy's einsum of the
        # three operands loops in C without it, 8x slower at Wu & Yuan's 90 dofs
        dH = ((V * lift[:, None, :]) @ V.transpose(0, 2, 1)).reshape(len(at), nk * nk)
        Cc = Cc + solve_triangular(Rm, Qg[at].T @ (dH[:, ij] * gw[at, None])) / sc[:, None]
    return best[1], max_iter


def _below(H, delta):
    """The eigenpairs of each symmetric H_k (n_g, n, n) with eigenvalue ≤ δ_k.

    Returns (at, lam, V): the points having any (indices into the n_g), their eigenvalues
    (len(at), m) ascending and eigenvectors (len(at), n, m), m the most at one point; a point with
    fewer is padded with eigenvalue δ_k and a zero vector (which lift nothing). A point whose
    H_k − δ_k I has a Cholesky factor has none (all its eigenvalues exceed δ_k) and costs n³/3
    flops; the others are LAPACK's dsyevr on the eigenvalue range (lo, δ_k], lo below the
    Gershgorin bound: a tridiagonal reduction and the m eigenvectors asked for.
    """
    from scipy.linalg import lapack

    n = H.shape[1]
    lo = -np.abs(H).sum(axis=2).max(axis=1) - 1.0                       # below every eigenvalue
    shifted = H - delta[:, None, None] * np.eye(n)
    found = []
    for k in range(len(H)):
        # the matrices are symmetric: their transposes are the Fortran-ordered arrays LAPACK
        # takes without a copy
        if lapack.dpotrf(shifted[k].T, clean=0, overwrite_a=1)[1] == 0:
            continue
        w, z, m, _, info = lapack.dsyevr(H[k].T, compute_v=1, range="V", vl=lo[k], vu=delta[k])
        if info != 0:
            raise np.linalg.LinAlgError(f"dsyevr failed (info {info}) at grid point {k}")
        if m:
            found.append((k, w[:m], z[:, :m]))
    if not found:
        return np.zeros(0, int), np.zeros((0, 1)), np.zeros((0, n, 1))
    mx = max(len(w) for _, w, _ in found)
    lam = np.empty((len(found), mx))
    V = np.zeros((len(found), n, mx))
    for q, (k, w, z) in enumerate(found):
        lam[q, :len(w)], lam[q, len(w):] = w, delta[k]
        V[q, :, :len(w)] = z
    return np.array([k for k, _, _ in found]), lam, V
