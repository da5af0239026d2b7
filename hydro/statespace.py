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

The fitting itself is :mod:`hydro.vectorfit` (vector fitting, ERA), the passivity enforcement
:mod:`hydro.passivity`; this module holds the pipeline, the realisation and the result.
"""
from __future__ import annotations

import dataclasses
import time as _time
from types import MappingProxyType

import numpy as np
import xarray as xr

from .passivity import _enforce_passivity, _enforce_passivity_common, _passivity_grid
from .phases import every, say
from .radiation import filon_weights, impulse_response, impulse_response_transform, memory_length
from .vectorfit import _basis, _era_fit, _pole_residue, _vf


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
    for k, n in enumerate(orders):
        say(f"state-space fit: order {n} ({k + 1} of at most {len(orders)})")
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
        for e, (i, j) in enumerate(entries):
            if e % every(len(entries)) == 0:
                say(f"state-space fit: entry {e + 1} of {len(entries)}")
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
    say("state-space fit: its realisation and report (band errors, passivity to 100 ω_max)")
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
