"""Natural frequencies of the model linearised about its equilibrium: the generalised eigenproblem
with A(ω) iterated per mode, the minima of |det Λ(ω)| without and with damping (Hallak et al. §2.10),
the seed's closed form for three coordinates, and the damping that is a ratio of critical for one
mode of one body (``[[body_matrices]] damping_ratio``)."""
from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np

from ..radiation import label as radiation_label
from ..loads import body_matrix
from ..loads.base import MODES
from ..mechanics.model import Model
from ..mechanics.points import BodyPoints, h_matrix_at
from .response import _frequency_range, _mass_and_damping_at
from .rest import linear_system
from ..validation import check_model


class NaturalModes(NamedTuple):
    """The numbers of :func:`natural_modes` (the dataset of :func:`mfm.natural_frequencies`)."""
    loads: tuple            # the loads of the linearisation
    eigen: np.ndarray       # (mode,) rad/s
    modes: np.ndarray       # (coordinate, mode)
    damping_ratio: np.ndarray
    radiation_damping_ratio: np.ndarray
    min_det: np.ndarray     # (root,) rad/s
    settings: dict
    min_det_damped: np.ndarray


def natural_modes(model: Model, omega_grid=None, *, q0=None, iterations: int = 30,
                  loads=None, radiation: str = "database") -> NaturalModes:
    """Natural frequencies (rad/s) and damping ratios, two ways.

    eigen: the generalised eigenproblem K φ = ω² M(ω) φ, M(ω) = M + Hᵀ(A(ω) − A∞)H, iterated on ω
        for each mode (A at that mode's own frequency); coordinates without stiffness have no mode
        of their own and move freely with the others (condensed out of the mass:
        M_ss − M_sf M_ff⁻¹ M_fs, the free part of each mode shape −M_ff⁻¹ M_fs φ_s).
    min_det: local minima of |det Λ(ω)|, Λ = −ω² M_eff(ω) + K_ss, over ``omega_grid``
        (Hallak et al. §2.10), refined parabolically.
    min_det_damped: the same with the damping kept (Hallak et al. eq. 27's remark):
        |det(−ω² M(ω) − iω (C + B(ω)) + K)|, B(ω) the radiation damping, C the joint, PTO and
        body-matrix damping, free coordinates condensed out dynamically; refined by a bounded
        search (:func:`_damped_minima`). These are the peaks of the response to a force of
        constant amplitude, not the damped natural frequencies ω_n √(1 − ζ²) of free decay: for
        one dof |det|² = (k − mω²)² + (cω)², and d/d(ω²) = 0 gives
        ω² = (2km − c²)/(2m²) = ω_n² (1 − 2ζ²), ζ = c / (2√(km)). Seed 000 eq. 32 writes
        ω_n √(1 − ζ²) there, which is the free-decay frequency, not the minimum.
    damping_ratio: φᵀ C φ / (2 ω φᵀ M(ω) φ) of each mode for the linear damping C (joint dampers,
        hydraulic β, body matrices); radiation_damping_ratio the same with Hᵀ B(ω) H.

    Returns :class:`NaturalModes`; :func:`mfm.natural_frequencies` returns them as an
    xarray.Dataset: ``eigen``, ``period``, ``damping_ratio``, ``radiation_damping_ratio``,
    ``damped`` (mode), ``modes`` (coordinate, mode), ``min_det`` (root), ``min_det_damped``
    (root_damped); it reads like the former dict (``nat["eigen"]``).
    """
    model = check_model(model)
    if omega_grid is not None:
        try:
            grid = np.asarray(omega_grid, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"omega_grid: {omega_grid!r} is not an array of frequencies "
                             "(rad/s)") from None
        if grid.ndim != 1 or grid.size < 3 or not np.all(np.isfinite(grid)) \
                or np.any(grid <= 0) or np.any(np.diff(grid) <= 0):
            raise ValueError(f"omega_grid: give at least 3 positive, finite, ascending "
                             f"frequencies in rad/s (got {np.array2string(grid, threshold=8)}); "
                             "or None for 2,000 over the database's range")

    options = {"radiation": radiation}
    sys = linear_system(model, q0, loads=loads)
    K = sys.K
    lo, hi = _frequency_range(sys.loads)
    stiff = [k for k in range(model.n_coordinates) if np.abs(K[:, k]).max() > 1e-9 * np.abs(K).max()]
    # coordinates without stiffness move freely with the modes (a floating body's surge under
    # its pitch): condensed out of the mass, M_ss − M_sf M_ff⁻¹ M_fs, not clamped
    free = [k for k in range(model.n_coordinates) if k not in stiff]
    ix = np.ix_(stiff, stiff)
    Ks = K[ix]
    n = len(stiff)

    def condensed(Mw):
        """(M_eff (n, n), G (n_free, n)): the free coordinates follow as x_f = G x_s."""
        if not free:
            return Mw[ix], np.zeros((0, n))
        G = -np.linalg.solve(Mw[np.ix_(free, free)], Mw[np.ix_(free, stiff)])
        return Mw[ix] + Mw[np.ix_(stiff, free)] @ G, G

    def M_at(w):
        return _mass_and_damping_at(model, sys, w, options)[0][0]

    freqs, modes, zeta, zeta_rad = [], [], [], []
    w_start = hi if math.isfinite(hi) else 1.0
    lam0 = _eig_pair(Ks, condensed(M_at(w_start))[0])[0] if n else []
    for m in range(n):
        w = math.sqrt(max(lam0[m], 1e-30))
        for _ in range(iterations):
            Me, G = condensed(M_at(w))
            lam, vec = _eig_pair(Ks, Me)
            w_new = math.sqrt(max(lam[m], 1e-30))
            if abs(w_new - w) < 1e-10 * w:
                break
            w = w_new
        freqs.append(w)
        v = np.zeros(model.n_coordinates)
        v[stiff] = vec[:, m]
        v[free] = G @ vec[:, m]
        modes.append(v)
        Mw, Cr = _mass_and_damping_at(model, sys, w, options)
        mm = float(v @ Mw[0] @ v)
        zeta.append(float(v @ sys.C @ v) / (2 * w * mm))
        zeta_rad.append(float(v @ Cr[0] @ v) / (2 * w * mm))
    if omega_grid is None:
        top = hi if math.isfinite(hi) else 3.0 * max(freqs, default=1.0)
        grid = np.linspace(lo if lo > 0 else top / 2000, top, 2000)
    else:
        grid = np.asarray(omega_grid, dtype=float)
    Mg = _mass_and_damping_at(model, sys, grid, options)[0] if n else np.zeros((len(grid), 0, 0))
    det = np.array([abs(np.linalg.det(-w**2 * condensed(Mg[i])[0] + Ks)) for i, w in enumerate(grid)])
    mins = []
    for i in range(1, len(grid) - 1):
        if det[i] < det[i - 1] and det[i] <= det[i + 1]:
            # parabola through the log|det| of three points
            y0, y1, y2 = np.log(det[i - 1:i + 2] + 1e-300)
            h = grid[i + 1] - grid[i]
            den = y0 - 2 * y1 + y2
            mins.append(grid[i] + (0.5 * h * (y0 - y2) / den if den > 0 else 0.0))
    mins_damped = _damped_minima(model, sys, grid, stiff, free, options)
    modes = np.array(modes).T if modes else np.zeros((model.n_coordinates, 0))
    return NaturalModes(sys.loads, np.array(freqs), modes, np.array(zeta), np.array(zeta_rad),
                        np.array(mins), {"radiation": radiation_label(radiation)},
                        np.array(mins_damped))


