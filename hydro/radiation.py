"""Radiation memory: impulse response K(t), Ogilvie's relations, memory length, grid check.

Cummins' radiation force is ``F_r(t) = −A_inf ξ̈(t) − ∫_0^t K(τ) ξ̇(t − τ) dτ`` with

    K(t) = (2/π) ∫_0^∞ B(ω) cos(ωt) dω                                   (1)

and Ogilvie's relations back to the frequency domain (checked: a convolution with ξ̇ = e^{iωt}
gives K̂(ω) = ∫K e^{−iωt}dt, and −[iωA∞ + K̂] must equal −[iωA(ω) + B(ω)]):

    A(ω) = A_inf − (1/ω) ∫_0^∞ K(t) sin(ωt) dt,   B(ω) = ∫_0^∞ K(t) cos(ωt) dt     (2)

so that the radiation impedance (Laplace transform of K at s = iω) is
``K(iω) = B(ω) + iω (A(ω) − A_inf)``. Example: K = e^{−at} gives B = a/(a² + ω²) ≥ 0 and
A = A∞ − 1/(a² + ω²).

All integrals treat the sampled function as piecewise linear and integrate it against the
cosine/sine exactly (Filon-trapezoid), so no sampling of the oscillation is needed: K(t) at large
t and A(ω) at large ω are as accurate as the linear interpolation of B(ω) or K(t) itself.
Units: K in N/(m/s)/s = N s/m / s (translation), ω rad/s, t s; dims (time, influenced_dof,
radiating_dof).
"""
from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from .database import HydroDatabaseWarning


# ------------------------------------------------------------------------------ Filon weights
def filon_weights(x, y) -> np.ndarray:
    """Complex weights W (len(y), len(x)) with ``W @ f ≈ ∫_{x0}^{xN} f(x) e^{i y x} dx``.

    Exact for f linear between the nodes x (ascending). Per segment [a, b] (h = b − a,
    midpoint c): ``∫ f e^{iyx} = [f_b e^{iyb} − f_a e^{iya} − (f_b − f_a) e^{iyc} S(yh/2)]/(iy)``,
    S(z) = sin z / z. Interior node weights telescope to ``(E_k − E_{k−1})/(iy)`` with
    E_k = e^{iy c_k} S(y h_k/2). Points with |y| x_span < 1e-6 use the trapezoid rule (error
    O((y x)²) there).
    """
    x = np.asarray(x, dtype=float)
    y = np.atleast_1d(np.asarray(y, dtype=float))
    h = np.diff(x)
    c = 0.5 * (x[:-1] + x[1:])
    trap = np.zeros(len(x))
    trap[:-1] += h / 2
    trap[1:] += h / 2
    W = np.empty((len(y), len(x)), dtype=complex)
    small = np.abs(y) * max(np.abs(x).max(), 1e-300) < 1e-6
    W[small] = trap
    ys = y[~small][:, None]
    if ys.size:
        E = np.exp(1j * ys * c) * np.sinc(ys * h / (2 * np.pi))
        iy = 1j * ys
        Wb = np.empty((ys.shape[0], len(x)), dtype=complex)
        Wb[:, 0] = (E[:, 0] - np.exp(1j * ys[:, 0] * x[0])) / iy[:, 0]
        Wb[:, 1:-1] = (E[:, 1:] - E[:, :-1]) / iy
        Wb[:, -1] = (np.exp(1j * ys[:, 0] * x[-1]) - E[:, -1]) / iy[:, 0]
        W[~small] = Wb
    return W


def _filon_part(x, y, part: str) -> np.ndarray:
    """``filon_weights(x, y).real`` (part "cos": ∫ f cos(yx) dx) or ``.imag`` (part "sin":
    ∫ f sin(yx) dx), (len(y), len(x)) real, from the same per-segment formula with only the sine
    or the cosine evaluated (no complex exponential: half the transcendental work and half the
    memory). With G_k = s(y c_k) S(y h_k/2), s = sin for "cos" and cos for "sin", the real part
    of (E_k − E_{k−1})/(iy) is (G_k − G_{k−1})/y and the imaginary part −(G_k − G_{k−1})/y
    (end nodes: s(y x_0), s(y x_N) in place of G_{−1}, G_N)."""
    x = np.asarray(x, dtype=float)
    y = np.atleast_1d(np.asarray(y, dtype=float))
    h = np.diff(x)
    c = 0.5 * (x[:-1] + x[1:])
    W = np.empty((len(y), len(x)))
    small = np.abs(y) * max(np.abs(x).max(), 1e-300) < 1e-6
    if small.any():
        trap = np.zeros(len(x))
        trap[:-1] += h / 2
        trap[1:] += h / 2
        W[small] = trap if part == "cos" else 0.0
    ys = y[~small][:, None]
    if ys.size:
        f, sign = (np.sin, 1.0) if part == "cos" else (np.cos, -1.0)
        G = f(ys * c) * np.sinc(ys * h / (2 * np.pi))
        Wb = np.empty((ys.shape[0], len(x)))
        Wb[:, 0] = G[:, 0] - f(ys[:, 0] * x[0])
        Wb[:, 1:-1] = G[:, 1:] - G[:, :-1]
        Wb[:, -1] = f(ys[:, 0] * x[-1]) - G[:, -1]
        Wb *= sign / ys
        W[~small] = Wb
    return W


