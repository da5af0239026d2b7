"""Pole–residue fitting of frequency responses, the engine of :mod:`hydro.statespace`.

Vector fitting (Gustavsen & Semlyen 1999; relaxed, Gustavsen 2006; fast, with one QR basis of
the residue columns shared by all functions) of f(s) ≈ Σ_m r_m / (s − p_m) on samples s = iω,
one function or many with one common pole set, and the eigensystem realisation (ERA, Hankel SVD)
of a sampled impulse response. Poles are kept as representatives (a real pole, or the member
of a conjugate pair with Im p > 0) with real coefficients of the real basis of :func:`_basis`.
The functions here are the package's internals: :func:`hydro.statespace.fit_state_space` is the
front door.
"""
from __future__ import annotations

import numpy as np

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
