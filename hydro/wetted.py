"""Pressure on the instantaneous wetted hull: nonlinear hydrostatics and Froude–Krylov.

The linear model takes the buoyancy as a constant force at the still-water centre of buoyancy, the
restoring as the water-plane stiffness C_wp and the incident wave's pressure (Froude–Krylov) on the
mean wetted surface. Here the pressure of the undisturbed flow is integrated over the part of a
closed hull mesh below the instantaneous free surface, at the body's instantaneous pose:

    F = −∫_{S_w(t)} p n dA,    M_r = −∫_{S_w(t)} (x − r) × n p dA,
    p(x, t) = −ρ g z + ρ g Σ_j a_j f_j(z_s) cos(k_j (x cos β_j + y sin β_j) − ω_j t + φ_j),

with n the outward normal, S_w(t) the panels cut at z = η(x, y, t) (Σ_j a_j cos(…) at z = 0) and
f_j the depth decay, cosh k_j(z_s + h)/cosh k_j h (e^{k_j z_s} in deep water).

**Above the mean level, Wheeler stretching**: the decay is evaluated at z_s = h (z − η)/(h + η)
(z − η in deep water), which maps the instantaneous surface to z_s = 0, so the total pressure
−ρ g η + ρ g η is zero exactly where the hull is cut (linear extrapolation, f = 1 + k z above 0,
is not: the cut would carry a pressure jump). Below a trough it makes the decay follow the
surface as well. It is the usual choice of nonlinear Froude–Krylov models on linear waves
(WEC-Sim's and OpenFAST's mesh-based forces take the same pressure field); its error against a
nonlinear wave is O((ka)²), the order this level keeps anyway.

**The cut**: each triangle is cut along the zero line of s = z − η interpolated linearly from its
vertices (exact for still water, where s = z; for a wave its error is that of the linear
interpolation of η over a panel, O(k² h_panel²)). A cut triangle is a triangle or a quadrilateral
(two triangles), so every input triangle gives at most two wet triangles (static shapes: jit and
vmap over bodies and cases without retracing).

**Quadrature**: on each wet triangle the edge-midpoint rule, exact for quadratics: the hydrostatic
force and moment (p linear, (x − r) p quadratic) are exact for the polyhedron whatever the pose;
for the wave pressure it is second order in the panel size.

Everything is jax (float64), differentiable almost everywhere (the cut's topology changes where a
vertex crosses the surface: there the loads are continuous, their derivative jumps).
"""
from __future__ import annotations

import math
import equinox as eqx
import jax.numpy as jnp
import numpy as np

# an edge whose ends' s differ by no more than this runs along the surface: no crossing point on
# it (no division by 0)
_TINY = 1e-300


class WaveField(eqx.Module):
    """Linear incident wave components, arrays (J,) float64: ``amplitude`` (m, ramp included),
    ``omega`` (rad/s), ``wavenumber`` (rad/m), ``heading`` (rad, 0 = towards +x), ``phase`` (rad);
    ``water_depth`` (m; inf for deep water; static). η = Σ a cos(k(x cos β + y sin β) − ω t + φ)."""
    amplitude: jnp.ndarray
    omega: jnp.ndarray
    wavenumber: jnp.ndarray
    heading: jnp.ndarray
    phase: jnp.ndarray
    water_depth: float = eqx.field(static=True, default=math.inf)

    @classmethod
    def of(cls, components, pad_to: int | None = None, g: float | None = None) -> "WaveField":
        """The field of :class:`hydro.waves.WaveComponents` (no ramp). ``pad_to``: that many
        components, the ones beyond the sea's of zero amplitude at ω = 1 rad/s (its wavenumber at
        the depth and ``g``, default the components' g: finite and positive, so every depth decay
        stays finite and every term a padded component adds is 0 · finite = 0 exactly): one
        structure for the cases of a batch whose seas have fewer components than its most."""
        cols = [np.asarray(getattr(components, k), dtype=float)
                for k in ("amplitude", "omega", "wavenumber", "heading", "phase")]
        n = len(cols[0])
        if pad_to is not None and pad_to != n:
            from .waves import wavenumber

            if pad_to < n:
                raise ValueError(f"pad_to = {pad_to}: fewer than the sea's {n} components")
            g = float(getattr(components, "g", 9.81) if g is None else g)
            k1 = float(wavenumber(1.0, float(components.water_depth), g))
            fill = (0.0, 1.0, k1, 0.0, 0.0)
            cols = [np.concatenate([c, np.full(pad_to - n, v)]) for c, v in zip(cols, fill)]
        return cls(*(jnp.asarray(c) for c in cols), float(components.water_depth))


def still_water() -> WaveField:
    z = jnp.zeros(0)
    return WaveField(z, z, z, z, z)


def ramped(wave: WaveField, T, t) -> WaveField:
    """``wave`` with its amplitudes ramped at t as the excitation is (:func:`hydro.waves.ramp`:
    ½(1 − cos πt/T) before T, 1 after; T = 0: 1). T and t may be traced."""
    r = jnp.where(T > 0, 0.5 * (1 - jnp.cos(jnp.pi * jnp.clip(t, 0.0, T) / jnp.where(T > 0, T, 1.0))),
                  1.0)
    return type(wave)(wave.amplitude * r, wave.omega, wave.wavenumber, wave.heading, wave.phase,
                      wave.water_depth)


def still(wave: WaveField) -> WaveField:
    """``wave`` with no components (still water), its depth kept."""
    z = jnp.zeros((0,), jnp.float64)
    return type(wave)(z, z, z, z, z, wave.water_depth)