# ------------------------------------------------------------------------- impulse response
def _tail_fit(omega, B, fit_fraction, noise):
    """Per entry power law B ≈ c ω^(−n) on the top `fit_fraction` of the band.

    Returns (c, n, ok): ok where the window has one sign, |B| > noise · peak everywhere in it
    (below that BEM damping is noise) and 1 < n < 20 (an integrable tail).
    """
    nw, ne = B.shape
    win = omega >= omega[-1] * (1.0 - fit_fraction)
    Bw = B[win]
    peak = np.abs(B).max(axis=0)
    same_sign = np.all(Bw > 0, axis=0) | np.all(Bw < 0, axis=0)
    above = np.all(np.abs(Bw) > noise * np.where(peak > 0, peak, np.inf), axis=0)
    lx = np.log(omega[win])
    ly = np.log(np.where(np.abs(Bw) > 0, np.abs(Bw), 1e-300))
    X = np.stack([np.ones_like(lx), -lx], axis=1)
    coef, *_ = np.linalg.lstsq(X, ly, rcond=None)
    n = coef[1]
    # all-zero entries (e.g. yaw of a body of revolution) fit absurd exponents: they are tapered
    # (ok is False), so their c is set to 0 rather than left to overflow
    with np.errstate(over="ignore", invalid="ignore"):
        c = np.sign(Bw[-1]) * np.exp(coef[0])
        resid = np.sqrt(np.mean((X @ coef - ly) ** 2, axis=0))
    ok = same_sign & above & (n > 1.0) & (n < 20.0) & (resid < 0.2)
    return np.where(ok, c, 0.0), n, ok


def _taper(omega, fraction):
    w0 = omega[-1] * (1.0 - fraction)
    u = np.clip((omega - w0) / max(omega[-1] - w0, 1e-300), 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * u))


def _damping_nodes(db, tail, fit_fraction, taper_fraction, noise, extend, n_extend):
    """B(ω) as the piecewise-linear function that eq. (1) integrates: nodes (n_nodes,), values
    Bn (n_nodes, nd²) (the BEM grid from B(0) = 0, tapered or extended per `tail`), and what the
    ringing check and the tail exponents need. K(t) = (2/π) Re W(nodes, t) @ Bn."""
    if tail not in ("extrapolate", "taper", "none"):
        raise ValueError(f"tail={tail!r}; accepted: 'extrapolate', 'taper', 'none'.")
    Bda = db["radiation_damping"].transpose("omega", "influenced_dof", "radiating_dof")
    om = np.asarray(Bda["omega"].values, dtype=float)
    nd = Bda.shape[1]
    B = np.asarray(Bda.values, dtype=float).reshape(len(om), -1)
    peak = np.abs(B).max(axis=0)
    n_exp = np.full(B.shape[1], np.nan)

    nodes = np.concatenate([[0.0], om])
    Bn = np.vstack([np.zeros((1, B.shape[1])), B])
    if tail == "none":
        B_end = B[-1]
        w_end = om[-1]
    elif tail == "taper":
        Bn = Bn * _taper(nodes, taper_fraction)[:, None]
        B_end = np.zeros(B.shape[1])
        w_end = om[-1]
    else:
        c, n, ok = _tail_fit(om, B, fit_fraction, noise)
        # entries negligible beside their diagonals (< 1e-3, e.g. yaw noise) are tapered
        dpk = np.diagonal(peak.reshape(nd, nd))
        ok &= peak > 1e-3 * np.sqrt(np.outer(dpk, dpk)).ravel()
        taper = _taper(nodes, taper_fraction)[:, None]
        Bn = np.where(ok[None], Bn, Bn * taper)
        ext = om[-1] * np.geomspace(1.0, extend, n_extend + 1)[1:]
        # the fitted exponent continues B from its last BEM value (continuous at ω_max)
        Bext = np.where(ok[None], B[-1][None] * (ext[:, None] / om[-1]) ** (-np.where(ok, n, 2.0))[None],
                        0.0)
        nodes = np.concatenate([nodes, ext])
        Bn = np.vstack([Bn, Bext])
        n_exp = np.where(ok, n, np.nan)
        B_end = Bext[-1]
        w_end = ext[-1]
    return dict(Bda=Bda, om=om, nd=nd, peak=peak, n_exp=n_exp, nodes=nodes, Bn=Bn, B_end=B_end,
                w_end=w_end, n_bem=len(om) + 1)


