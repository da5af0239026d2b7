"""State-space realisation of the radiation memory force.

    F_r(t) = ∫_0^t K(τ) ξ̇(t − τ) dτ  ≈  C x(t),     ẋ = A x + B ξ̇

Each non-negligible entry (i, j) of the impedance is fitted as a SISO pole–residue model

    K̂_ij(s) = Σ_m r_m / (s − p_m)   (strictly proper, Re p_m < 0, real impulse response
                                      K̂_ij(t) = Σ_m r_m e^{p_m t})

and the SISO blocks are assembled into one block-diagonal MIMO system: the states of entry
(i, j) are driven by ξ̇_j (column j of B) and output into F_i (row i of C). The target is the
radiation impedance K(iω) = B(ω) + iω (A(ω) − A_inf), the Laplace transform of K(t) at s = iω.

Pipeline of :func:`fit_state_space`: symmetrize (reciprocity), project B(ω) onto the positive
semi-definite matrices, K(t) from it (hydro.radiation), its transform K(iω) (causal, and defined
beyond the BEM range), drop negligible entries, fit each remaining entry, enforce passivity by
residue perturbation, correct A_inf by the constant that makes the database A(ω) consistent with
B(ω), and report errors against the database. With one common pole set (many coupled bodies)
the fit is relaxed fast vector fitting of the whole matrix and, in the fit band, its target is
the database impedance itself (``band_target``); passivity is enforced by clipping the spectrum
of the Hermitian part on a grid and refitting the residues (:func:`_enforce_passivity_common`).

Methods
    "vf"  (default): vector fitting (Gustavsen & Semlyen 1999) of K(iω), weight 1 on the fit
          band, `weight_outside` elsewhere up to 3 ω_max, and K(0) = 0 imposed (a floating body
          has B(0) = 0 and a finite A(0)); unstable poles are reflected.
    "era": eigensystem realisation (Hankel SVD) of K(t) sampled at ≈ π/(2.5 ω_max) for the poles,
          residues by least squares on K(t) (slower: ≈ 10 s for RM3).
Units: x arbitrary; B maps m/s (rad/s) to state rates; C x is N (N m).
"""
from __future__ import annotations

import dataclasses
import time as _time
from types import MappingProxyType

import numpy as np
import xarray as xr

from .radiation import filon_weights, impulse_response, impulse_response_transform, memory_length


# ------------------------------------------------------------------------------- SISO fitting
def _basis(s, poles):
    """Real-coefficient basis (len(s), n): 1/(s−a) for real a; for a pair (a, ā) stored once
    (Im a > 0): 1/(s−a) + 1/(s−ā) and i/(s−a) − i/(s−ā)."""
    cols = []
    for a in poles:
        if a.imag == 0:
            cols.append(1.0 / (s - a.real))
        else:
            g1, g2 = 1.0 / (s - a), 1.0 / (s - np.conj(a))
            cols += [g1 + g2, 1j * g1 - 1j * g2]
    return np.stack(cols, axis=1)


def _real_ls(M, rhs, w):
    """Weighted least squares on complex rows, real unknowns (columns scaled for conditioning);
    ``rhs`` (n_s,) or (n_s, n_f) for several right-hand sides."""
    Mw, rw = M * w[:, None], rhs * (w if rhs.ndim == 1 else w[:, None])
    Mr = np.vstack([Mw.real, Mw.imag])
    rr = np.concatenate([rw.real, rw.imag])
    sc = np.linalg.norm(Mr, axis=0)
    sc[sc == 0] = 1.0
    x, *_ = np.linalg.lstsq(Mr / sc, rr, rcond=None)
    return x / (sc if x.ndim == 1 else sc[:, None])


def _initial_poles(order, w_lo, w_hi):
    npair, nreal = order // 2, order % 2
    beta = np.linspace(w_lo, w_hi, npair) if npair > 1 else np.array([np.sqrt(w_lo * w_hi)])[:npair]
    poles = [complex(-b / 10.0, b) for b in beta]          # damped starting poles (VF advice: −β/100)
    poles += [complex(-np.sqrt(w_lo * w_hi), 0.0)] * nreal
    return poles


def _flip(poles):
    return [complex(-abs(p.real) if p.real != 0 else -1e-6, abs(p.imag)) for p in poles]


# functions whose projected rows _sigma_relaxed makes at a time (M4 134: 1.6 MB, within a cache)
_GRAM_BLOCK = 16