def triangles(vertices, faces) -> np.ndarray:
    """The panels of a mesh as triangles (n, 3, 3): ``vertices`` (V, 3), ``faces`` (F, 3) or
    (F, 4) vertex indices ordered for the outward normal (a quadrilateral split along its first
    diagonal; one whose last index repeats is a triangle). Degenerate triangles (zero area) are
    dropped."""
    V = np.asarray(vertices, float)
    F = np.asarray(faces, dtype=np.int64)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ValueError(f"vertices: shape {V.shape}; give (V, 3) in m")
    if F.ndim != 2 or F.shape[1] not in (3, 4):
        raise ValueError(f"faces: shape {F.shape}; give (F, 3) or (F, 4) vertex indices")
    if F.size and (F.min() < 0 or F.max() >= len(V)):
        raise ValueError(f"faces: indices in [{F.min()}, {F.max()}]; the mesh has {len(V)} vertices")
    T = V[F[:, [0, 1, 2]]]
    if F.shape[1] == 4:
        T = np.concatenate([T, V[F[:, [0, 2, 3]]]], axis=0)
    area = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    scale = max(float(np.ptp(V, axis=0).max()) if len(V) else 1.0, 1e-300)
    return np.ascontiguousarray(T[area > 1e-14 * scale**2])


def closed_volume(tri) -> float:
    """Σ a·(b×c)/6 over the triangles: the volume a closed surface encloses (> 0 for outward
    normals)."""
    from .meshfiles import closed_volume as vol

    return vol(tri)


def check_hull(tri, *, what: str, fix: str | None = None) -> None:
    """Refuse a hull that is not a closed, outward-facing surface: every edge shared by exactly
    two triangles run in opposite directions, and a positive enclosed volume. (A nonlinear level
    cuts the hull anywhere: a hole or a face turned inward changes the force wherever it gets
    wet.) Errors start with ``what``, give the number of bad edges and a sample of them (m), and
    the fix; ``fix`` replaces the open hull's (a mesh file's choices)."""
    from .meshfiles import edge_report, edges_text

    T = np.asarray(tri, float)
    if T.ndim != 3 or T.shape[1:] != (3, 3) or not len(T):
        raise ValueError(f"{what}: no triangles; give a closed hull mesh (vertices and faces)")
    rep = edge_report(T)
    if len(rep["non_manifold"]):
        E = rep["non_manifold"]
        raise ValueError(f"{what}: {len(E)} non-manifold edge(s), shared by three or more "
                         f"triangles ({edges_text(E)}): duplicated or crossing panels; a hull is "
                         "one closed surface: remove the extra panels")
    if len(rep["open"]):
        E = rep["open"]
        raise ValueError(f"{what}: {len(E)} edge(s) belong to one triangle only ({edges_text(E)}): "
                         "the hull is open; " + (fix or "a nonlinear level needs the whole closed "
                                                 "hull, above the water line too"))
    if len(rep["flipped"]):
        E = rep["flipped"]
        raise ValueError(f"{what}: {len(E)} edge(s) run the same way in two triangles "
                         f"({edges_text(E)}): the faces are not ordered consistently (some "
                         "normals point inward); reorder them for outward normals")
    vol = closed_volume(T)
    if vol <= 0:
        raise ValueError(f"{what}: enclosed volume {vol:.6g} m³ ≤ 0: the normals point inward; "
                         "reverse the order of every face")


# ------------------------------------------------------------------------------ the free surface
def _phase_rows(wave, x, y, t):
    """The components' phases k (x cos β + y sin β) − ω t + φ at points given as rows x, y
    (..., n): (J, ..., n)."""
    shape = (-1,) + (1,) * x.ndim
    c, s = jnp.cos(wave.heading).reshape(shape), jnp.sin(wave.heading).reshape(shape)
    return (wave.wavenumber.reshape(shape) * (x[None] * c + y[None] * s)
            - (wave.omega * t - wave.phase).reshape(shape))


def _stretched(z, eta, h):
    """Wheeler's z_s: h (z − η)/(h + η), z − η in deep water (module docstring)."""
    return z - eta if math.isinf(h) else h * (z - eta) / (h + eta)


def _decay(k, zs, h):
    """cosh k(z_s + h)/cosh k h (e^{k z_s} in deep water) at z_s ≤ 0 (clipped to [−h, 0]),
    without overflow: e^{k z_s} (1 + e^{−2k(z_s+h)})/(1 + e^{−2kh})."""
    if math.isinf(h):
        return jnp.exp(k * jnp.minimum(zs, 0.0))
    zc = jnp.clip(zs, -h, 0.0)
    return jnp.exp(k * zc) * (1 + jnp.exp(-2 * k * (zc + h))) / (1 + jnp.exp(-2 * k * h))


def _velocity_decays(k, zs, h, xp):
    """The particle velocity's depth decays at z_s ≤ 0: f_h = cosh k(z_s + h)/sinh k h and
    f_v = sinh k(z_s + h)/sinh k h (z_s clipped to [−h, 0]; e^{k z_s} both in deep water), without
    overflow: e^{k z_s} (1 ± e^{−2k(z_s+h)})/(1 − e^{−2kh}). ``xp``: jax.numpy in the time
    domain's traced code, numpy on the frequency domain's host side (the same operations)."""
    if math.isinf(h):
        f = xp.exp(k * zs)
        return f, f
    zc = xp.clip(zs, -h, 0.0)
    e, d = xp.exp(k * zc), 1 - xp.exp(-2 * k * h)
    return e * (1 + xp.exp(-2 * k * (zc + h))) / d, e * (1 - xp.exp(-2 * k * (zc + h))) / d


def _kinematics(wave: WaveField, points, t):
    """What the flow's velocity and acceleration share at ``points`` (..., 3): the phases θ
    (J, ...), the depth decays f_h, f_v (J, ...) at the Wheeler-stretched z_s, a ω (J, 1…), the
    heading's cos and sin (J, 1…), and whether each point is under the instantaneous surface
    (...)."""
    x, y, z = points[..., 0], points[..., 1], points[..., 2]
    th = _phase_rows(wave, x, y, t)                                        # (J, ...)
    shape = (-1,) + (1,) * x.ndim
    a, k = wave.amplitude.reshape(shape), wave.wavenumber.reshape(shape)
    eta = jnp.sum(a * jnp.cos(th), axis=0)
    h = wave.water_depth
    fh, fv = _velocity_decays(k, jnp.minimum(_stretched(z, eta, h), 0.0), h, jnp)
    return (th, fh, fv, a * wave.omega.reshape(shape), jnp.cos(wave.heading).reshape(shape),
            jnp.sin(wave.heading).reshape(shape), z <= eta)