def _entries(d):
    """The columns of Bn (flat entries i·nd + j) that need a product, and how to fill the rest:
    (cols, mirror). Entries whose B is zero at every node are zero (a mask's cross-body blocks);
    when Bn is exactly symmetric (a symmetrised database: HydroSpec.database()) only the upper
    triangle is computed and ``mirror`` is True (K_ji = K_ij: the same column, the same sum)."""
    nd, Bn = d["nd"], d["Bn"]
    B3 = Bn.reshape(len(Bn), nd, nd)
    mirror = bool(np.array_equal(B3, B3.transpose(0, 2, 1)))
    take = np.triu(np.ones((nd, nd), bool)) if mirror else np.ones((nd, nd), bool)
    take &= np.any(B3 != 0, axis=0)
    return np.flatnonzero(take.ravel()), mirror


def _node_product(W, d, cols=None):
    """``W @ Bn[:, cols]`` (W: (m, n_nodes) weights on the damping nodes), by blocks that skip the
    products by zeros: the BEM nodes (B(0) = 0 up to ω_max) for every column, the tail-extension
    nodes (``extrapolate``: 300 of the 311 nodes) only for the columns whose tail was fitted (the
    others are tapered: zero there). The same sums in another order: round-off."""
    Bn, nb = d["Bn"], d["n_bem"]
    cols = np.arange(Bn.shape[1]) if cols is None else np.asarray(cols)
    out = W[:, :nb] @ Bn[:nb, cols]
    if Bn.shape[0] > nb:
        ext = np.flatnonzero(np.any(Bn[nb:, cols] != 0, axis=0))
        if ext.size:
            out[:, ext] += W[:, nb:] @ Bn[nb:, cols[ext]]
    return out


def _fill(vals, cols, mirror, nd):
    """(m, len(cols)) values of the entries ``cols`` → (m, nd, nd), zero elsewhere, mirrored."""
    out = np.zeros((vals.shape[0], nd * nd))
    out[:, cols] = vals
    out = out.reshape(-1, nd, nd)
    if mirror:
        i, j = np.triu_indices(nd, 1)
        out[:, j, i] = out[:, i, j]
    return out


def _ringing(d, Kpk):
    """The truncation term's amplitude at t = 2π/ω_end relative to max_t |K_ij| per entry, and the
    largest over the relevant entries (see :func:`impulse_response`)."""
    ring = (2.0 / np.pi) * np.abs(d["B_end"]) / (2 * np.pi / d["w_end"]) / np.where(Kpk > 0, Kpk, np.inf)
    relevant = d["peak"] > 1e-3 * d["peak"].max()
    return ring, relevant, float(np.max(ring[relevant], initial=0.0))


def _ringing_band_error(d):
    """What the cut-off of B at ω_end does to a computation at the frequencies of the data, per
    entry, relative to sqrt(peak B_ii · peak B_jj).

    With B piecewise linear and ending at B_end, K holds the truncation term
    T(t) = (2/π) B_end sin(ω_e t)/t (ω_e = ω_end). Its one-sided transform is
    ∫_0^∞ T e^{−iωt} dt = B_end·[ω < ω_e] − i (B_end/π) ln|(ω_e + ω)/(ω_e − ω)|: the real part is
    the damping as given; the imaginary part is what the cut-off adds to ω(A(ω) − A∞) of every
    computation that uses K (a convolution of any time step, A∞ "consistent", the state-space
    target) at the frequencies ω its motions have. Those are the database's (its waves: the
    excitation ends at ω_max), so the error is that term at the grid's highest frequency below
    ω_e: (2/π)|B_end| ω/ω_e for ω ≪ ω_e (tail "extrapolate", ω_e = 10³ ω_max: 6e-4 |B_end|),
    log-large at ω_max for a plain cut ("none"). The ringing itself, at one cut-off period
    2π/ω_e, is seen only on a time grid finer than that and averages out over a step dt ≫ 2π/ω_e
    (Stansby & Li: ω_e = 2,500 rad/s, 2.5 ms)."""
    om = d["om"]
    below = om[om < d["w_end"] * (1.0 - 1e-12)]
    if below.size == 0:
        return np.zeros_like(d["peak"]), 0.0
    w, we = below[-1], d["w_end"]
    err_abs = np.abs(d["B_end"]) / np.pi * np.log((we + w) / (we - w))
    nd = d["nd"]
    dpk = np.diagonal(d["peak"].reshape(nd, nd))
    scale = np.sqrt(np.outer(dpk, dpk)).ravel()
    err = err_abs / np.where(scale > 0, scale, np.inf)
    relevant = d["peak"] > 1e-3 * d["peak"].max()
    return err, float(np.max(err[relevant], initial=0.0))