def _sigma_relaxed(Phi, Fw, w, n_f):
    """The σ coefficients (d, c) of relaxed vector fitting with one pole set for n_f functions
    f_k (the columns of F, (n_s, n_f)): σ(s) = d + Σ c_m φ_m(s), f_k σ ≈ Σ r_km φ_m for every k,
    and the relaxation Re Σ_s w σ(s) = Σ_s w (Gustavsen 2006, IEEE Trans. Power Delivery 21(3))
    instead of d = 1, which lets d follow the data and converges in fewer iterations.

    Fw: the weighted functions w f_k as rows, (n_f, n_s), or any rows with the same Gram
    matrix Σ_k a_k a_kᵀ of a_k = [Re w f_k, Im w f_k] (:func:`_vf` passes 2 n_s of them when
    there are more functions): the projected rows below are linear in a_k, so the triangle
    they reduce to depends on the functions only through that Gram matrix.

    Fast VF (Gustavsen's QR elimination, one orthonormal basis U of the shared residue columns
    Φ for all functions): each function's rows [−f_k X] (X = [1 | Φ]) are projected onto the
    complement of Φ, which eliminates its residues r_k; the projected rows of all functions are
    reduced to one (n + 1)² triangle (Cholesky of their Gram matrix, Householder QR when that is
    ill-conditioned: diagonal ratio < 1e-6) and solved with the relaxation row. Cost
    O(n_f n_s n²) in BLAS products.
    """
    n_s, n = Phi.shape
    Pw = Phi * w[:, None]
    P = np.vstack([Pw.real, Pw.imag])                                    # (2n_s, n)
    sp = np.linalg.norm(P, axis=0)
    sp[sp == 0] = 1.0
    U, _ = np.linalg.qr(P / sp)                                          # orthonormal, (2n_s, n)
    X = np.hstack([np.ones((n_s, 1)), Phi])                              # σ's basis (n_s, n + 1)

    def projected(k):
        """Functions k's rows [−f X] (real and imaginary parts stacked) with the part in span Φ
        removed, (len(k), 2n_s, n + 1)."""
        fr, fi = Fw.real[k, :, None], Fw.imag[k, :, None]
        Xr, Xi = X.real[None], X.imag[None]
        g = np.concatenate([-(fr * Xr - fi * Xi), -(fr * Xi + fi * Xr)], axis=1)
        g -= U @ (U.T @ g)
        return g

    # the Gram matrix of all functions' projected rows, a block of functions at a time: the rows
    # of all n_f functions together (M4 134: 300 × 242 × 41, 24 MB) made each pass of the
    # arithmetic a trip to memory, 3x slower; the columns' norms (the scaling cs) are its diagonal
    gram = np.zeros((n + 1, n + 1))
    for a in range(0, len(Fw), _GRAM_BLOCK):
        g = projected(slice(a, a + _GRAM_BLOCK)).reshape(-1, n + 1)
        gram += g.T @ g
    cs = np.sqrt(np.diag(gram))
    cs[cs == 0] = 1.0
    n_rows = n_f * 2 * n_s
    try:
        # the triangle from the Gram matrix (half the time of Householder QR of the n_f·2n_s
        # rows); exact in exact arithmetic, so used only while well conditioned
        Rg = np.linalg.cholesky(gram / np.outer(cs, cs)).T
        dg = np.abs(np.diag(Rg))
        if not dg.min() > 1e-6 * dg.max():
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        Rg = np.linalg.qr(projected(slice(None)).reshape(-1, n + 1) / cs, mode="r")  # (n+1, n+1)
    # relaxation row, weighted like an average data row (Gustavsen 2006 eq. 8)
    row = np.concatenate([[np.sum(w)], (Phi * w[:, None]).real.sum(axis=0)]) / cs
    scale = np.linalg.norm(Rg) / np.sqrt(n_rows)
    lhs = np.vstack([Rg, scale * row / np.linalg.norm(row)])
    rhs = np.zeros(len(lhs))
    rhs[-1] = scale * np.sum(w) / np.linalg.norm(row)
    x, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    x = x / cs
    d, c = x[0], x[1:]
    if abs(d) < 1e-8 * max(1.0, float(np.abs(c).max())):
        # relaxation failed (d ≈ 0): the non-relaxed step, d = 1
        r, *_ = np.linalg.lstsq(Rg[:, 1:], -Rg[:, 0], rcond=None)
        d, c = 1.0, r / cs[1:] * cs[0]
    return d, c


def _gram_rows(Fw):
    """Rows (m, n_s) whose a_r = [Re, Im] have the Gram matrix Σ a aᵀ of the rows of Fw
    (n_f, n_s) complex, all the σ step sees of the functions (:func:`_sigma_relaxed`): Fw itself
    when n_f ≤ 2 n_s, else the triangle R of the QR of [Re Fw | Im Fw] (RᵀR = AᵀA). Wu & Yuan:
    2,834 functions become 154 rows, and its σ steps take 10x less time."""
    n_s = Fw.shape[1]
    if len(Fw) <= 2 * n_s:
        return Fw
    R = np.linalg.qr(np.hstack([Fw.real, Fw.imag]), mode="r")           # (2 n_s, 2 n_s)
    return R[:, :n_s] + 1j * R[:, n_s:]


def _sigma_zeros(poles, d, c):
    """Zeros of σ(s) = d + Σ c φ(s): eig(Λ − b cᵀ/d) in the real block form; returned as the
    next pole set (Im ≥ 0 representatives, reflected into the left half plane)."""
    n = len(c)
    Lam = np.zeros((n, n))
    b = np.zeros(n)
    k = 0
    for a in poles:
        if a.imag == 0:
            Lam[k, k] = a.real
            b[k] = 1.0
            k += 1
        else:
            Lam[k:k + 2, k:k + 2] = [[a.real, a.imag], [-a.imag, a.real]]
            b[k] = 2.0
            k += 2
    z = np.linalg.eigvals(Lam - np.outer(b, c) / d)
    new = [complex(p.real, 0.0) for p in z if abs(p.imag) <= 1e-12 * max(abs(p), 1e-300)]
    new += [complex(p) for p in z if p.imag > 1e-12 * max(abs(p), 1e-300)]
    return _flip(new)