def particle_velocity(wave: WaveField, points, t):
    """The undisturbed flow's velocity (m/s) at ``points`` (..., 3), inertial axes: linear wave
    kinematics, each component's

        u_h = a ω f_h(z_s) cos θ (cos β, sin β),   u_z = a ω f_v(z_s) sin θ,
        θ = k (x cos β + y sin β) − ω t + φ,

    f_h = cosh k(z_s + h)/sinh k h, f_v = sinh k(z_s + h)/sinh k h (e^{k z_s} both in deep water),
    at the Wheeler-stretched z_s of the pressure (module docstring); 0 at a point above the instantaneous surface
    (in air: a reference point on the mean level has flow under a crest, none under a trough,
    so its mean drag follows the wave, as the flow's mean above the troughs does; the surface's
    flow carried up to it would push it back under every trough)."""
    if wave.amplitude.shape[0] == 0:
        return jnp.zeros(jnp.shape(points))
    th, fh, fv, aw, cb, sb, wet = _kinematics(wave, points, t)
    c = aw * fh * jnp.cos(th)
    u = jnp.stack([jnp.sum(c * cb, axis=0), jnp.sum(c * sb, axis=0),
                   jnp.sum(aw * fv * jnp.sin(th), axis=0)], axis=-1)
    return jnp.where(wet[..., None], u, 0.0)


def particle_acceleration(wave: WaveField, points, t):
    """The undisturbed flow's local acceleration ∂u/∂t (m/s²) at ``points`` (..., 3), inertial
    axes, of the linear kinematics of :func:`particle_velocity` (the same f_h, f_v at the same
    Wheeler-stretched z_s, 0 above the instantaneous surface):

        u̇_h = a ω² f_h(z_s) sin θ (cos β, sin β),   u̇_z = −a ω² f_v(z_s) cos θ.

    Linear theory's: the convective part u·∇u and the stretching's own time derivative (through
    η(t) in z_s) are second order in ka, the order the stretching itself leaves out. What
    Morison's inertia term ρ (1 + C_A) V u̇ takes."""
    if wave.amplitude.shape[0] == 0:
        return jnp.zeros(jnp.shape(points))
    th, fh, fv, aw, cb, sb, wet = _kinematics(wave, points, t)
    w = wave.omega.reshape(aw.shape)
    s = aw * w * fh * jnp.sin(th)
    a = jnp.stack([jnp.sum(s * cb, axis=0), jnp.sum(s * sb, axis=0),
                   -jnp.sum(aw * w * fv * jnp.cos(th), axis=0)], axis=-1)
    return jnp.where(wet[..., None], a, 0.0)