def _eig_pair(K, M):
    """The generalised eigenpairs K φ = λ M φ (λ ascending, φ real, φᵀ M φ = 1 where it is
    positive). ``scipy.linalg.eigh`` where M is positive definite; else (a radiation strategy's
    A(ω) at a frequency where its mass is indefinite: a convolution's Ogilvie transform of a
    truncated K(t) at the end of a database, far from the mode the iteration is after) the
    general eigenproblem, its real parts: the iteration moves on to the mode's own frequency, where
    the mass is positive again. Raises LinAlgError only where neither solves."""
    import scipy.linalg

    try:
        return scipy.linalg.eigh(K, M)
    except np.linalg.LinAlgError:
        lam, vec = scipy.linalg.eig(K, M)
        keep = np.isfinite(lam)
        lam, vec = lam[keep].real, vec[:, keep].real
        order = np.argsort(lam)
        lam, vec = lam[order], vec[:, order]
        norm = np.einsum("im,ij,jm->m", vec, M, vec)
        vec = vec / np.sqrt(np.where(norm > 0, norm, 1.0))
        if lam.size < K.shape[0]:             # pad: the iteration indexes every mode
            lam = np.concatenate([lam, np.full(K.shape[0] - lam.size, lam.max(initial=1.0))])
            vec = np.concatenate([vec, np.zeros((K.shape[0], K.shape[0] - vec.shape[1]))], 1)
        return lam, vec


