"""Stochastic linearisation of quadratic drag on the relative flow, for the spectral level.

A quadratic drag on the velocity of a point relative to the incident wave's flow there,

    f = D |w| w,   w = P (u − v),   v = R q̇ (the point's velocity, first order about q₀),

(u the flow's velocity at the point's rest position, P a projector: the identity, or I − e eᵀ the
part normal to a slender member of axis e; R = P H the projected rows of ξ̇ = H q̇), is replaced
in a Gaussian sea by the linear force of least mean-square error (Atalik & Utku 1976; Stein's
lemma for a zero-mean Gaussian w of covariance Σ):

    f ≈ C w,   C = E[∂f/∂w] = D E[|w| I + w wᵀ/|w|]            (a vector drag: |w| its length)
    C = diag(D_a √(8/π) σ_a),   σ_a² = Σ_aa                       (a drag per axis, |w_a| w_a)

— per axis Borgman's c_eq = D √(8/π) σ (E[|w| w · w]/E[w²] for a scalar Gaussian), which
:mod:`mfm.studies.design` takes on the body's own velocity. The vector form: with w = L z
(L Lᵀ = Σ, z standard normal in the rank r of Σ), E[J(w)] = E[ρ] · mean over the unit sphere
S^{r−1} of J(L n) (J homogeneous of degree 1, ρ = |z| chi-distributed with r degrees of freedom:
E[ρ] = √2 Γ((r+1)/2)/Γ(r/2)); the sphere's mean by exact points for r = 1 (n = ±1: Borgman's
√(8/π) σ along the flow), the trapezoidal rule on the circle for r = 2 and Gauss–Legendre in
cos θ times the trapezoidal rule in φ for r = 3 (J(Ln) smooth where Σ has full rank r: both
converge geometrically).

Put in the equation of motion (x(t) = Re[x̂ e^{−iωt}], per unit complex wave amplitude,
Z(ω) x̂ = F(ω) of :mod:`mfm.frequency.response`), C w = C P û − C R q̇ gives

    [Z(ω_j) − iω_j Σ_p R_pᵀ C_p R_p] x̂_j = F(ω_j, β_j) + Σ_p R_pᵀ C_p P_p û_p(ω_j, β_j),
    ŵ_pj = P_p û_pj + iω_j R_p x̂_j   (relative flow u − v),
    Σ_p = Σ_j ½ a_j² Re[ŵ_pj ŵ_pjᴴ],

û the linear particle velocity per unit amplitude of each component at the point's rest position
(:func:`hydro.wetted.velocity_transfer`: every component of the sea, headings and spreading as the
time domain's), a_j the components' amplitudes. C depends on Σ, which depends on C: the pair is
iterated to a fixed point from C = 0 (:func:`linearise`), per sea state.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..loads.base import QuadraticDrag

# Borgman's factor: E[|v| v · v] / E[v²] = √(8/π) σ for a zero-mean Gaussian v
BORGMAN = math.sqrt(8.0 / math.pi)
# the fixed point: stopped once max|ΔC| ≤ TOL · max|C| or after MAX_ITERATIONS
TOL, MAX_ITERATIONS = 1e-10, 200
# eigenvalues of Σ below RANK_TOL × the largest count as 0 (a flow along fewer axes: w = L z in
# the rank of Σ; a direction of relative variance 1e-10 changes C by ~1e-5 of itself at most)
RANK_TOL = 1e-10
# quadrature on the unit circle (r = 2) and sphere (r = 3): geometric convergence for a smooth
# J(Ln); 256 and 48 × 96 points leave < 1e-12 for axis ratios of Σ down to ~1e-2 (tests)
N_CIRCLE, N_THETA, N_PHI = 256, 48, 96


def _sphere_mean_J(L, r):
    """The mean over the unit sphere S^{r−1} of J(L n) = |Ln| I + (Ln)(Ln)ᵀ/|Ln|, L (3, r)."""
    if r == 1:
        n = np.array([[1.0], [-1.0]])
        wts = np.array([0.5, 0.5])
    elif r == 2:
        phi = 2 * np.pi * np.arange(N_CIRCLE) / N_CIRCLE
        n = np.stack([np.cos(phi), np.sin(phi)], axis=1)
        wts = np.full(N_CIRCLE, 1.0 / N_CIRCLE)
    else:
        c, wc = np.polynomial.legendre.leggauss(N_THETA)         # cos θ on [−1, 1]
        phi = 2 * np.pi * np.arange(N_PHI) / N_PHI
        s = np.sqrt(1 - c**2)
        n = np.stack([(s[:, None] * np.cos(phi)).ravel(), (s[:, None] * np.sin(phi)).ravel(),
                      np.repeat(c, N_PHI)], axis=1)
        wts = (np.repeat(wc, N_PHI) / (2 * N_PHI))                # sums to 1: the mean
    w = n @ L.T                                                   # (N, 3)
    m = np.linalg.norm(w, axis=1)
    inv = np.where(m > 0, 1.0 / np.where(m > 0, m, 1.0), 0.0)
    J = m[:, None, None] * np.eye(3) + w[:, :, None] * w[:, None, :] * inv[:, None, None]
    return np.einsum("n,nab->ab", wts, J)


def chi_mean(r: int) -> float:
    """E[|z|] for z standard normal in r dimensions: √2 Γ((r+1)/2)/Γ(r/2)."""
    return math.sqrt(2.0) * math.exp(math.lgamma((r + 1) / 2) - math.lgamma(r / 2))


def vector_coefficient(D, cov):
    """C = D E[|w| I + w wᵀ/|w|] (3, 3) for a zero-mean Gaussian w of covariance ``cov`` (3, 3)
    (module docstring); 0 for a w that is 0."""
    cov = 0.5 * (np.asarray(cov, dtype=float) + np.asarray(cov, dtype=float).T)
    lam, V = np.linalg.eigh(cov)
    top = lam.max()
    if not top > 0:
        return np.zeros((3, 3))
    keep = lam > RANK_TOL * top
    L = V[:, keep] * np.sqrt(lam[keep])[None]
    r = int(keep.sum())
    return float(D) * chi_mean(r) * _sphere_mean_J(L, r)


def coefficients(group: QuadraticDrag, cov):
    """C (P, 3, 3) of each point of ``group`` for the covariances ``cov`` (P, 3, 3) of its
    relative flow w (module docstring)."""
    if group.kind == "axis":
        sigma = np.sqrt(np.clip(np.einsum("paa->pa", cov), 0.0, None))
        return np.einsum("pa,ab->pab", np.asarray(group.drag) * BORGMAN * sigma, np.eye(3))
    return np.stack([vector_coefficient(D, c) for D, c in zip(group.drag, cov)]) \
        if len(cov) else np.zeros((0, 3, 3))


class Linearised(NamedTuple):
    """The fixed point of :func:`linearise`: ``x`` (n_j, n_q) the RAOs with the linearised drag,
    ``C`` (P, 3, 3) the equivalent damping of every point (the groups' in turn), ``sigma`` (P, 3)
    the standard deviation of the relative flow w = P(u − v) per inertial axis, ``iterations``
    and ``change`` (the last relative change of C: ≤ TOL when converged)."""
    x: np.ndarray
    C: np.ndarray
    sigma: np.ndarray
    iterations: int
    change: float


def linearise(groups, Z, F, omega, amplitude, U):
    """The stochastic linearisation of the module docstring for one sea state.

    groups: the :class:`QuadraticDrag` of the loads. Z (n_j, n_q, n_q), F (n_j, n_q): the linear
    system of each component without the drag. omega, amplitude (n_j,): the components'. U: one
    (n_j, P_g, 3) array per group, the flow's velocity per unit complex amplitude at its points
    (unprojected: :func:`hydro.wetted.velocity_transfer`). Returns a :class:`Linearised`."""
    R = np.concatenate([g.rows for g in groups])                               # (P, 3, n)
    Pu = np.concatenate([np.einsum("pab,jpb->jpa", g.project, u) for g, u in zip(groups, U)],
                        axis=1)                                                # (n_j, P, 3)
    sizes = np.cumsum([0] + [len(g.rows) for g in groups])
    half_a2 = 0.5 * np.asarray(amplitude, dtype=float) ** 2
    w = np.asarray(omega, dtype=float)
    C = np.zeros((len(R), 3, 3))
    change, it = np.inf, 0

    def solve(C):
        Cq = np.einsum("pai,pab,pbj->ij", R, C, R)
        x = np.linalg.solve(Z - 1j * w[:, None, None] * Cq[None],
                            (F + np.einsum("pai,pab,jpb->ji", R, C, Pu))[..., None])[..., 0]
        W = Pu + 1j * w[:, None, None] * np.einsum("pai,ji->jpa", R, x)       # u − v
        cov = np.einsum("j,jpa,jpb->pab", half_a2, W, W.conj()).real
        return x, cov

    while it < MAX_ITERATIONS:
        x, cov = solve(C)
        C_new = np.concatenate([coefficients(g, cov[sizes[k]:sizes[k + 1]])
                                for k, g in enumerate(groups)])
        scale = np.abs(C_new).max() if C_new.size else 0.0
        change = float(np.abs(C_new - C).max() / scale) if scale > 0 else 0.0
        C, it = C_new, it + 1
        if change <= TOL:
            break
    x, cov = solve(C)
    sigma = np.sqrt(np.clip(np.einsum("paa->pa", cov), 0.0, None))
    return Linearised(x, C, sigma, it, change)