def velocity_transfer(points, omega, wavenumber, heading, water_depth: float) -> np.ndarray:
    """The linear particle velocity per unit complex wave amplitude at fixed ``points`` (P, 3)
    (inertial, at rest) for components (ω_j, k_j, β_j) (n,): û (n, P, 3) complex with
    u(t) = Re[c û e^{−iωt}] for a component of complex amplitude c = a e^{iφ} (the hydro
    databases' convention; :func:`particle_velocity` of that component to first order in a):

        û_h = ω f_h(z) e^{ik(x cos β + y sin β)} (cos β, sin β),
        û_z = −i ω f_v(z) e^{ik(x cos β + y sin β)},

    f_h = cosh k(z + h)/sinh k h, f_v = sinh k(z + h)/sinh k h (e^{kz} both in deep water), at the
    rest depth z (the stretching is second order); 0 at a point above the mean surface (dry at
    rest). The acceleration's is −iω û. numpy (the frequency domain's host side)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    w = np.asarray(omega, dtype=float).reshape(-1, 1)
    k = np.asarray(wavenumber, dtype=float).reshape(-1, 1)
    b = np.asarray(heading, dtype=float).reshape(-1, 1)
    x, y, z = p[None, :, 0], p[None, :, 1], np.minimum(p[None, :, 2], 0.0)
    fh, fv = _velocity_decays(k, z, float(water_depth), np)
    ph = w * np.exp(1j * k * (x * np.cos(b) + y * np.sin(b)))
    wet = (p[None, :, 2] <= 0.0)
    u = np.stack([ph * fh * np.cos(b), ph * fh * np.sin(b), -1j * ph * fv], axis=-1)
    return np.where(wet[..., None], u, 0.0)


# ------------------------------------------------------------------------------------- the cut
def _norm(v):
    """|v| over the last axis with a derivative at v = 0 (0 there, not 0/0: an absent piece of
    a cut is a zero triangle, and its weight 0 must not meet a NaN)."""
    n2 = jnp.sum(v * v, axis=-1)
    pos = n2 > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, n2, 1.0)), 0.0)


def _wet_pieces(V, S):
    """The wet part (s < 0) of triangles given as rows, ``V`` their three vertices (3, n) each and
    ``S`` the surface function s at them (n,) each: each triangle's at most two wet triangles
    (module docstring) as their areas ``A`` (2, 1, n) (0 for an absent piece), every piece's edge
    midpoints ``X`` (3, 6n) (piece, edge, triangle order: the quadrature's points) and the
    parents' unit outward normals ``n_hat`` (3, n) (the pieces keep no orientation).

    The vertex order comes from a three-comparator sorting network (element-wise: XLA vectorises
    it, where a sort and gathers on (n, 3, 3) blocks cost 2.2 times the whole integral)."""
    V, S = list(V), list(S)
    area_n = 0.5 * _cross(V[1] - V[0], V[2] - V[0])                       # (3, n): A n̂
    n_hat = area_n / _norm(area_n.T)[None]

    parity = [jnp.ones_like(S[0])]

    def swap(i, j):
        # a compare-swap of the sorting network: after it S[i] ≤ S[j]; a swap turns the
        # vertices' order (parity −1)
        c = S[j] < S[i]
        V[i], V[j] = jnp.where(c, V[j], V[i]), jnp.where(c, V[i], V[j])
        S[i], S[j] = jnp.where(c, S[j], S[i]), jnp.where(c, S[i], S[j])
        parity[0] = jnp.where(c, -parity[0], parity[0])

    swap(0, 1)
    swap(1, 2)
    swap(0, 1)
    v0, v1, v2 = V
    s0, s1, s2 = S

    def point(va, sa, vb, sb):
        # where s crosses 0 on the edge a→b; a safe denominator where the edge does not cross
        d = sa - sb
        ok = jnp.abs(d) > _TINY
        f = jnp.where(ok, jnp.clip(sa / jnp.where(ok, d, 1.0), 0.0, 1.0), 0.0)
        return va + f * (vb - va)

    p01, p02, p12 = point(v0, s0, v1, s1), point(v0, s0, v2, s2), point(v1, s1, v2, s2)
    one = (s0 < 0) & (s1 >= 0)            # one vertex wet: a triangle
    two = (s1 < 0) & (s2 >= 0)            # two wet: a quadrilateral, two triangles
    all3 = s2 < 0
    first = (v0, jnp.where(one, p01, v1), jnp.where(one, p02, jnp.where(two, p12, v2)))
    second = (v0, p12, p02)
    weights = ((one | two | all3).astype(v0.dtype), two.astype(v0.dtype))
    areas, mids = [], []
    for (a, b, c), wk in zip((first, second), weights):
        # each piece runs as its sorted parent does (v0 v1 v2; v0 p12 p02 keeps that turn): its
        # area is its signed area along the parent's normal times the sort's parity. Smooth where
        # a piece is degenerate (a vertex on the surface: a quadrilateral's second half, zero at
        # rest, grows linearly with the motion), where |·| has no derivative and the safe norm's
        # is 0: the stiffness at rest lost that piece's growth
        areas.append(0.5 * jnp.sum(_cross(b - a, c - a) * n_hat, axis=0) * parity[0] * wk)
        mids.extend(((a + b) / 2, (b + c) / 2, (c + a) / 2))
    return jnp.stack(areas)[:, None], jnp.concatenate(mids, axis=1), n_hat


def pressure_loads(tri_body, rotation, origin, ref, wave: WaveField, t, *, rho: float, g: float,
                   parts: bool = False):
    """Force (3,) and moment about ``ref`` (3,) of the flow's pressure on the wetted part of a
    hull, inertial axes (module docstring).

    tri_body: (n, 3, 3) the closed hull's triangles in body axes about the body's origin, ordered
    for outward normals (:func:`triangles`, :func:`check_hull`); rotation (3, 3) and origin (3,):
    the pose, x = origin + rotation @ x_b; ref (3,): the moment's point; wave: the incident wave
    (:func:`still_water` for hydrostatics alone); t: s. ``parts``: return the hydrostatic
    pressure's (−ρ g z) and the wave's (nonlinear Froude–Krylov) loads apart, each (6,), on the
    same cut: (hydrostatic, froude_krylov).
    """
    hs, fk = pressure_loads_rows(soa(tri_body), rotation, origin, ref, wave, t, rho=rho, g=g)
    if parts:
        return hs, fk
    out = hs + fk
    return out[:3], out[3:]


def soa(tri) -> jnp.ndarray:
    """Triangles (n, 3, 3) as rows (3, 3, n): vertex, axis, triangle (the layout the time step
    keeps: each coordinate of each vertex an (n,) row, which XLA vectorises)."""
    return jnp.transpose(jnp.asarray(tri), (1, 2, 0))


def _cross(a, b):
    """a × b of (3, n) rows."""
    return jnp.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                      a[0] * b[1] - a[1] * b[0]])


def _kept(x):
    """x, materialised: gathered by a fixed permutation and back. XLA's CPU fusion would make a
    fused producer (the elevation's cosines) again in each of its consumers (the cut's sorting
    network has dozens: 16 cosine ops compiled for 2 in the source, 3.6 times the time); a
    gather's operand is made once. (An optimisation barrier does not survive XLA CPU's passes.)"""
    n = x.size
    perm = np.roll(np.arange(n), 1)
    return x.reshape(-1)[perm][np.argsort(perm)].reshape(x.shape)


def pressure_loads_rows(T, rotation, origin, ref, wave: WaveField, t, *, rho: float, g: float):
    """(hydrostatic, Froude–Krylov) loads (6,) each of :func:`pressure_loads`, the triangles as
    rows ``T`` (3, 3, n) (:func:`soa`): the time step's form.

    The cut's vertex order comes from a three-comparator sorting network (element-wise), the
    midpoints of every wet piece are evaluated as one block (3, 6n), and the triangles' sums are
    one reduction at the end: 2.2 times faster than a sort and gathers on (n, 3, 3) blocks
    (benchmarks/RESULTS.md, issue 53)."""
    V = [origin[:, None] + rotation @ T[i] for i in range(3)]              # 3 × (3, n)
    z = jnp.stack([v[2] for v in V])                                      # (3, n)
    J = wave.amplitude.shape[0]
    if J:
        th = _phase_rows(wave, jnp.stack([v[0] for v in V]), jnp.stack([v[1] for v in V]), t)
        z = _kept(z - jnp.sum(wave.amplitude[:, None, None] * jnp.cos(th), axis=0))
    A, X, n_hat = _wet_pieces(V, [z[0], z[1], z[2]])
    n = n_hat.shape[1]
    hs = -rho * g * X[2]
    if J:
        cos = jnp.cos(_phase_rows(wave, X[0], X[1], t))                    # (J, 6n)
        a, k = wave.amplitude[:, None], wave.wavenumber[:, None]
        eta = jnp.sum(a * cos, axis=0)
        decay = _decay(k, _stretched(X[2], eta, wave.water_depth)[None], wave.water_depth)
        dyn = _kept(rho * g * jnp.sum(a * decay * cos, axis=0))
    else:
        dyn = jnp.zeros_like(hs)
    Xr = (X - ref[:, None]).reshape(3, 2, 3, n)

    def contributions(p):
        # per triangle (6, n): −∫ p n dA and −∫ (x − r) × n p dA over its wet pieces by the
        # edge-midpoint rule
        p = p.reshape(2, 3, n)
        Ip = jnp.sum(A * p, axis=(0, 1)) / 3
        Ixp = jnp.sum(A[None] * p[None] * Xr, axis=(1, 2)) / 3
        return jnp.concatenate([-Ip * n_hat, -_cross(Ixp, n_hat)])

    out = jnp.sum(jnp.concatenate([contributions(hs), contributions(dyn)]), axis=1)
    return out[:6], out[6:]


def froude_krylov_linear(tri, ref, wavenumber, heading, *, water_depth: float, rho: float,
                         g: float) -> np.ndarray:
    """The linear Froude–Krylov force and moment about ``ref`` per metre of wave amplitude,
    (J, 6) complex, hydro's convention (x(t) = Re[x̂ e^{−iωt}], η = Re[e^{ik(x cos β + y sin β)}
    e^{−iωt}]): the dynamic pressure of a unit wave integrated over the hull at rest cut at z = 0,

        X_FK = −∫_{S₀} ρ g f(z) e^{ik(x cos β + y sin β)} (n, (x − r) × n) dA.

    tri: (n, 3, 3) the closed hull at rest, inertial axes. Numpy (made once per run on the
    host): what the nonlinear level takes out of the database's excitation, leaving the
    diffraction, so that in small waves its total is the database's."""
    R = np.transpose(np.asarray(tri, float), (1, 2, 0))                     # (3, 3, n)
    A, X, n_hat = (np.asarray(x) for x in _wet_pieces([R[0], R[1], R[2]], [R[0][2], R[1][2],
                                                                           R[2][2]]))
    n = n_hat.shape[1]
    k = np.asarray(wavenumber, float)[:, None]
    beta = np.asarray(heading, float)[:, None]
    decay = np.asarray(_decay(k, np.minimum(X[2], 0.0)[None], water_depth))   # (J, 6n)
    p = rho * g * decay * np.exp(1j * k * (X[0][None] * np.cos(beta) + X[1][None] * np.sin(beta)))
    # the edge-midpoint rule on each piece, then the triangles' sums (as pressure_loads_rows)
    p = p.reshape(-1, 2, 3, n)
    Ip = np.sum(A[None] * p, axis=(1, 2)) / 3                                 # (J, n)
    Xr = (X - np.asarray(ref, float)[:, None]).reshape(3, 2, 3, n)
    Ixp = np.sum(A[None, None] * p[:, None] * Xr[None], axis=(2, 3)) / 3      # (J, 3, n)
    F = -np.einsum("jn,in->ji", Ip, n_hat)
    M = -np.cross(Ixp, n_hat[None], axis=1).sum(axis=2)
    return np.concatenate([F, M], axis=1)