def _warn_ringing(d, ring, relevant, ringing, ringing_tol, stacklevel):
    err, worst = _ringing_band_error(d)
    if worst > ringing_tol:
        nd = d["nd"]
        labels = [str(x) for x in d["Bda"]["influenced_dof"].values]
        rlabels = [str(x) for x in d["Bda"]["radiating_dof"].values]
        k = int(np.argmax(np.where(relevant, err, 0)))
        warnings.warn(
            f"K(t) rings from the truncation of B at omega = {d['w_end']:.4g} rad/s: the cut-off "
            f"changes the radiation impedance at the grid's frequencies by {worst:.3g} of "
            f"sqrt(B_ii B_jj) for ({labels[k // nd]}, {rlabels[k % nd]}) (B_end = {d['B_end'][k]:.4g}; "
            f"ringing amplitude {ring[k]:.3g} of max|K| at t = 2 pi/omega_end). Use "
            "tail='extrapolate' or 'taper', or compute B to higher omega.",
            HydroDatabaseWarning, stacklevel=stacklevel + 1)
    return worst


def impulse_response(db: xr.Dataset, t, *, tail: str = "extrapolate", fit_fraction: float = 0.25,
                     taper_fraction: float = 0.1, noise: float = 0.005, extend: float = 1e3,
                     n_extend: int = 300, ringing_tol: float = 0.01) -> xr.DataArray:
    """Radiation impulse response K(t) (time, influenced_dof, radiating_dof) from eq. (1).

    db: database with radiation_damping (omega, influenced_dof, radiating_dof) [N s/m …].
    t: times (s), ≥ 0. Between 0 and the first ω, B is interpolated linearly to B(0) = 0.
    tail — how B beyond ω_max (the last BEM frequency) is handled:
      "extrapolate": per entry, fit B ≈ c ω^(−n) on the top `fit_fraction` of the band and
          integrate it to `extend`·ω_max on `n_extend` geometric nodes (remainder
          ∝ extend^{1−n}, < 0.1 % for n ≥ 2). Entries whose top band is noise (sign change, or
          |B| < `noise`·peak: e.g. heave, which falls as ω^−7) or whose fit is not integrable
          (n ≤ 1), and entries below 1e-3 of sqrt(peak_ii peak_jj), are tapered instead. The exponents are the coordinate ``tail_exponent``
          (NaN = tapered).
      "taper": B·w(ω), w a half-cosine from 1 at (1 − taper_fraction)·ω_max to 0 at ω_max.
      "none": plain truncation at ω_max (for comparison; it rings).
    Ringing check: with piecewise-linear B ending at value B_end, eq. (1) contains exactly the
    truncation term (2/π) B_end sin(ω_end t)/t. attrs["ringing_ratio"] is its amplitude at one
    cut-off period t = 2π/ω_end relative to max_t |K_ij|, the largest over the entries (what a
    plot of K on a grid finer than 2π/ω_end shows); attrs["ringing_band_error"] what the cut-off
    changes in the radiation impedance at the data's frequencies, relative to sqrt(B_ii B_jj)
    (:func:`_ringing_band_error`): a warning is issued when that exceeds `ringing_tol`.
    """
    if tail not in ("extrapolate", "taper", "none"):
        raise ValueError(f"tail={tail!r}; accepted: 'extrapolate', 'taper', 'none'.")
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or np.any(t < 0):
        raise ValueError("t must be a 1-D array of times ≥ 0 (s).")
    d = _damping_nodes(db, tail, fit_fraction, taper_fraction, noise, extend, n_extend)
    Bda, om, nd, n_exp = d["Bda"], d["om"], d["nd"], d["n_exp"]
    W = _filon_part(d["nodes"], t, "cos")                                  # (n_t, n_nodes)
    cols, mirror = _entries(d)
    Kc = (2.0 / np.pi) * _node_product(W, d, cols)
    K = _fill(Kc, cols, mirror, nd)
    ring, relevant, ringing = _ringing(d, _fill(np.abs(Kc).max(axis=0)[None], cols, mirror, nd).ravel())
    labels = [str(x) for x in Bda["influenced_dof"].values]
    rlabels = [str(x) for x in Bda["radiating_dof"].values]
    out = xr.DataArray(K.reshape(len(t), nd, nd), dims=("time", "influenced_dof", "radiating_dof"),
                       coords={"time": t, "influenced_dof": labels, "radiating_dof": rlabels},
                       name="impulse_response")
    out.coords["tail_exponent"] = (("influenced_dof", "radiating_dof"), n_exp.reshape(nd, nd))
    band_error = _warn_ringing(d, ring, relevant, ringing, ringing_tol, stacklevel=2)
    out.attrs.update(tail=tail, omega_max=float(om[-1]), ringing_ratio=ringing,
                     ringing_band_error=band_error,
                     units="N s/m per s (translation); N m s per s (rotation); per dof pair",
                     equation="K(t) = (2/pi) int_0^inf B(omega) cos(omega t) d omega")
    return out