def _vf(s, f, w, order, w_lo, w_hi, n_iter=10):
    """Vector fitting of f(s) ≈ Σ r/(s−p); returns poles (Im ≥ 0 representatives), coefficients.
    f (n_s,): one function; f (n_s, n_f): n_f functions with one common pole set (coefficients
    (n_coef, n_f)), by relaxed fast VF (:func:`_sigma_relaxed`)."""
    poles = _initial_poles(order, w_lo, w_hi)
    extra = np.zeros((len(s), 0))
    ne = 0
    if f.ndim == 2:
        Fw = (f * w[:, None]).T                                          # (n_f, n_s)
        n_f = len(Fw)
        Fw = _gram_rows(Fw)
    for _ in range(n_iter):
        Phi = _basis(s, poles)
        n = Phi.shape[1]
        if f.ndim == 2:
            d, ct = _sigma_relaxed(Phi, Fw, w, n_f)
        else:
            x = _real_ls(np.hstack([Phi, extra, -f[:, None] * Phi]), f, w)
            d, ct = 1.0, x[n + ne:]
        poles = _sigma_zeros(poles, d, ct)
    Phi = _basis(s, poles)
    return poles, _real_ls(Phi, f, w)


def _pole_residue(poles, coef):
    """Expand (representative poles, real coefficients) to full complex poles and residues."""
    P, R = [], []
    k = 0
    for a in poles:
        if a.imag == 0:
            P.append(a)
            R.append(complex(coef[k]))
            k += 1
        else:
            r = complex(coef[k], coef[k + 1])
            P += [a, np.conj(a)]
            R += [r, np.conj(r)]
            k += 2
    return np.array(P), np.array(R)