def submerged_volume(tri_body, rotation, origin):
    """(V, centre of buoyancy (3,)) of the hull at a pose in still water, from the hydrostatic
    pressure loads: F = ρ g V ẑ and M_0 = ρ g V x_B × ẑ (so x_B's horizontal part; its height
    from the closed wet polyhedron's first moment). For checks and docs; the loads themselves are
    :func:`pressure_loads`."""
    zero = jnp.zeros(3)
    F, M = pressure_loads(tri_body, rotation, origin, zero, still_water(), 0.0, rho=1.0, g=1.0)
    vol = F[2]
    xb, yb = -M[1] / vol, M[0] / vol
    # z_B: ∫_wet z dV = ½ ∫ z² n_z dA over the wet hull (the cut plane z = 0 adds nothing)
    T = soa(tri_body)
    V = [origin[:, None] + rotation @ T[i] for i in range(3)]
    A, X, n_hat = _wet_pieces(V, [v[2] for v in V])
    Iz2 = jnp.sum(A * (X[2] ** 2).reshape(2, 3, -1), axis=(0, 1)) / 3        # ∫ z² dA, (n,)
    zb = 0.5 * jnp.sum(Iz2 * n_hat[2]) / vol
    return vol, jnp.stack([xb, yb, zb])


# ------------------------------------------------------------------------------------ hulls
def box_hull(length: float, beam: float, bottom: float, top: float):
    """A closed box (vertices (8, 3), faces (12, 3), outward): x in ±length/2, y in ±beam/2,
    z from ``bottom`` to ``top`` (m)."""
    x, y = length / 2, beam / 2
    V = np.array([[-x, -y, bottom], [x, -y, bottom], [x, y, bottom], [-x, y, bottom],
                  [-x, -y, top], [x, -y, top], [x, y, top], [-x, y, top]], float)
    F = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
    return V, F


def revolved_hull(profile, n_azimuth: int):
    """A closed hull of revolution about the z axis (vertices, triangle faces, outward): the
    meridian ``profile`` (m, 2) of (r, z) from the top on the axis (r = 0) down to the keel on the
    axis, its inner points r > 0, revolved in ``n_azimuth`` sectors. Points on the exact surface:
    volumes converge as O(n_azimuth⁻²)."""
    prof = np.asarray(profile, float)
    if prof.ndim != 2 or prof.shape[1] != 2 or len(prof) < 3:
        raise ValueError(f"profile: shape {prof.shape}; give (m ≥ 3, 2) points (r, z)")
    if prof[0, 0] != 0 or prof[-1, 0] != 0 or np.any(prof[1:-1, 0] <= 0):
        raise ValueError("profile: start and end on the axis (r = 0) with r > 0 between")
    n = int(n_azimuth)
    if n < 3:
        raise ValueError(f"n_azimuth: {n_azimuth!r}; give at least 3")
    th = 2 * np.pi * np.arange(n) / n
    inner = prof[1:-1]
    m = len(inner)
    ring = np.stack([inner[None, :, 0] * np.cos(th)[:, None], inner[None, :, 0] * np.sin(th)[:, None],
                     np.broadcast_to(inner[:, 1], (n, m))], axis=-1).reshape(-1, 3)
    top, keel = len(ring), len(ring) + 1
    V = np.concatenate([ring, [[0.0, 0.0, prof[0, 1]], [0.0, 0.0, prof[-1, 1]]]])
    F = []
    for k in range(n):
        k1 = (k + 1) % n
        F.append([top, k * m, k1 * m])
        for i in range(m - 1):
            a, b = k * m + i, k * m + i + 1
            c, d = k1 * m + i + 1, k1 * m + i
            F += [[a, b, c], [a, c, d]]
        F.append([k * m + m - 1, keel, k1 * m + m - 1])
    return V, np.asarray(F)