def impulse_response_transform(db: xr.Dataset, t, omega, *, tail: str = "extrapolate",
                               fit_fraction: float = 0.25, taper_fraction: float = 0.1,
                               noise: float = 0.005, extend: float = 1e3, n_extend: int = 300,
                               ringing_tol: float = 0.01) -> np.ndarray:
    """∫_0^{t_end} K(t) e^{−iωt} dt (n_ω, nd, nd) complex, K of :func:`impulse_response` on the
    times t (same options, same ringing warning), without forming K for every entry.

    Both steps are linear maps of the damping nodes Bn (:func:`_damping_nodes`):
    K = (2/π) Re W_B Bn (W_B: Filon weights nodes → t) and the transform F_t K (F_t: Filon weights
    t → −ω), so the transform is (2/π) (F_t Re W_B) Bn: one (n_ω × n_t)(n_t × n_nodes) product
    shared by all nd² entries instead of two products of n_t rows per entry (M4 134: 7,501 times,
    2,304 entries; the same numbers up to round-off). K itself is formed only for the entries whose
    ringing could exceed `ringing_tol` by the bound max|K| ≥ |K(0)|.
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or np.any(t < 0):
        raise ValueError("t must be a 1-D array of times ≥ 0 (s).")
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    d = _damping_nodes(db, tail, fit_fraction, taper_fraction, noise, extend, n_extend)
    nd = d["nd"]
    W = _filon_part(d["nodes"], t, "cos")                                  # (n_t, n_nodes)
    # F_t W with F_t = filon_weights(t, −ω) by its real and imaginary parts (real products)
    FW = _filon_part(t, -omega, "cos") @ W + 1j * (_filon_part(t, -omega, "sin") @ W)
    Z = (2.0 / np.pi) * (FW @ d["Bn"])
    _check_ringing(d, W, ringing_tol, stacklevel=2)
    return Z.reshape(len(omega), nd, nd)


def _check_ringing(d, W, ringing_tol, stacklevel):
    """:func:`impulse_response`'s ringing check and warning without K for every entry: the exact
    max_t |K| (W: the cosine weights of the times) only where the bound with |K(0)| (trapezoid of
    Bn; max|K| ≥ |K(0)|) does not clear it, and only when the warning is due (its message
    quotes the amplitude)."""
    if _ringing_band_error(d)[1] <= ringing_tol:
        return
    K0 = np.abs((2.0 / np.pi) * (filon_weights(d["nodes"], [0.0]).real @ d["Bn"])[0])
    ring, relevant, _ = _ringing(d, K0)
    need = relevant & (ring > ringing_tol)
    Kpk = K0.copy()
    if need.any():
        Kpk[need] = np.abs((2.0 / np.pi) * _node_product(W, d, np.flatnonzero(need))).max(axis=0)
    ring, relevant, ringing = _ringing(d, Kpk)
    _warn_ringing(d, ring, relevant, ringing, ringing_tol, stacklevel=stacklevel + 1)


def impulse_response_memory(db: xr.Dataset, t, *, rtol: float = 0.01, tail: str = "extrapolate",
                            fit_fraction: float = 0.25, taper_fraction: float = 0.1,
                            noise: float = 0.005, extend: float = 1e3, n_extend: int = 300,
                            ringing_tol: float = 0.01, chunk: int = 512) -> float:
    """``memory_length(impulse_response(db, t, …), t, rtol=rtol)`` (same options, same ringing and
    undecayed warnings) without forming K for every time and entry.

    The scale of each entry needs only the diagonals' max|K_ii|; then the last time some |K_ij|
    exceeds its threshold is searched from t_end backwards, `chunk` times at a time, over the
    entries that count (finite scale; the upper triangle when B is symmetric), stopping at the
    first chunk with a hit: for a memory T_K of t_end, K is formed on (t_end − T_K)/t_end of the
    grid (Wu & Yuan: 234 of 400 s). The same numbers up to round-off.
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or np.any(t < 0):
        raise ValueError("t must be a 1-D array of times ≥ 0 (s).")
    d = _damping_nodes(db, tail, fit_fraction, taper_fraction, noise, extend, n_extend)
    nd = d["nd"]
    W = _filon_part(d["nodes"], t, "cos")                                  # (n_t, n_nodes)
    _check_ringing(d, W, ringing_tol, stacklevel=2)
    diag = np.arange(nd) * (nd + 1)
    Kmax_diag = np.abs((2.0 / np.pi) * _node_product(W, d, diag)).max(axis=0)
    scale = _relevant_scale(Kmax_diag, nd).ravel()
    cols, _ = _entries(d)
    cols = cols[np.isfinite(scale[cols])]
    thr = rtol * scale[cols]
    last = -1
    for b in range(len(t), 0, -chunk):
        a = max(b - chunk, 0)
        hit = np.flatnonzero((np.abs((2.0 / np.pi) * _node_product(W[a:b], d, cols)) > thr).any(axis=1))
        if hit.size:
            last = a + int(hit[-1])
            break
    if last < 0:
        return 0.0
    if last == len(t) - 1:
        warnings.warn(f"K(t) has not decayed below rtol={rtol:g} of its scale by t = {t[-1]:.4g} s: "
                      "extend t to find the memory length.", HydroDatabaseWarning, stacklevel=2)
        return float(t[-1])
    return float(t[last + 1])


