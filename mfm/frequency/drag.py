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
:mod:`mfm.studies.design` takes on the body's own velocity. The vector form is diagonal in Σ's
eigenbasis, each entry a one-dimensional Laplace integral (:func:`vector_coefficient`): along a
one-dimensional flow Borgman's √(8/π) σ, across it E|w| = √(2/π) σ.

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
# eigenvalues of Σ below RANK_TOL × the largest count as 0: the round-off of a flow along fewer
# axes (a direction of relative variance 1e-10 changes C by ~1e-5 of itself at most)
RANK_TOL = 1e-10
# the Laplace integrals of vector_coefficient: the trapezoidal rule in τ = ln s on [−80, 100]
# (s in units of 1/(2 λ_max)) with step 0.25: the integrands decay as e^{−|τ|/2} at both ends
# (below e^{−36} at the ends for every kept eigenvalue ≥ RANK_TOL λ_max) and are analytic in a
# strip of half-width π, so the rule's error is ~e^{−2π²/h}: round-off, at any axis ratio
_TAU = np.arange(-80.0, 100.0 + 0.125, 0.25)
_H = 0.25


def vector_coefficient(D, cov):
    """C = D E[|w| I + w wᵀ/|w|] (3, 3) for a zero-mean Gaussian w of covariance ``cov`` (3, 3);
    0 for a w that is 0.

    In Σ's eigenbasis (w = V y, y_i independent of variance λ_i) the expectation is diagonal (y_i
    → −y_i leaves the density unchanged): C = D V diag(E|y| + E[y_i²/|y|]) Vᵀ, each a Laplace
    integral from |y| = (2√π)⁻¹ ∫₀^∞ (1 − e^{−s|y|²}) s^{−3/2} ds,
    1/|y| = π^{−1/2} ∫₀^∞ e^{−s|y|²} s^{−1/2} ds and E[e^{−s|y|²}] = Π_k (1 + 2sλ_k)^{−1/2}:

        E|y| = (2√π)⁻¹ ∫₀^∞ [1 − Π_k (1 + 2sλ_k)^{−1/2}] s^{−3/2} ds,
        E[y_i²/|y|] = π^{−1/2} ∫₀^∞ λ_i (1 + 2sλ_i)^{−1} Π_k (1 + 2sλ_k)^{−1/2} s^{−1/2} ds,

    by the trapezoidal rule in ln s (round-off at any axis ratio). Along a one-dimensional flow of
    σ: D √(8/π) σ (Borgman's), across it D √(2/π) σ."""
    cov = 0.5 * (np.asarray(cov, dtype=float) + np.asarray(cov, dtype=float).T)
    lam, V = np.linalg.eigh(cov)
    top = lam.max()
    if not top > 0:
        return np.zeros((3, 3))
    # in units where 2 λ_max = 1 (|y| then scales back by √(2 λ_max))
    lam = np.where(lam > RANK_TOL * top, lam, 0.0) / (2 * top)
    sv = np.exp(_TAU)[:, None]
    log_f = np.log1p(2.0 * sv * lam[None])                            # (n_τ, 3)
    prod = np.exp(-0.5 * np.sum(log_f, axis=1))                       # E[e^{−s|y|²}]
    one_minus = -np.expm1(-0.5 * np.sum(log_f, axis=1))               # 1 − Π, no cancellation
    mean_norm = _H * np.sum(one_minus * np.exp(-0.5 * _TAU)) / (2 * math.sqrt(math.pi))
    mean_sq = _H * np.sum(lam[None] * np.exp(-log_f) * (prod * np.exp(0.5 * _TAU))[:, None],
                          axis=0) / math.sqrt(math.pi)
    d = math.sqrt(2 * top) * (mean_norm + mean_sq)
    return float(D) * (V * d[None]) @ V.T


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