def _era_poles(y, dt, order):
    """Continuous poles of a sampled impulse response y_k = K(k dt) by ERA (Hankel SVD)."""
    m = min((len(y) - 1) // 2, 120)                  # Hankel 120 × 120 covers 29 s at dt = 0.24 s
    H0 = np.lib.stride_tricks.sliding_window_view(y[:2 * m], m)[:m]
    H1 = np.lib.stride_tricks.sliding_window_view(y[1:2 * m + 1], m)[:m]
    U, S, Vt = np.linalg.svd(H0)
    order = min(order, int(np.sum(S > S[0] * 1e-12)))
    Ur, Sr, Vr = U[:, :order], S[:order], Vt[:order].T
    Si = 1.0 / np.sqrt(Sr)
    Ad = (Si[:, None] * (Ur.T @ H1 @ Vr)) * Si[None, :]
    reps = []
    for lam in np.linalg.eigvals(Ad):
        if abs(lam) < 1e-12 or (abs(lam.imag) <= 1e-12 and lam.real < 0):
            continue                                   # no continuous-time equivalent: dropped
        p = np.log(complex(lam)) / dt
        if abs(lam.imag) <= 1e-12:
            reps.append(complex(p.real, 0.0))
        elif lam.imag > 0:
            reps.append(p)
    return _flip(reps)


def _era_fit(tk, yk, dt_era, order):
    """ERA poles from K sampled at dt_era, residues by least squares on K(t) at tk."""
    n_s = int(round(dt_era / (tk[1] - tk[0])))
    ys = yk[::n_s]
    poles = _era_poles(ys, dt_era, order)
    E = []
    for a in poles:
        if a.imag == 0:
            E.append(np.exp(a.real * tk))
        else:
            e = np.exp(a * tk)
            E += [2 * e.real, -2 * e.imag]             # r e^{pt} + conj = 2 Re(r) Re(e) − 2 Im(r) Im(e)
    E = np.stack(E, axis=1)
    coef, *_ = np.linalg.lstsq(E, yk, rcond=None)
    return poles, coef


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


# --------------------------------------------------------------------------------- the result
@dataclasses.dataclass(frozen=True)
class StateSpaceRadiation:
    """Immutable state-space radiation model ẋ = A x + B ξ̇, F_r = C x.

    A (n_x, n_x), B (n_x, n_dof), C (n_dof, n_x) float64 read-only; added_mass_inf (n_dof, n_dof)
    kg…: the A_inf to use with this model (the database's, symmetrized, plus the fitted correction
    when fit_added_mass_inf); dofs: dof labels;
    entries: ((i, j), …) fitted entries; poles / residues: per entry complex arrays;
    report: read-only mapping (see fit_state_space).
    """
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    added_mass_inf: np.ndarray
    dofs: tuple
    entries: tuple
    poles: tuple
    residues: tuple
    report: MappingProxyType

    def impedance(self, omega) -> np.ndarray:
        """Fitted K̂(iω) (n_ω, n_dof, n_dof), complex; see :func:`fitted_impedance`."""
        return fitted_impedance(self, omega)

    def impulse_response(self, t) -> np.ndarray:
        """Fitted K̂(t) = Σ r e^{p t} per entry, (n_t, n_dof, n_dof)."""
        t = np.asarray(t, dtype=float)
        out = np.zeros((len(t), len(self.dofs), len(self.dofs)))
        for (i, j), P, R in zip(self.entries, self.poles, self.residues):
            out[:, i, j] = (np.exp(np.outer(t, P)) @ R).real
        return out


def fitted_impedance(ss: StateSpaceRadiation, omega) -> np.ndarray:
    """K̂(iω) = Σ_m r_m/(iω − p_m) per fitted entry (0 for dropped ones); (n_ω, n_dof, n_dof).

    Equal to C (iωI − A)^{-1} B of the block-diagonal realisation (evaluated per block).
    """
    s = 1j * np.asarray(omega, dtype=float)
    nd = len(ss.dofs)
    out = np.zeros((len(s), nd, nd), dtype=complex)
    # entries sharing their poles (all of them, with pole_sharing "common") in one product
    groups: dict = {}
    for e, P in enumerate(ss.poles):
        groups.setdefault(np.asarray(P).tobytes(), []).append(e)
    for es in groups.values():
        P = ss.poles[es[0]]
        R = np.stack([ss.residues[e] for e in es], axis=1)              # (n_poles, n_entries)
        I, J = np.array([ss.entries[e] for e in es]).T
        out[:, I, J] = (1.0 / (s[:, None] - P[None])) @ R
    return out


def _fit_common(entries, T, Z, band, n_om, dpk, s, w, orders, target, w_lo, w_hi, symmetrize,
                labels, enforce, w_max, n_iter=5):
    """One pole set for all entries (vector fitting of the normalised matrix function): the
    smallest order of ``orders`` with overall band error below ``target``, else the best; then
    (``enforce``) the residue perturbation to a passive model (:func:`_enforce_passivity_common`).
    T: the fit target on s[1:] (n_s − 1, nd, nd); Z: the database impedance (errors, in band).
    Each order: ``n_iter`` relaxed VF iterations (M4 134: 5 give the error of 10).
    Returns fits (poles, coef) per entry (all sharing one poles list), orders, done, iterations."""
    done = {}                                   # distinct entry -> its first place in entries
    for e, (i, j) in enumerate(entries):
        if not (symmetrize and (j, i) in done):
            done[(i, j)] = e
    keys = list(done)
    norm = np.array([np.sqrt(dpk[i] * dpk[j]) for (i, j) in keys])
    Fn = np.concatenate([np.zeros((1, len(keys))),
                         np.stack([T[:, i, j] for (i, j) in keys], axis=1) / norm], axis=0)
    Zb = np.stack([Z[band, i, j] for (i, j) in keys], axis=1) / norm
    # the error over the whole matrix: an off-diagonal entry stands for two (when symmetrized)
    ew = np.array([1.0 if (i == j or not symmetrize) else np.sqrt(2.0) for (i, j) in keys])
    wb = 1j * _band_omega(s, band, n_om)
    best = None
    for n in orders:
        poles, coef = _vf(s, Fn, w, n, w_lo, w_hi, n_iter=n_iter)
        fit = _basis(wb, poles) @ coef
        err = float(np.linalg.norm((fit - Zb) * ew) / np.linalg.norm(Zb * ew))
        if best is None or err < best[0]:
            best = (err, poles, coef, n)
        if err < target:
            break
    _, poles, coef, n = best
    n_enf = 0
    if enforce and symmetrize:
        ok = sorted({i for k in keys for i in k})
        pos = {d: q for q, d in enumerate(ok)}
        coef, n_enf = _enforce_passivity_common(poles, coef, [(pos[i], pos[j]) for i, j in keys],
                                                len(ok), s, w, w_max)
    distinct = {k: (poles, coef[:, e] * norm[e]) for e, k in enumerate(keys)}
    fits = [distinct[(i, j) if (i, j) in distinct else (j, i)] for (i, j) in entries]
    used = {}
    for (i, j) in entries:
        used[(labels[i], labels[j])] = int(n)
    return fits, used, done, n_enf


def _band_omega(s, band, n_om):
    """The in-band ω of the fit grid s = [0, iω_0, …] (the first n_om after s = 0 are the BEM ω)."""
    return s[1:1 + n_om].imag[band]


def _pole_coef_rows(reps, coef):
    """Per pole representative: (2×2 or 1×1 block, its B column, its C row) of the real form."""
    k = 0
    for a in reps:
        if a.imag == 0:
            yield np.array([[a.real]]), np.array([1.0]), np.array([coef[k]])
            k += 1
        else:
            # z' = a z + u, y = r z + conj: with z = x1 + i x2, y = 2 (Re r x1 − Im r x2)
            yield (np.array([[a.real, -a.imag], [a.imag, a.real]]), np.array([1.0, 0.0]),
                   np.array([2 * coef[k], -2 * coef[k + 1]]))
            k += 2


def _realise(entries, poles, nd, shared=False):
    """Block-diagonal real realisation of the per-entry pole–residue models. ``shared`` (one pole
    set for all entries): one block of states per input dof j, read by every entry (i, j)."""
    if shared and entries:
        reps = poles[0][0]
        ins = sorted({j for _, j in entries})
        rows = list(_pole_coef_rows(reps, poles[0][1]))
        m = sum(len(bb) for _, bb, _ in rows)
        A = np.zeros((m * len(ins), m * len(ins)))
        B = np.zeros((m * len(ins), nd))
        C = np.zeros((nd, m * len(ins)))
        for q, j in enumerate(ins):
            o = q * m
            for b, bb, _ in rows:
                A[o:o + len(bb), o:o + len(bb)] = b
                B[o:o + len(bb), j] = bb
                o += len(bb)
        # a C row is the coefficients times 1 (a real pole) or 2, −2 (a pair): _pole_coef_rows
        times = np.concatenate([cc for _, _, cc in _pole_coef_rows(reps, np.ones(m))])
        place = {j: q * m for q, j in enumerate(ins)}
        for (i, j), (_, coef) in zip(entries, poles):
            C[i, place[j]:place[j] + m] = coef * times
        return A, B, C
    blocks = [(blk, bb, cc, i, j) for (i, j), (reps, coef) in zip(entries, poles)
              for blk, bb, cc in _pole_coef_rows(reps, coef)]
    nx = sum(b[0].shape[0] for b in blocks)
    A = np.zeros((nx, nx))
    B = np.zeros((nx, nd))
    C = np.zeros((nd, nx))
    o = 0
    for blk, bb, cc, i, j in blocks:
        m = blk.shape[0]
        A[o:o + m, o:o + m] = blk
        B[o:o + m, j] = bb
        C[i, o:o + m] = cc
        o += m
    return A, B, C


def _max_real_eig(A) -> float:
    """max Re λ(A) (−inf for no states). A realisation of :func:`_realise` is block diagonal with
    1 × 1 and 2 × 2 blocks: their eigenvalues are those of A, found block by block (Wu & Yuan's
    3,000 states: 3 s as one matrix). Any other A is decomposed whole."""
    n = len(A)
    if n == 0:
        return -np.inf
    # 2 × 2 blocks start where the subdiagonal is not 0; they must not overlap, and A must hold
    # nothing outside its blocks
    first = np.flatnonzero(np.diagonal(A, -1) != 0)
    upper = np.diagonal(A, 1)
    on_pattern = (np.count_nonzero(np.diagonal(A)) + len(first)
                  + np.count_nonzero(upper[first]))
    if np.any(np.diff(first) < 2) or np.count_nonzero(upper) > np.count_nonzero(upper[first]) \
            or np.count_nonzero(A) > on_pattern:
        return float(np.max(np.linalg.eigvals(A).real))
    inside = np.zeros(n, bool)
    inside[first], inside[first + 1] = True, True
    blocks = np.stack([A[first, first], A[first, first + 1], A[first + 1, first],
                       A[first + 1, first + 1]], axis=-1).reshape(-1, 2, 2)
    single = np.diagonal(A)[~inside]
    return float(max(np.max(single, initial=-np.inf),
                     np.max(np.linalg.eigvals(blocks).real, initial=-np.inf)))


def fit_state_space(db: xr.Dataset, *, order="auto", method: str = "vf",
                    omega_fit=(0.2, 2.0), max_order: int | None = None, target: float = 0.005,
                    drop_tol: float = 1e-2, symmetrize: bool = True, weight_outside: float = 0.1,
                    fit_added_mass_inf: bool = True, passivity_omega=None,
                    passivity_tol: float = 1e-6, irf_dt: float = 0.02, irf_tmax: float = 150.0,
                    tail: str = "extrapolate", passive_target: bool = True,
                    enforce_passivity: bool = True, dofs=None,
                    pole_sharing: str = "entry", band_target: str | None = None) -> StateSpaceRadiation:
    """Fit a state-space radiation model to `db` (added_mass, radiation_damping, added_mass_inf).

    Target. K(t) from B(ω) (hydro.radiation.impulse_response, `tail` beyond the last BEM
    frequency, t = 0 … `irf_tmax` step `irf_dt`) and its transform
    K(iω) = ∫K e^{−iωt}dt = B(ω) + iω(A_K(ω) − A_inf): causal by construction (Kramers–Kronig), equal
    to the database B in band, and defined beyond the BEM range (fitted up to 3 ω_max with
    weight `weight_outside`, which keeps spurious poles out of the unmeasured range).
    order: int (poles per entry, same for all) or "auto": per entry the smallest even order
        2, 4, …, max_order (default 12) whose relative error over `omega_fit` is below `target`
        (and, for a diagonal entry, whose Re K̂_ii ≥ −1e-3 · band max on 0 … 100 ω_max).
    pole_sharing: "entry" (each entry its own poles and states: few poles each, but the states
        grow with the number of entries, O(n_dof²)) or "common" (one pole set for all entries,
        vector fitting of the whole matrix, each entry normalised by √(D_i D_j), D the band
        maxima of the diagonal; the states are shared by the entries of one input dof:
        O(n_dof · order), what many-body systems need, M4 134: 24 dofs, 300 distinct entries).
        With "common", order "auto" is the smallest of 8, 12, …, max_order (default 40) whose
        overall error is below `target`, else the best; each order is 5 iterations of relaxed
        fast vector fitting (Gustavsen 2006), and passivity is enforced by spectral clipping and
        residue refit (converges to min eig ≥ 0 on the grid: M4 134 in 8 iterations).
    band_target: with pole_sharing "common", what is fitted inside `omega_fit`: "database"
        (default for "common": the database's own B(ω) (made passive, `passive_target`) and
        iω(A(ω) − A_inf)) or "irf" (the transform of K(t), as outside the band, and as always with
        pole_sharing "entry", which accepts only "irf"). Why: K(t)'s transform rebuilds A(ω) from
        B(ω) alone (Kramers–Kronig), through B's extrapolated tail and its interpolation below the
        first BEM frequency; for M4 134 that rebuilt A differs from the BEM's own A by 4.5 % of the
        band impedance, a floor no fit to it could go below (the old default: 4.6 %); fitted
        directly, the database gives 1.0 % with the same 40 poles. The fit stays causal (a sum of
        stable poles) and K(t)'s transform still sets it outside the band.
    method: "vf" (vector fitting of K(iω)) or "era" (Hankel SVD of K(t)); module docstring.
    omega_fit: (ω_lo, ω_hi) rad/s, the band of weight 1 and of the reported errors.
    symmetrize: fit (K + Kᵀ)/2 (reciprocity; a BEM asymmetry is discretisation error) — K_ij and
        K_ji share one fitted model (each its own states).
    fit_added_mass_inf: return added_mass_inf = sym(A_inf) + ΔA, ΔA_ij = mean over the band of
        A_ij(ω) − A_K,ij(ω), the least-squares constant that makes the database A(ω) consistent
        with its B(ω). A BEM A_inf inconsistent with A(ω) (RM3: the spar's surge/pitch A_inf is off
        by a constant, 2.7–3.7 %) leaves iω ΔA in the impedance, which no strictly proper (causal)
        model can fit; Perez & Fossen (2009) identify A_inf with the fit for that reason.
    passive_target: (with symmetrize) replace sym B(ω) by its nearest positive semi-definite
        matrix (eigenvalues clipped at 0 in coordinates normalised by the band diagonal) before
        K(t) is computed, so that the fit target is passive; the change is part of the reported
        error against the database.
    enforce_passivity: (with symmetrize) perturb the residues, least change of the weighted fit,
        until the Hermitian part Re K̂(iω) of the normalised model is ≥ 0 on a grid of 0 … 100 ω_max
        (Gustavsen's residue perturbation, linearised and iterated; with "common" poles the
        spectral clipping of :func:`_enforce_passivity_common`). Needed because the BEM B(ω)
        matrices of coupled bodies are themselves slightly indefinite (RM3: −0.039, normalised).
    drop_tol: an entry is dropped when max_band |K_ij(iω)| < drop_tol · sqrt(max|K_ii| max|K_jj|);
        a dof whose band damping is below 1e-6 of the largest (rotations divided by L², L the cube
        root of the largest displaced volume), e.g. yaw of an axisymmetric body, is dropped with
        all its entries.
    dofs: the dofs to model, as labels or indices (default: all). A dof left out gets no entries
        (its rows and columns of K̂ are 0): pass the dofs the mechanics can move, e.g. without the
        sway, roll and yaw of a planar model, whose inputs ξ̇_j are always 0 and whose outputs
        do no work (M4 134: 24 of 48 dofs, a quarter of the entries).
    Report (read-only mapping):
        entry_error {(dof_i, dof_j): relative L2 error over the band against the database
            impedance B + iω(A − A_inf) taken about the model's added_mass_inf};
        overall_error: ||K̂ − K||_F / ||K||_F, the same over all entries of the modelled dofs
            (dropped ones included);
        added_mass_inf_correction_max: (dof_i, dof_j, ΔA, ΔA / sqrt(A∞_ii A∞_jj));
        dropped, drop_tol, n_states, orders, max_real_eig (max Re eig(A); < 0: stable);
        passivity_min_eig: min over ω of the smallest eigenvalue of the Hermitian part of
            D^{-1/2} K̂(iω) D^{-1/2} (D = band max of |K_ii|: unit-free; PSD is scale invariant);
        passivity_min_eig_data: the same for the (symmetrized) database impedance;
        passive: passivity_min_eig ≥ −passivity_tol; passivity_violations: [(ω, min eig)] where
            not (BEM B matrices of coupled bodies are themselves indefinite by ~1 %: RM3 −0.0096);
        fit_seconds.
    """
    t0 = _time.perf_counter()
    if method not in ("vf", "era"):
        raise ValueError(f"method={method!r}; accepted: 'vf', 'era'.")
    if not (order == "auto" or (isinstance(order, (int, np.integer)) and order >= 1)):
        raise ValueError(f"order={order!r}; accepted: a positive int or 'auto'.")
    w_lo, w_hi = map(float, omega_fit)
    om = np.asarray(db["omega"].values, dtype=float)
    dims = ("omega", "influenced_dof", "radiating_dof")
    A = np.asarray(db["added_mass"].transpose(*dims).values, dtype=float)
    Bw = np.asarray(db["radiation_damping"].transpose(*dims).values, dtype=float)
    Ainf = np.asarray(db["added_mass_inf"].transpose(*dims[1:]).values, dtype=float)
    nd = A.shape[1]
    labels = [str(d) for d in db["influenced_dof"].values]
    band = (om >= w_lo) & (om <= w_hi)
    if band.sum() < 4:
        raise ValueError(f"omega_fit={omega_fit}: fewer than 4 database frequencies in the band.")
    sym = (lambda M: 0.5 * (M + np.swapaxes(M, -1, -2))) if symmetrize else (lambda M: M)

    # which dofs have a model: a dof whose band damping is below 1e-6 of the largest (rotations
    # divided by L², L = cube root of the largest displaced volume, else 1 m), e.g. yaw of an
    # axisymmetric body or roll/pitch of a sphere about its centre, is BEM noise
    bpk = np.abs(np.diagonal(Bw[band], axis1=1, axis2=2)).max(axis=0)
    rot = (np.arange(nd) % 6) >= 3
    L = float(np.cbrt(np.max(db["displaced_volume"].values))) if "displaced_volume" in db else 1.0
    cmp_ = np.where(rot, bpk / L ** 2, bpk)
    dof_ok = cmp_ > 1e-6 * cmp_.max()
    if dofs is not None:
        chosen = np.zeros(nd, dtype=bool)
        for d in dofs:
            k = labels.index(str(d)) if str(d) in labels else d
            if not isinstance(k, (int, np.integer)) or not 0 <= k < nd:
                raise ValueError(f"dofs: {d!r} is neither a dof label of the database ({labels[:3]} "
                                 f"…) nor an index in [0, {nd})")
            chosen[k] = True
        dof_ok &= chosen
    db_t = db
    if passive_target and symmetrize:
        # nearest PSD damping per frequency (normalised by the band diagonal): BEM B matrices of
        # coupled bodies are slightly indefinite (RM3 surge–pitch group: −0.039 at 1.28 rad/s)
        Dn = np.where(dof_ok, 1.0 / np.sqrt(np.where(dof_ok, bpk, 1.0)), 0.0)
        Bn = sym(Bw)[:, dof_ok][:, :, dof_ok] * np.outer(Dn[dof_ok], Dn[dof_ok])[None]
        lam_b, V_b = np.linalg.eigh(Bn)
        Bp = np.einsum("wik,wk,wjk->wij", V_b, np.clip(lam_b, 0.0, None), V_b)
        Bfix = sym(Bw).copy()
        sub = np.ix_(np.arange(len(om)), np.flatnonzero(dof_ok), np.flatnonzero(dof_ok))
        Bfix[sub] = Bp / np.outer(Dn[dof_ok], Dn[dof_ok])[None]
        db_t = db.copy()
        db_t["radiation_damping"] = (dims, Bfix)
    # causal target from K(t)
    t = np.arange(0.0, irf_tmax + irf_dt / 2, irf_dt)
    om_fit = np.concatenate([om, om[-1] * np.geomspace(1.0, 3.0, 21)[1:]])
    if method == "era":
        K = impulse_response(db_t, t, tail=tail).values
        ZK = sym(np.tensordot(filon_weights(t, -om_fit), K, axes=(1, 0)))  # ∫K e^{−iωt} dt
    else:
        ZK = sym(impulse_response_transform(db_t, t, om_fit, tail=tail))  # the same, K not formed
    A_K = Ainf[None] + ZK[:len(om)].imag / om[:, None, None]
    dA = np.mean(sym(A)[band] - sym(A_K)[band], axis=0) if fit_added_mass_inf else np.zeros((nd, nd))
    Ainf_fit = sym(Ainf) + dA
    Z_raw = Bw + 1j * om[:, None, None] * (A - Ainf_fit[None])        # database, about the model's A∞
    Z = sym(Z_raw)

    # which entries to fit (judged on the fit band: outside it BEM noise and asymmetry dominate)
    pk = np.abs(ZK[:len(om)][band]).max(axis=0)
    dpk = np.diag(pk).copy()
    scale = np.sqrt(np.outer(dpk, dpk))
    keep = (pk >= drop_tol * scale) & np.outer(dof_ok, dof_ok)
    entries = [(i, j) for i in range(nd) for j in range(nd) if keep[i, j]]
    dropped = [(labels[i], labels[j]) for i in range(nd) for j in range(nd)
               if not keep[i, j] and pk[i, j] > 0]

    s = np.concatenate([[0.0], 1j * om_fit])                     # s = 0: K(0) = 0 imposed
    in_band = np.concatenate([band, np.zeros(len(om_fit) - len(om), bool)])
    w = np.concatenate([[10.0], np.where(in_band, 1.0, weight_outside)])
    if method == "era":
        dt_era = max(irf_dt, round(np.pi / (2.5 * om[-1]) / irf_dt) * irf_dt)
        T_K = memory_length(K, t, rtol=1e-3)
        n_t = int(np.searchsorted(t, max(2.0 * T_K, 20.0)))

    if pole_sharing not in ("entry", "common"):
        raise ValueError(f"pole_sharing={pole_sharing!r}; accepted: 'entry', 'common'")
    if band_target is None:
        band_target = "database" if pole_sharing == "common" else "irf"
    if band_target not in ("database", "irf") or (band_target == "database" and pole_sharing != "common"):
        raise ValueError(f"band_target={band_target!r} with pole_sharing={pole_sharing!r}; accepted: "
                         "'irf', or 'database' with pole_sharing='common'")
    if method == "era" and pole_sharing == "common":
        raise ValueError("pole_sharing='common' needs method='vf' (ERA fits one entry at a time)")
    if pole_sharing == "common":
        max_order = 40 if max_order is None else max_order
        orders = [order] if order != "auto" else list(range(8, max_order + 1, 4))
    else:
        max_order = 12 if max_order is None else max_order
        orders = [order] if order != "auto" else list(range(2, max_order + 1, 2))
    w_chk = np.concatenate([np.linspace(0.0, om[-1], 200)[1:], om[-1] * np.geomspace(1.0, 100.0, 30)[1:]])
    fits, errs, used, done = [], {}, {}, {}
    n_enforce = 0
    if pole_sharing == "common":
        T = ZK
        if band_target == "database":
            # in band the database itself (damping as made passive above), about the model's A∞
            Bt = np.asarray(db_t["radiation_damping"].transpose(*dims).values, dtype=float)
            T = ZK.copy()
            T[:len(om)][band] = sym(Bt + 1j * om[:, None, None] * (A - Ainf_fit[None]))[band]
        fits, used, done, n_enforce = _fit_common(
            entries, T, Z, band, len(om), dpk, s, w, orders, target, w_lo, w_hi, symmetrize, labels,
            enforce_passivity, om[-1])
    else:
        for (i, j) in entries:
            if symmetrize and (j, i) in done:               # same model, its own states
                fits.append(fits[done[(j, i)]])
                used[(labels[i], labels[j])] = used[(labels[j], labels[i])]
                continue
            done[(i, j)] = len(fits)
            fs = np.abs(ZK[:len(om)][band, i, j]).max()
            fn = np.concatenate([[0.0], ZK[:, i, j] / fs])
            zb = Z[band, i, j] / fs
            best = None
            for n in orders:
                if method == "vf":
                    poles, coef = _vf(s, fn, w, n, w_lo, w_hi)
                else:
                    poles, coef = _era_fit(t[:n_t], K[:n_t, i, j] / fs, dt_era, n)
                P, R = _pole_residue(poles, coef)
                fit = (1.0 / (1j * om[band][:, None] - P[None])) @ R
                err = np.linalg.norm(fit - zb) / np.linalg.norm(zb)
                # a diagonal entry must itself be passive (Re K̂_ii ≥ 0) everywhere, not only in band
                pas = True
                if i == j:
                    pas = bool(((1.0 / (1j * w_chk[:, None] - P[None])) @ R).real.min() > -1e-3)
                key = (not pas, err)
                if best is None or key < best[0]:
                    best = (key, poles, coef, n)
                if err < target and pas:
                    break
            _, poles, coef, n = best
            fits.append((poles, coef * fs))
            used[(labels[i], labels[j])] = int(n)

    if enforce_passivity and symmetrize and done and pole_sharing == "entry":
        n_enforce = _enforce_passivity(fits, done, nd, dpk, dof_ok, s, w, om[-1])
        fits = [fits[done[(i, j)] if (i, j) in done else done[(j, i)]] for (i, j) in entries]
    Am, Bm, Cm = _realise(entries, fits, nd, shared=pole_sharing == "common")
    P_all, R_all = zip(*[_pole_residue(p, c) for p, c in fits]) if fits else ((), ())
    ss = StateSpaceRadiation(Am, Bm, Cm, Ainf_fit, tuple(labels), tuple(entries), tuple(P_all),
                             tuple(R_all), MappingProxyType({}))
    # report
    Zf = fitted_impedance(ss, om)
    blk = np.ix_(np.flatnonzero(band), np.flatnonzero(dof_ok), np.flatnonzero(dof_ok))
    overall = float(np.linalg.norm((Zf - Z)[blk]) / np.linalg.norm(Z[blk]))
    e_num = np.linalg.norm((Zf - Z)[band], axis=0)
    e_den = np.linalg.norm(Z[band], axis=0)
    errs = {(labels[i], labels[j]): float(e_num[i, j] / e_den[i, j]) for (i, j) in entries}
    dA_rel = np.abs(dA) / np.sqrt(np.abs(np.outer(np.diag(Ainf_fit), np.diag(Ainf_fit))) + 1e-300)
    k_dA = np.unravel_index(np.argmax(dA_rel), dA_rel.shape)
    max_re = _max_real_eig(Am)
    if passivity_omega is None:
        passivity_omega = _passivity_grid(om[-1])
    passivity_omega = np.asarray(passivity_omega, dtype=float)
    Dm = 1.0 / np.sqrt(np.where(dof_ok, dpk, np.inf))

    def herm_min(Zs):
        Zs = Zs * Dm[None, :, None] * Dm[None, None, :]
        H = 0.5 * (Zs + np.conj(np.swapaxes(Zs, 1, 2)))
        return np.linalg.eigvalsh(H)[:, 0]

    lam = herm_min(fitted_impedance(ss, passivity_omega))
    lam_data = herm_min(Z)
    viol = [(float(passivity_omega[k]), float(lam[k])) for k in np.flatnonzero(lam < -passivity_tol)]
    report = {
        "method": method, "omega_fit": (w_lo, w_hi), "entry_error": errs,
        "overall_error": overall,
        "symmetrized": bool(symmetrize),
        "added_mass_inf_correction_max": (labels[k_dA[0]], labels[k_dA[1]], float(dA[k_dA]),
                                          float(dA_rel[k_dA])),
        "orders": used, "dropped": dropped, "drop_tol": drop_tol, "pole_sharing": pole_sharing,
        "modelled_dofs": tuple(labels[k] for k in np.flatnonzero(dof_ok)),
        "n_states": int(Am.shape[0]), "max_real_eig": max_re, "stable": bool(max_re < 0),
        "passivity_min_eig": float(lam.min()),
        "passivity_min_eig_omega": float(passivity_omega[int(np.argmin(lam))]),
        "passivity_min_eig_data": float(lam_data.min()),
        "passivity_tol": passivity_tol, "passive": not viol, "passivity_violations": viol[:20],
        "passivity_enforcement_iterations": n_enforce,
        "fit_seconds": _time.perf_counter() - t0,
    }
    for arr in (Am, Bm, Cm, Ainf_fit):
        arr.setflags(write=False)
    for arr in P_all + R_all:
        arr.setflags(write=False)
    return dataclasses.replace(ss, report=MappingProxyType(report))