# --------------------------------------------------------------------------- Ogilvie's relations
def _as_array(K, t):
    if isinstance(K, xr.DataArray):
        tt = np.asarray(K["time"].values if t is None else t, dtype=float)
        return np.asarray(K.transpose("time", ...).values, dtype=float), tt, K
    if t is None:
        raise ValueError("t is required when K is a plain array (time first).")
    return np.asarray(K, dtype=float), np.asarray(t, dtype=float), None


def _wrap(val, omega, Kda):
    if Kda is None:
        return val
    rest = [d for d in Kda.dims if d != "time"]
    return xr.DataArray(val, dims=("omega", *rest),
                        coords={"omega": omega, **{d: Kda[d].values for d in rest}})


def added_mass_from_irf(K, t=None, A_inf=None, omega=None):
    """A(ω) = A_inf − (1/ω) ∫_0^{t_end} K(t) sin(ωt) dt (eq. 2); ω > 0 (rad/s).

    K: DataArray (time, …) or array (n_t, …); A_inf broadcastable to K's trailing shape.
    Returns (n_ω, …) (a DataArray with dim omega when K is one).
    """
    if A_inf is None or omega is None:
        raise ValueError("added_mass_from_irf needs A_inf and omega.")
    Karr, tt, Kda = _as_array(K, t)
    omega = np.asarray(omega, dtype=float)
    if np.any(omega <= 0):
        raise ValueError("omega must be > 0 (A(0) is the limit; use a small omega).")
    S = filon_weights(tt, omega).imag
    integ = np.tensordot(S, Karr, axes=(1, 0))
    A = np.asarray(A_inf, dtype=float)[None] - integ / omega.reshape((-1,) + (1,) * (integ.ndim - 1))
    return _wrap(A, omega, Kda)


def damping_from_irf(K, t=None, omega=None):
    """B(ω) = ∫_0^{t_end} K(t) cos(ωt) dt (eq. 2); returns (n_ω, …)."""
    if omega is None:
        raise ValueError("damping_from_irf needs omega.")
    Karr, tt, Kda = _as_array(K, t)
    omega = np.asarray(omega, dtype=float)
    Cw = filon_weights(tt, omega).real
    return _wrap(np.tensordot(Cw, Karr, axes=(1, 0)), omega, Kda)


# ------------------------------------------------------------------------------ memory length
def _relevant_scale(Kmax_diag, nd):
    """sqrt(peak_ii peak_jj) per entry; dofs negligible beside their kind (1e-6) are excluded."""
    rot = (np.arange(nd) % 6) >= 3 if nd % 6 == 0 else np.zeros(nd, bool)
    kind_max = np.where(rot, Kmax_diag[rot].max(initial=0.0), Kmax_diag[~rot].max(initial=0.0))
    keep = Kmax_diag > 1e-6 * kind_max
    s = np.sqrt(np.outer(Kmax_diag, Kmax_diag))
    return np.where(np.outer(keep, keep), s, np.inf)