def _damped_minima(model, sys, grid, stiff, free, options):
    """Local minima over ``grid`` of |det Λ_d(ω)|, Λ_d = −ω² M(ω) − iω (C + B(ω)) + K, the free
    coordinates condensed out dynamically (Schur complement Λ_ss − Λ_sf Λ_ff⁻¹ Λ_fs, which is the
    undamped condensation when C = B = 0), each refined by a bounded Brent search on log|det|
    between its grid neighbours (|det Λ_d| is smooth at a damped minimum: no cusp)."""
    import scipy.optimize

    if not stiff:
        return []
    ss, sf, fs, ff = (np.ix_(a, b) for a, b in ((stiff, stiff), (stiff, free), (free, stiff),
                                                 (free, free)))

    def log_det(w):
        w = np.atleast_1d(np.asarray(w, dtype=float))
        Mw, Cr = _mass_and_damping_at(model, sys, w, options)
        W = w[:, None, None]
        L = -W**2 * Mw - 1j * W * (sys.C[None] + Cr) + sys.K[None]
        if free:
            L = L[(slice(None),) + ss] - L[(slice(None),) + sf] @ np.linalg.solve(
                L[(slice(None),) + ff], L[(slice(None),) + fs])
        return np.linalg.slogdet(L)[1]

    y = log_det(grid)
    out = []
    for i in range(1, len(grid) - 1):
        if y[i] < y[i - 1] and y[i] <= y[i + 1]:
            r = scipy.optimize.minimize_scalar(lambda w: float(log_det(w)[0]),
                                               bounds=(grid[i - 1], grid[i + 1]), method="bounded",
                                               options={"xatol": 1e-12 * grid[i]})
            out.append(float(r.x))
    return out


def cubic_natural_frequencies(M, K):
    """The three natural frequencies (rad/s, ascending) of a 3-dof undamped system with constant
    mass M and stiffness K (3, 3), from the cubic of Hallak et al. §2.11 (eqs. 37–44):

        P(λ) = det(K − λM) = â λ³ + b̂ λ² + ĉ λ + d̂,   λ = ω²,
        â = −det M,  b̂ = tr(adj(M) K),  ĉ = −tr(adj(K) M),  d̂ = det K

    (the expansion det(A + tB) = det A + t tr(adj(A) B) + t² tr(A adj(B)) + t³ det B). Its
    discriminant Δ₃ = 18âb̂ĉd̂ − 4b̂³d̂ + b̂²ĉ² − 4âĉ³ − 27â²d̂² (eq. 40) is > 0 for three distinct
    real roots; with Δ₀ = b̂² − 3âĉ, Δ₁ = 2b̂³ − 9âb̂ĉ + 27â²d̂ (eqs. 43, 44) Cardano's E of eq. 42
    is complex there, |E| = √Δ₀, arg E = φ/3 with cos φ = Δ₁ / (2 Δ₀^{3/2}), and eq. 41 becomes
    the trigonometric form

        λ_k = −(b̂ + 2 √Δ₀ cos((φ + 2πk)/3)) / (3â),   k = 0, 1, 2,

    (real arithmetic, no cancellation of complex parts). Each root is then polished by Newton
    steps on P itself. For symmetric M positive definite and symmetric K the roots are the
    generalised eigenvalues of (K, M): real; positive when K is positive definite.

    Raises ValueError when M or K is not a finite 3×3 matrix, when det M = 0 (no cubic), when
    Δ₃ < 0 (complex roots: M and K are not a symmetric pair with M positive definite) or when a
    root ω² ≤ 0 (K not positive definite: a mode without restoring stiffness, or unstable).
    """
    M = np.asarray(M, dtype=float)
    K = np.asarray(K, dtype=float)
    for name, A in (("M", M), ("K", K)):
        if A.shape != (3, 3) or not np.isfinite(A).all():
            raise ValueError(f"{name}: give a finite 3×3 matrix (got shape {A.shape}); the cubic "
                             "is for three coordinates (reduce the model first)")

    def adj(A):
        """The adjugate: the transposed cofactors (defined for a singular A too)."""
        return np.array([[(-1) ** (i + j) * np.linalg.det(np.delete(np.delete(A, j, 0), i, 1))
                          for j in range(3)] for i in range(3)])

    detM = np.linalg.det(M)
    if not abs(detM) > 1e-14 * np.abs(M).max() ** 3:
        raise ValueError(f"M: det M = {detM:.4g}: singular, so det(K − ω²M) is not a cubic in ω² "
                         "(a coordinate without inertia); give a positive definite mass matrix")
    a, b, c, d = -detM, np.trace(adj(M) @ K), -np.trace(adj(K) @ M), np.linalg.det(K)
    disc = 18 * a * b * c * d - 4 * b**3 * d + b**2 * c**2 - 4 * a * c**3 - 27 * a**2 * d**2
    d0 = b**2 - 3 * a * c
    d1 = 2 * b**3 - 9 * a * b * c + 27 * a**2 * d
    # scale of Δ₃ (each of its terms is of the size of (b̂ĉ)²): below it, a rounding of a double root
    scale = max(abs(18 * a * b * c * d), abs(b**3 * d), (b * c) ** 2, abs(a * c**3), (a * d) ** 2)
    if disc < -1e-10 * scale:
        raise ValueError(f"M, K: the cubic det(K − ω²M) has complex roots (discriminant Δ₃ = "
                         f"{disc:.4g} < 0): M and K are not a symmetric pair with M positive "
                         "definite")
    cos_phi = np.clip(d1 / (2 * max(d0, 0.0) ** 1.5), -1.0, 1.0) if d0 > 0 else 1.0
    phi = math.acos(cos_phi)
    lam = np.array([-(b + 2 * math.sqrt(max(d0, 0.0)) * math.cos((phi + 2 * math.pi * k) / 3))
                    / (3 * a) for k in range(3)])
    for _ in range(3):            # Newton on P: the rounding of the trigonometric form away
        P = ((a * lam + b) * lam + c) * lam + d
        dP = (3 * a * lam + 2 * b) * lam + c
        step = np.where(np.abs(dP) > 0, P / np.where(dP == 0, 1.0, dP), 0.0)
        lam = lam - step
    lam = np.sort(lam)
    if not lam[0] > 0:
        raise ValueError(f"K: the cubic det(K − ω²M) has the root ω² = {lam[0]:.4g} ≤ 0: K is not "
                         "positive definite (a mode without restoring stiffness, or an unstable "
                         "one); remove free coordinates first")
    return np.sqrt(lam)