def _face_grid(corner, u, v, nu: int, nv: int):
    """A planar rectangle corner + [0, 1]u + [0, 1]v in nu × nv quads (vertices, faces; normal
    along u × v)."""
    s, t = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1), indexing="ij")
    V = corner + s[..., None] * u + t[..., None] * v                  # (nu+1, nv+1, 3)
    idx = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
    F = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], axis=-1).reshape(-1, 4)
    return V.reshape(-1, 3), F


HULL_SHAPES = {"sphere": ("radius",), "cylinder": ("radius", "bottom", "top"),
               "box": ("length", "beam", "bottom", "top"), "revolution": ("profile",),
               "geometry": ()}
HULL_KEYS = ({"shape", "center", "panel_size", "notes", "top"}
             | {k for v in HULL_SHAPES.values() for k in v})
# a hull from a mesh file (``mesh = "path"`` in place of ``shape``): its keys
HULL_MESH_KEYS = {"mesh", "center", "freeboard", "notes"}


def hull_mesh(spec: dict, *, where: str = "hull", geometry: dict | None = None,
              base=None, read_files: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """A closed hull (vertices (V, 3) m, faces (F, 4) or (F, 3), outward) from a plain dict, the
    ``[bodies.hull]`` table of a config, in the config's axes at rest:

    - ``shape = "sphere"``: ``radius``; ``center`` its centre.
    - ``shape = "cylinder"``: a vertical cylinder, ``radius``, ``bottom`` and ``top`` (z of its
      ends from ``center``'s z, bottom < top).
    - ``shape = "box"``: ``length`` along x, ``beam`` along y, ``bottom``, ``top`` (z from
      ``center``'s z); ``center`` the middle of its footprint.
    - ``shape = "revolution"``: ``profile`` [[r, z], …] from the top on the axis (r = 0) down to
      the keel on the axis, z from ``center``'s z: any body of revolution about the vertical
      through ``center``.
    - ``shape = "geometry"``: the body's BEM hull (``geometry``, its :mod:`hydro.geometry` spec:
      cylinder, hemisphere, sphere or revolution) closed above the water line by a vertical wall
      up to a deck at ``top`` (m above still water): the wetted hull the database was made from,
      with a freeboard. ``center`` is the spec's origin. A geometry of ``shape = "mesh"``: its
      ``file`` translated by its ``origin`` (as ``mfm hydro`` places it), used as it is when the
      file is the closed hull, and closed by :func:`hydro.meshfiles.extrude_waterline` up to
      ``top`` when it is the wetted surface only (open at z = 0; a lid in the plane z = 0
      replaced).
    - ``mesh = "path"`` (in place of ``shape``): a mesh file (:func:`hydro.meshfiles.read_mesh`:
      WAMIT .gdf, NEMOH .dat, STL), relative to ``base``, its origin placed at ``center``: the
      closed hull; or the wetted surface only with ``freeboard`` (m), closed as above up to
      z = freeboard. Checked closed, manifold and outward (:func:`check_hull`) with errors that
      name the file.

    ``center`` [x, y, z] m (default the origin); ``panel_size`` m (default a sixteenth of the hull's
    smallest dimension): panels no larger, so that the wave pressure's quadrature and a curved
    hull's facets converge (volumes as O(panel_size²)). ``where`` names the table in errors.
    ``base``: the folder relative mesh paths are read from (the config's; None: the working
    directory); ``read_files`` False checks the table's keys only and returns None (a config given
    as a dict, whose folder is known only when it loads)."""
    if not isinstance(spec, dict):
        raise ValueError(f"{where}: expected a table such as {{ shape = \"cylinder\", radius = 3.0, "
                         "bottom = -5.0, top = 2.0 }}")
    if "mesh" in spec:
        return _hull_of_file(spec, where, base, read_files)
    bad = sorted(set(spec) - HULL_KEYS)
    if bad:
        raise ValueError(f"{where}: unknown key(s) {bad}; accepted keys: {sorted(HULL_KEYS)} "
                         f"(a hull from a mesh file: {sorted(HULL_MESH_KEYS)})")
    shape = spec.get("shape")
    if shape not in HULL_SHAPES:
        raise ValueError(f"{where}.shape: {shape!r}; accepted: {sorted(HULL_SHAPES)}, or "
                         "mesh = \"<file>\" in place of shape (WAMIT .gdf, NEMOH .dat, STL)")
    missing = [k for k in HULL_SHAPES[shape] if k not in spec]
    if missing:
        raise ValueError(f"{where}: shape {shape!r} needs {missing}")

    def number(key, positive=False):
        v = spec[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                or (positive and v <= 0):
            raise ValueError(f"{where}.{key}: {v!r}; give a {'positive ' if positive else ''}"
                             "finite length in m")
        return float(v)

    c = spec.get("center", [0.0, 0.0, 0.0])
    try:
        center = np.asarray(c, dtype=float).reshape(3)
    except (TypeError, ValueError):
        raise ValueError(f"{where}.center: {c!r}; give [x, y, z] in m") from None
    if not np.all(np.isfinite(center)):
        raise ValueError(f"{where}.center: {c!r}; give finite [x, y, z] in m")
    if shape == "geometry":
        return _hull_of_geometry(spec, geometry, where,
                                 number("top", True) if "top" in spec else None,
                                 number("panel_size", True) if "panel_size" in spec else None,
                                 base, read_files)
    if shape in ("cylinder", "box"):
        bottom, top = number("bottom"), number("top")
        if not bottom < top:
            raise ValueError(f"{where}: bottom {bottom:g} m must lie below top {top:g} m")
    if shape == "sphere":
        R = number("radius", True)
        size = 2 * R
    elif shape == "cylinder":
        R = number("radius", True)
        size = min(2 * R, top - bottom)
    elif shape == "box":
        L, B = number("length", True), number("beam", True)
        size = min(L, B, top - bottom)
    else:
        prof = spec["profile"]
        try:
            prof = np.asarray(prof, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{where}.profile: not a list of [r, z] points") from None
        if prof.ndim != 2 or prof.shape[1] != 2 or len(prof) < 3 or not np.all(np.isfinite(prof)):
            raise ValueError(f"{where}.profile: shape {prof.shape}; give ≥ 3 finite [r, z] points")
        if prof[0, 0] != 0 or prof[-1, 0] != 0 or np.any(prof[1:-1, 0] <= 0):
            raise ValueError(f"{where}.profile: start at the top on the axis (r = 0), end at the "
                             "keel on the axis, r > 0 between")
        size = min(2 * float(prof[:, 0].max()), float(np.ptp(prof[:, 1])))
    dx = number("panel_size", True) if "panel_size" in spec else size / 16
    if shape == "box":
        n = [max(1, math.ceil(x / dx)) for x in (L, B, top - bottom)]
        x0, y0 = -L / 2, -B / 2
        ex, ey, ez = np.eye(3)
        faces_def = [  # corner, u, v, nu, nv: u × v outward
            ((x0, y0, bottom), B * ey, L * ex, n[1], n[0]),          # bottom (−z)
            ((x0, y0, top), L * ex, B * ey, n[0], n[1]),             # top (+z)
            ((x0, y0, bottom), L * ex, (top - bottom) * ez, n[0], n[2]),    # −y
            ((-x0, -y0, bottom), -L * ex, (top - bottom) * ez, n[0], n[2]),  # +y
            ((x0, -y0, bottom), -B * ey, (top - bottom) * ez, n[1], n[2]),   # −x
            ((-x0, y0, bottom), B * ey, (top - bottom) * ez, n[1], n[2]),    # +x
        ]
        Vs, Fs, off = [], [], 0
        for corner, u, v, nu, nv in faces_def:
            V, F = _face_grid(np.asarray(corner, float), u, v, nu, nv)
            Vs.append(V)
            Fs.append(F + off)
            off += len(V)
        return np.concatenate(Vs) + center, np.concatenate(Fs)
    if shape == "sphere":
        m = max(4, math.ceil(math.pi * R / dx))
        a = np.linspace(math.pi / 2, -math.pi / 2, m + 1)
        prof = np.stack([R * np.cos(a), R * np.sin(a)], axis=1)
        prof[0, 0] = prof[-1, 0] = 0.0
    elif shape == "cylinder":
        def seg(p, q):
            k = max(1, math.ceil(math.dist(p, q) / dx))
            return np.linspace(p, q, k + 1)[1:]
        corners = [(0.0, top), (R, top), (R, bottom), (0.0, bottom)]
        prof = np.concatenate([[corners[0]]] + [seg(p, q) for p, q in zip(corners[:-1], corners[1:])])
    else:
        pts = [prof[0]]
        for p, q in zip(prof[:-1], prof[1:]):
            k = max(1, math.ceil(math.dist(p, q) / dx))
            pts.extend(np.linspace(p, q, k + 1)[1:])
        prof = np.asarray(pts)
    rmax = float(prof[:, 0].max())
    n_az = max(12, 4 * math.ceil(2 * math.pi * rmax / dx / 4))
    V, F = revolved_hull(prof, n_az)
    return V + center, F


def _as_vertices_faces(T):
    """Triangles (n, 3, 3) as (vertices (3n, 3), faces (n, 3)): :func:`hull_mesh`'s return."""
    T = np.asarray(T, float)
    return T.reshape(-1, 3), np.arange(3 * len(T)).reshape(-1, 3)


def _hull_of_file(spec, where, base, read_files):
    """:func:`hull_mesh` of ``mesh = "path"``: the file's triangles placed at ``center``, closed
    by its side continued up to ``freeboard`` when the file is the wetted surface only."""
    import os
    from pathlib import Path

    from .meshfiles import FORMATS

    if "shape" in spec:
        raise ValueError(f"{where}: give shape or mesh, not both (shape {spec['shape']!r}, mesh "
                         f"{spec['mesh']!r})")
    bad = sorted(set(spec) - HULL_MESH_KEYS)
    if bad:
        raise ValueError(f"{where}: key(s) {bad} do not go with mesh (a mesh file's hull); "
                         f"accepted with mesh: {sorted(HULL_MESH_KEYS)}")
    f = spec["mesh"]
    if not isinstance(f, (str, os.PathLike)) or not os.fspath(f):
        raise ValueError(f"{where}.mesh: {f!r}; give the path of a mesh file (relative to the "
                         "config's folder): WAMIT .gdf, NEMOH .dat or STL")
    c = spec.get("center", [0.0, 0.0, 0.0])
    try:
        center = np.asarray(c, dtype=float).reshape(3)
    except (TypeError, ValueError):
        raise ValueError(f"{where}.center: {c!r}; give [x, y, z] in m (where the file's origin "
                         "goes, the config's axes at rest)") from None
    if not np.all(np.isfinite(center)):
        raise ValueError(f"{where}.center: {c!r}; give finite [x, y, z] in m")
    fb = spec.get("freeboard")
    if fb is not None and (isinstance(fb, bool) or not isinstance(fb, (int, float))
                           or not math.isfinite(fb) or fb <= 0):
        raise ValueError(f"{where}.freeboard: {fb!r}; give a positive height in m (the deck "
                         "above still water of a mesh that stops at its water line)")
    path = Path(f)
    if path.suffix.lower() not in FORMATS:
        raise ValueError(f"{where}.mesh {os.fspath(f)!r}: suffix {path.suffix!r} is not a mesh "
                         f"format read here; accepted: {sorted(FORMATS)} (WAMIT .gdf, NEMOH .dat, "
                         "STL); convert other formats (e.g. with meshio or trimesh) to STL")
    if not read_files:
        return None
    if not path.is_absolute() and base is not None:
        path = Path(base) / path
    what = f"{where}.mesh {os.fspath(f)!r}"
    return _as_vertices_faces(_closed_mesh_hull(path, center, fb, what, "freeboard"))


def _closed_mesh_hull(path, offset, freeboard, what, key):
    """The triangles of mesh file ``path`` translated by ``offset``, closed up to ``freeboard``
    (the key ``key`` names it) when the file is the wetted surface only, and checked
    (:func:`check_hull`): errors start with ``what`` (body, table, file)."""
    from .meshfiles import edge_report, extrude_waterline, read_mesh

    try:
        T = read_mesh(path) + np.asarray(offset, float)
    except FileNotFoundError:
        raise ValueError(f"{what}: file {str(path)!r} not found (relative paths are read from the "
                         "config's folder)") from None
    except ValueError as e:
        raise ValueError(f"{what}: {e}") from None
    size = float(np.ptp(T.reshape(-1, 3), axis=0).max())
    tol = 1e-6 * size
    zmax = float(T[..., 2].max())
    lid = np.all(np.abs(T[..., 2]) <= tol, axis=1)     # panels in the water plane z = 0
    if freeboard is not None:
        if zmax > tol:
            raise ValueError(f"{what}: the mesh reaches z = {zmax:.4g} m above still water, so it "
                             f"is not the wetted surface only; leave {key} out (a closed hull "
                             "has its own deck) or give the mesh cut at its water line")
        # a lid in the water plane (a BEM mesh closed at z = 0) is replaced by the wall and deck
        if not np.any(~lid) or not len(edge_report(T[~lid])["rim"]):
            raise ValueError(f"{what}: no open water line to continue up to {key} = "
                             f"{freeboard:g} m (the mesh does not pierce z = 0)")
        try:
            T = extrude_waterline(T[~lid], freeboard)
        except ValueError as e:
            raise ValueError(f"{what}: {e}") from None
    elif zmax <= tol and float(T[..., 2].min()) < -tol and np.any(lid):
        raise ValueError(f"{what}: closed by a lid at the still-water line (its top is z = 0): "
                         "no freeboard, so a heave or a wave would wet a deck that is not the "
                         f"hull's; give the whole hull, or give {key} (m) to continue its side "
                         "vertically above the water line in place of the lid")
    check_hull(T, what=what, fix=(
        "the nonlinear level needs the whole closed hull, above the water line too: give a mesh "
        f"of the whole hull, or, for a mesh that stops at its water line z = 0, {key} = <m> to "
        "continue its side vertically up to a deck, or an analytic shape (sphere, cylinder, box, "
        "revolution)"))
    return T


def _hull_of_geometry(spec, geometry, where, top, dx, base=None, read_files=True):
    """:func:`hull_mesh` of ``shape = "geometry"``: the body's hydro.geometry meridian (from its
    water line down to its keel) under a wall and a deck at ``top``; a mesh geometry's file,
    closed up to ``top`` when it is the wetted surface only (:func:`_closed_mesh_hull`)."""
    import os
    from pathlib import Path

    from .geometry import meridian, normalize_spec

    if geometry is None:
        raise ValueError(f"{where}: shape 'geometry' takes the body's [bodies.geometry] table, and "
                         "this body has none; give the hull's own shape (sphere, cylinder, box, "
                         "revolution)")
    if "center" in spec:
        raise ValueError(f"{where}.center: shape 'geometry' is placed at its geometry's origin; "
                         "leave center out")
    if geometry.get("shape") == "mesh":
        if "panel_size" in spec:
            raise ValueError(f"{where}.panel_size: the body's geometry is a mesh file, whose "
                             "panels are its own; leave panel_size out")
        f = geometry.get("file")
        if not isinstance(f, (str, os.PathLike)):
            raise ValueError(f"{where}: its body's geometry.file: {f!r}; give a mesh file's path")
        if not read_files:
            return None
        path = Path(f)
        if not path.is_absolute() and base is not None:
            path = Path(base) / path
        try:
            g = normalize_spec({"name": "hull", **geometry, "file": str(path)})
        except (ValueError, TypeError) as e:
            raise ValueError(f"{where}: its body's geometry: {e}") from None
        return _as_vertices_faces(_closed_mesh_hull(
            path, g["origin"], top, f"{where} (shape 'geometry': the body's mesh file {f!r})",
            "top"))
    if top is None:
        raise ValueError(f"{where}: shape 'geometry' needs ['top'] (m above still water: the "
                         "deck over the body's geometry)")
    try:
        g = normalize_spec({"name": "hull", **geometry})
    except (ValueError, TypeError) as e:
        raise ValueError(f"{where}: its body's geometry: {e}") from None
    prof0 = meridian(g, 1e9)     # the spec's corners; refined below
    size = min(2 * float(prof0[:, 0].max()), float(np.ptp(prof0[:, 1])) + top)
    dx = size / 16 if dx is None else dx
    prof = np.array(meridian(g, dx), dtype=float)
    prof[np.abs(prof[:, 0]) < 1e-12 * size, 0] = 0.0     # the keel on the axis (an arc's cos π/2)
    if prof[0, 0] <= 0 or abs(prof[0, 1]) > 1e-12:
        raise ValueError(f"{where}: the body's geometry does not pierce the water line (fully "
                         "submerged); give the hull's own shape")
    r0 = float(prof[0, 0])
    wall = [[r0, z] for z in np.linspace(top, 0.0, max(1, math.ceil(top / dx)) + 1)[:-1]]
    deck = [[r, top] for r in np.linspace(0.0, r0, max(1, math.ceil(r0 / dx)) + 1)[1:-1]]
    full = np.asarray([[0.0, top]] + deck + wall + prof.tolist())
    n_az = max(12, 4 * math.ceil(2 * math.pi * float(full[:, 0].max()) / dx / 4))
    V, F = revolved_hull(full, n_az)
    o = np.asarray(g["origin"], float)
    return V + np.array([o[0], o[1], 0.0]), F