def memory_length(K, t=None, *, rtol: float = 0.01) -> float:
    """T_K (s): the time after which |K_ij(t)| < rtol · sqrt(max|K_ii| max|K_jj|) for all entries.

    The scale of entry (i, j) is that of its diagonals, so a weak coupling is judged against the
    motions it couples, not against itself. Dofs whose K is below 1e-6 of the largest of their kind
    (translation / rotation; e.g. yaw of an axisymmetric body, pure noise) are ignored. Warns
    if K has not decayed within the given t (then T_K = t_end).
    """
    Karr, tt, _ = _as_array(K, t)
    nd = Karr.shape[1]
    scale = _relevant_scale(np.abs(np.diagonal(Karr, axis1=1, axis2=2)).max(axis=0), nd)
    above = np.abs(Karr) > rtol * scale[None]
    any_above = above.reshape(len(tt), -1).any(axis=1)
    if not any_above.any():
        return 0.0
    last = int(np.flatnonzero(any_above)[-1])
    if last == len(tt) - 1:
        warnings.warn(f"K(t) has not decayed below rtol={rtol:g} of its scale by t = {tt[-1]:.4g} s: "
                      "extend t to find the memory length.", HydroDatabaseWarning, stacklevel=2)
        return float(tt[-1])
    return float(tt[last + 1])


def check_grid(db: xr.Dataset, memory_length: float, *, on_fail: str = "raise", band=None,
               dofs=None, tol: float = 0.05) -> float:
    """Check that the ω grid resolves the memory of length T_K = `memory_length` (s) that a run
    integrates, for the frequencies it needs.

    Aliasing. B(ω) sampled at spacing Δω and interpolated linearly gives (Poisson summation)
    K_PL(t) = sinc²(Δω t/2) Σ_n K(t − 2πn/Δω): K on [0, t_N], t_N = π/Δω, is told apart from its
    first alias K(2π/Δω − t); beyond t_N the grid cannot tell K from the alias. So T_K ≤ t_N
    passes outright (the ratio returned, Δω T_K/π, is then ≤ 1).

    T_K > t_N is not by itself an error: T_K is measured on K_PL, which holds the alias image of
    K's own peak at 2π/Δω, attenuated by the sinc² of the linear interpolation to about
    (Δω w/2π)² of the peak for a peak of width w (M4: Δω = 0.25 rad/s, w ≈ 1 s: 1.6e-3, above
    the memory's 1e-3), so a grid that resolves K still shows T_K ≈ 2π/Δω (M4 111: 21.8 s with K
    below 1 % of its scale from 6 s). What matters is what the run's radiation impedance takes
    from the part of the kernel the grid cannot resolve: E = max |∫_{t_N}^{T_K} K_ij e^{−iωt} dt| /
    sqrt(B_ii B_jj)_peak over the frequencies ω of the grid in `band` (the wave band: what the
    run's waves excite) and the `dofs` the run moves. Whether that part is K's own memory or its
    alias, the error it can make is of its size. It passes when E ≤ `tol`: 0.05, the asymmetry at
    which :func:`hydro.database.validate` calls the BEM coefficients themselves unconverged
    (same scale), below which a finer ω grid cannot make the run more accurate than its data.
    Δω is the largest step of the grid inside `band` (a coarser step outside it aliases the
    content of those frequencies, which stays at those frequencies).
    Returns E/tol when T_K > t_N (≤ 1 passes). on_fail: "raise" (ValueError) or "warn".
    """
    if on_fail not in ("raise", "warn"):
        raise ValueError(f"on_fail={on_fail!r}; accepted: 'raise', 'warn'.")
    om = np.asarray(db["omega"].values, dtype=float)
    if len(om) < 2:
        raise ValueError("the database has fewer than 2 frequencies: no impulse response possible.")
    lo, hi = (om[0], om[-1]) if band is None else (float(band[0]), float(band[1]))
    d = np.diff(om)
    # the steps that meet the band (a segment [ω_k, ω_k+1] overlapping [lo, hi])
    meet = (om[1:] >= lo) & (om[:-1] <= hi)
    k = int(np.flatnonzero(meet)[np.argmax(d[meet])]) if meet.any() else int(np.argmax(d))
    t_N = np.pi / d[k]
    if memory_length <= t_N:
        return float(memory_length / t_N)
    sub = db
    if dofs is not None:
        sub = db.isel(influenced_dof=list(dofs), radiating_dof=list(dofs))
    w = om[(om >= lo) & (om <= hi)]
    # the transform of K over [t_N, T_K] on a step resolving ω_max four times (as the other
    # transforms of K here); the truncation/ringing check is the business of impulse_response
    step = min(0.02, np.pi / om[-1] / 4.0)
    t = np.linspace(t_N, memory_length, max(int(np.ceil((memory_length - t_N) / step)), 1) + 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HydroDatabaseWarning)   # the ringing check is the caller's
        Z = impulse_response_transform(sub, t, w)
    B = np.asarray(sub["radiation_damping"].transpose("omega", "influenced_dof", "radiating_dof").values,
                   dtype=float)
    scale = _relevant_scale(np.abs(np.diagonal(B, axis1=1, axis2=2)).max(axis=0), B.shape[1])
    E = np.abs(Z) / scale[None]
    q = np.unravel_index(int(np.argmax(E)), E.shape)
    err = float(E[q])
    if err > tol:
        labels = [str(x) for x in sub["influenced_dof"].values]
        msg = (f"the omega grid is too coarse for a memory length T_K = {memory_length:.4g} s: "
               f"d omega = {d[k]:.4g} rad/s between {om[k]:.4g} and {om[k + 1]:.4g} rad/s resolves "
               f"K(t) up to pi/T_K = pi/{t_N:.4g} s only, and K beyond it changes the radiation "
               f"impedance by {err:.3g} of sqrt(B_ii B_jj) for ({labels[q[1]]}, {labels[q[2]]}) at "
               f"omega = {w[q[0]]:.4g} rad/s (tolerance {tol:g}). Recompute the database with a step "
               f"≤ {np.pi / memory_length:.4g} rad/s (or accept a shorter memory).")
        if on_fail == "raise":
            raise ValueError(msg)
        warnings.warn(msg, HydroDatabaseWarning, stacklevel=2)
    return err / tol