def critical_damping(model: Model, body: str, mode: str, ratio: float, *, point=None,
                     loads=None, iterations: int = 30) -> float:
    """The damping coefficient (N s/m or N m s/rad) that is ``ratio`` of critical for one
    single-body mode of ``body`` (surge … yaw at ``point``, default its CoM), from the model's own
    linearisation: with φ the least-norm coordinate motion that moves that dof of the point by one
    unit, k = φᵀKφ, m(ω) = φᵀM(ω)φ (added mass at the mode's frequency, iterated), it is
    c = 2 ζ √(k m). Used by ``[[body_matrices]] damping_ratio``."""
    j = MODES.index(mode)
    i = model.body_index(body)
    pt = np.asarray(model.com[i]) if point is None else np.asarray(point, dtype=float)
    sys = linear_system(model, loads=loads)
    Hp = np.asarray(h_matrix_at(BodyPoints.on_bodies(model.com, [i], [pt]), sys.kin0))
    phi = np.linalg.pinv(Hp)[:, j]
    moved = float((Hp @ phi)[j]) if phi.size else 0.0
    if abs(moved) < 1e-9:
        raise ValueError(f"damping_ratio.{mode} of body {body!r}: no coordinate of the model moves "
                         f"that body in {mode}; give damping for the modes it has")
    phi = phi / moved
    k = float(phi @ sys.K @ phi)
    if not k > 0:
        raise ValueError(f"damping_ratio.{mode} of body {body!r}: the mode has no restoring "
                         f"stiffness (φᵀKφ = {k:.4g}), so critical damping is undefined; give the "
                         "damping in N s/m (or N m s/rad) instead")
    w = math.sqrt(k / float(phi @ sys.M @ phi))
    for _ in range(iterations):
        m = float(phi @ _mass_and_damping_at(model, sys, w, {"radiation": "database"})[0][0] @ phi)
        w_new = math.sqrt(k / m)
        if abs(w_new - w) < 1e-12 * w:
            break
        w = w_new
    return 2.0 * float(ratio) * math.sqrt(k * m)


def resolve_damping_ratios(model: Model, load):
    """``load`` with the fractions of critical damping it asks for (a
    :class:`~mfm.loads.LinearBodyMatrix`'s ``damping_ratios``) added to its damping, each
    :func:`critical_damping` of the model with this load (whose own damping does not enter: only
    K and M do). A load without any is returned as it is. :func:`mfm.load` calls this for each
    load of a config, with the model as built so far."""
    pending = getattr(load, "damping_ratios", ())
    if not pending:
        return load
    base = dataclasses.replace(load, damping_ratios=())
    out = base
    for p, body, mode, ratio, point in pending:
        c = critical_damping(model, body, mode, ratio, point=np.asarray(point, dtype=float),
                             loads=(base,))
        out = out.with_damping(p, mode, c)
    return out


body_matrix.register_resolver(resolve_damping_ratios)