def radiation_band(omega, B, fraction: float = 0.05):
    """(ω_lo, ω_hi): where some diagonal damping B_ii(ω) is at least `fraction` of its own peak
    (B: (n_ω, n, n)); dofs whose peak is below 1e-6 of the largest of their kind (translation /
    rotation) are ignored. Above ω_hi the BEM damping is numerical noise (CAPYTAINE.md)."""
    om = np.asarray(omega, dtype=float)
    diag = np.einsum("wii->wi", np.asarray(B, dtype=float))
    peak = np.abs(diag).max(axis=0)
    active = np.zeros(len(om), dtype=bool)
    for i in range(diag.shape[1]):
        group = [j for j in range(diag.shape[1]) if (j % 6 < 3) == (i % 6 < 3)]
        if peak[i] > 1e-6 * peak[group].max():
            active |= diag[:, i] >= fraction * peak[i]
    idx = np.flatnonzero(active)
    if idx.size == 0:
        return float(om[0]), float(om[-1])
    return float(om[idx[0]]), float(om[idx[-1]])


def estimate_added_mass_inf(db: xr.Dataset, fraction: float = 0.05) -> np.ndarray:
    """A∞ (n, n) from A(ω) and B(ω) alone, for a database whose source has no infinite-frequency
    added mass (NEMOH; capytaine runs without ω = ∞).

    Ogilvie's relation (2) gives, at every ω of the grid, A∞ = A(ω) + (1/ω) ∫ K(t) sin(ωt) dt
    with K from B by (1); the estimate is its median over the band where radiation matters
    (:func:`radiation_band`: B_ii ≥ `fraction` of its peak), robust to the stretches where A(ω)
    is noisy or irregular; symmetrised. This is the constant :class:`hydro.prepare.HydroSpec`'s
    ``added_mass_inf = "consistent"`` adds to a database A∞, so with that option (the default) a
    model gets the same A∞ whether the source gave one or not. Checked on the shipped WAMIT RM3,
    whose .1 gives A∞: see tests/test_bem_formats.py.
    """
    om = np.asarray(db["omega"].values, dtype=float)
    A = np.asarray(db["added_mass"].values, dtype=float)
    with warnings.catch_warnings():
        # ringing / undecayed-K warnings concern a time-domain model, not this estimate
        warnings.simplefilter("ignore", HydroDatabaseWarning)
        t0 = np.arange(0.0, 400.0, 0.05)
        mem = impulse_response_memory(db, t0, rtol=1e-3)        # memory_length of K on t0
        t = np.arange(0.0, max(2.0 * mem, 60.0), min(0.02, np.pi / om.max() / 4.0))
        T = impulse_response_transform(db, t, om)        # ∫ K e^{−iωt} dt: Im = −∫ K sin ωt dt
    cand = A - T.imag / om[:, None, None]
    lo, hi = radiation_band(om, db["radiation_damping"].values, fraction)
    sel = (om >= lo) & (om <= hi)
    est = np.median(cand[sel], axis=0)
    return 0.5 * (est + est.T)
