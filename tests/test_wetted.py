"""Pressure on the instantaneous wetted hull (hydro.wetted): submerged volume and centre of
buoyancy of a box and a sphere at any draft and tilt against closed forms, the stiffness at rest
against the water-plane formulas, the Froude–Krylov force on a vertical cylinder against its
closed form in a small wave, and bad meshes refused."""
from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.special import j1

from hydro import wetted as W

RHO, G = 1025.0, 9.81


def _rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], float)


def _rot(v):
    """Rotation matrix of a rotation vector, exp of its skew matrix (jax, differentiable at 0)."""
    K = jnp.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return jax.scipy.linalg.expm(K)


@pytest.mark.parametrize("theta", [0.0, 0.1, -0.25])
@pytest.mark.parametrize("z0", [-0.7, 0.4])
def test_a_tilted_box_s_volume_and_centre_of_buoyancy_are_its_closed_form(theta, z0):
    """A box L × B, z from −3 to 2 m in its axes, rolled by θ about x and lifted by z0: while the
    surface cuts only its sides, the wet height over y is h(y) = (−z0 − y sin θ)/cos θ − bottom,
    so V = L B (−z0/cos θ − bottom) and the centre of buoyancy is the first moments of that
    prism (module docstring of hydro.wetted: the hydrostatic integrals are exact for a
    polyhedron). Tolerance 1e-12 relative: round-off."""
    L, B, bot, top = 4.0, 2.0, -3.0, 2.0
    V, F = W.box_hull(L, B, bot, top)
    T = jnp.asarray(W.triangles(V, F))
    R = _rot_x(theta)
    vol, cb = W.submerged_volume(T, jnp.asarray(R), jnp.array([0.0, 0.0, z0]))
    c, t = math.cos(theta), math.tan(theta)
    V_ref = L * B * (-z0 / c - bot)
    yb = -t * L * B**3 / 12 / V_ref
    zb = L * (B * z0**2 / c**2 + t**2 * B**3 / 12 - B * bot**2) / (2 * V_ref)
    cb_ref = R @ np.array([0.0, yb, zb]) + np.array([0.0, 0.0, z0])
    assert float(vol) == pytest.approx(V_ref, rel=1e-12)
    np.testing.assert_allclose(np.asarray(cb), cb_ref, rtol=0, atol=1e-12 * L)


def _sphere(n_profile, n_azimuth, r=1.0):
    a = np.linspace(np.pi / 2, -np.pi / 2, n_profile + 1)
    prof = np.stack([r * np.cos(a), r * np.sin(a)], axis=1)
    prof[0, 0] = prof[-1, 0] = 0.0
    V, F = W.revolved_hull(prof, n_azimuth)
    return jnp.asarray(W.triangles(V, F))


@pytest.mark.parametrize("zc", [-0.5, 0.3])
def test_a_sphere_s_cap_converges_to_its_closed_form_at_any_tilt(zc):
    """A sphere of radius 1 with its centre at z_c: the cap below z = 0 has h = 1 − z_c,
    V = π h² (3 − h)/3 and its centroid 3 (2 − h)²/(4 (3 − h)) below the centre, whatever the
    rotation. The panels are inscribed: the error falls as the square of the panel size (ratio
    within 4 ± 0.6 on halving it) and is below 0.3 % at 64 × 128 panels; at a pose turned
    about an arbitrary axis the same value within round-off of that error (1e-3 relative: the
    polyhedron is not round, so a turn changes its cut slightly)."""
    h = 1.0 - zc
    V_ref = math.pi * h**2 * (3 - h) / 3
    zb_ref = zc - 3 * (2 - h) ** 2 / (4 * (3 - h))
    errs = []
    for n in (16, 32, 64):
        vol, cb = W.submerged_volume(_sphere(n, 2 * n), jnp.eye(3), jnp.array([0.0, 0.0, zc]))
        errs.append(abs(float(vol) / V_ref - 1))
    assert 3.4 < errs[0] / errs[1] < 4.6 and 3.4 < errs[1] / errs[2] < 4.6
    assert errs[2] < 3e-3
    assert float(cb[2]) == pytest.approx(zb_ref, abs=3e-3)
    R = _rot(jnp.array([0.3, -0.5, 1.1]))
    vol_t, cb_t = W.submerged_volume(_sphere(64, 128), R, jnp.array([0.0, 0.0, zc]))
    assert float(vol_t) == pytest.approx(float(vol), rel=1e-3)
    np.testing.assert_allclose(np.asarray(cb_t), [0.0, 0.0, float(cb[2])], atol=3e-3)


def _loads(T, ref):
    """(F, M about ref) of a pose (x, y, z, rotation vector about ref) in still water."""
    def f(pose):
        R = _rot(pose[3:])
        origin = ref + pose[:3] - R @ ref
        Fo, M = W.pressure_loads(T, R, origin, ref + pose[:3], W.still_water(), 0.0, rho=RHO, g=G)
        return jnp.concatenate([Fo, M])
    return f


def test_the_stiffness_at_rest_is_the_water_plane_s():
    """A box floating at draft d (water line through its centre plane): −∂(F, M)/∂(heave, roll,
    pitch) about the water-line centre from jax's derivative is the linear model's hydrostatic
    stiffness: C33 = ρ g L B, C44 = ρ g (L B³/12 + V z_B), C55 = ρ g (B L³/12 + V z_B), no heave
    coupling (the box is symmetric). Tolerance 1e-9 relative: the cut is exact and the
    derivative exact where no vertex lies on the surface."""
    L, B, d = 6.0, 3.0, 1.5
    V, F = W.box_hull(L, B, -d, 2.0)
    T = jnp.asarray(W.triangles(V, F))
    J = -jax.jacfwd(_loads(T, jnp.zeros(3)))(jnp.zeros(6))
    vol, zb = L * B * d, -d / 2
    rg = RHO * G
    C = np.zeros((6, 6))
    C[2, 2] = rg * L * B
    C[3, 3] = rg * (L * B**3 / 12 + vol * zb)
    C[4, 4] = rg * (B * L**3 / 12 + vol * zb)
    for i, j in ((2, 2), (3, 3), (4, 4), (2, 3), (2, 4), (3, 4)):
        assert float(J[i, j]) == pytest.approx(C[i, j], rel=1e-9, abs=1e-9 * rg * L * B), (i, j)
    # and at rest the force is the buoyancy, ρ g V up, no moment
    F0 = _loads(T, jnp.zeros(3))(jnp.zeros(6))
    np.testing.assert_allclose(np.asarray(F0), [0, 0, rg * vol, 0, 0, 0], atol=1e-9 * rg * vol)


def test_froude_krylov_on_a_vertical_cylinder_in_a_small_wave():
    """A fixed vertical cylinder R 1 m, draft 2 m, in deep water, wave a = 1 mm (k a = 2.5e-4)
    at kR = 0.5: the nonlinear pressure integral minus the buoyancy is the linear Froude–Krylov
    force F_x = −ρ g a 2π R J₁(kR) (1 − e^{−kd})/k sin ωt,
    F_z = ρ g a 2π R J₁(kR)/k e^{−kd} cos ωt (η = a cos(kx − ωt)), within 0.5 % of its amplitude: the polygon's
    O(n⁻²) error (128 sectors: 0.04 %), the panels' quadrature and k a ≈ 2.5e-4 of second-order
    terms."""
    R_, d, k = 1.0, 2.0, 0.5
    w = math.sqrt(k * G)
    a = 1e-3
    prof = [[0.0, 1.0], [R_, 1.0]] + [[R_, z] for z in np.linspace(1.0, -d, 61)[1:]] + [[0.0, -d]]
    V, F = W.revolved_hull(np.asarray(prof), 128)
    T = jnp.asarray(W.triangles(V, F))
    W.check_hull(np.asarray(T), what="cylinder")
    wave = W.WaveField(*(jnp.array([v]) for v in (a, w, k, 0.0, 0.0)))
    amp = RHO * G * a * 2 * math.pi * R_ * j1(k * R_) / k
    for t in np.linspace(0.0, 2 * math.pi / w, 7)[:-1]:
        Fo, _ = W.pressure_loads(T, jnp.eye(3), jnp.zeros(3), jnp.zeros(3), wave, t, rho=RHO, g=G)
        Fo = np.asarray(Fo)
        V0 = float(W.submerged_volume(T, jnp.eye(3), jnp.zeros(3))[0])
        fx = -amp * (1 - math.exp(-k * d)) * math.sin(w * t)
        fz = amp * math.exp(-k * d) * math.cos(w * t)
        assert abs(Fo[0] - fx) < 5e-3 * amp, (t, Fo[0], fx)
        assert abs(Fo[2] - RHO * G * V0 - fz) < 5e-3 * amp, (t, Fo[2] - RHO * G * V0, fz)


def test_the_linear_froude_krylov_coefficient_is_the_small_wave_limit():
    """The same cylinder: froude_krylov_linear's X (per metre, e^{−iωt}) against the Bessel closed
    form, X_x = −i ρ g 2π R J₁(kR)(1 − e^{−kd})/k, X_z = ρ g 2π R J₁(kR) e^{−kd}/k (0.5 %, the
    mesh's), and the nonlinear level's wave part in a 1 mm wave at a heading of 30° and a phase of
    0.4 rad against Re[X a e^{iφ} e^{−iωt}] of the same mesh (1e-3 of its amplitude: the
    second-order terms, k a = 2.5e-4, and the stretching)."""
    R_, d, k = 1.0, 2.0, 0.5
    w = math.sqrt(k * G)
    prof = [[0.0, 1.0], [R_, 1.0]] + [[R_, z] for z in np.linspace(1.0, -d, 61)[1:]] + [[0.0, -d]]
    V, F = W.revolved_hull(np.asarray(prof), 128)
    T = W.triangles(V, F)
    X = W.froude_krylov_linear(T, np.zeros(3), np.array([k, k]), np.array([0.0, math.pi / 6]),
                               water_depth=math.inf, rho=RHO, g=G)
    amp = RHO * G * 2 * math.pi * R_ * j1(k * R_) / k
    assert abs(X[0, 0] - (-1j * amp * (1 - math.exp(-k * d)))) < 5e-3 * amp
    assert abs(X[0, 2] - amp * math.exp(-k * d)) < 5e-3 * amp
    a, phi, beta = 1e-3, 0.4, math.pi / 6
    wave = W.WaveField(*(jnp.array([v]) for v in (a, w, k, beta, phi)))
    for t in (0.3, 1.1, 2.0):
        _, fk = W.pressure_loads(jnp.asarray(T), jnp.eye(3), jnp.zeros(3), jnp.zeros(3), wave, t,
                                 rho=RHO, g=G, parts=True)
        ref = np.real(X[1] * a * np.exp(1j * (phi - w * t)))
        np.testing.assert_allclose(np.asarray(fk), ref, rtol=0, atol=1e-3 * a * amp)


def test_bad_hulls_are_refused():
    """An open hull (a face removed) and one whose faces all point inward, each with a message
    that says what is wrong and the fix."""
    V, F = W.box_hull(1.0, 1.0, -1.0, 1.0)
    with pytest.raises(ValueError, match="the hull is open"):
        W.check_hull(W.triangles(V, F[:-1]), what="box")
    with pytest.raises(ValueError, match="normals point inward"):
        W.check_hull(W.triangles(V, F[:, ::-1]), what="box")
    with pytest.raises(ValueError, match="not ordered consistently"):
        G2 = F.copy()
        G2[0] = G2[0, ::-1]
        W.check_hull(W.triangles(V, G2), what="box")
    with pytest.raises(ValueError, match="faces: indices"):
        W.triangles(V, F + 10)


@pytest.mark.parametrize("depth", [math.inf, 12.0])
def test_the_particle_velocity_is_the_potential_s_gradient(depth):
    """u = ∇φ of the linear potential φ = Σ (a g/ω) cosh k(z + h)/cosh kh sin θ (e^{kz} in deep
    water) by central differences at points under the surface, two components at two headings,
    in deep and finite water: 1e-6 relative (the differences' error at step 1e-4 m is ~1e-9; the
    stretching moves the decay by η, k a ≈ 1e-6 here)."""
    from hydro.waves import wavenumber

    w = np.array([0.7, 1.3])
    k = wavenumber(w, depth, G)
    amp, beta, phi = np.array([1e-6, 2e-6]), np.array([0.3, -1.0]), np.array([0.2, 1.1])
    wave = W.WaveField(*(jnp.asarray(v) for v in (amp, w, k, beta, phi)), water_depth=depth)

    def potential(p, t):
        th = k * (p[0] * np.cos(beta) + p[1] * np.sin(beta)) - w * t + phi
        f = np.exp(k * p[2]) if math.isinf(depth) else np.cosh(k * (p[2] + depth)) / np.cosh(k * depth)
        return float(np.sum(amp * G / w * f * np.sin(th)))

    pts = np.array([[0.5, -1.0, -0.7], [3.0, 2.0, -4.0]])
    t, h = 1.7, 1e-4
    u = np.asarray(W.particle_velocity(wave, jnp.asarray(pts), t))
    for p, up in zip(pts, u):
        grad = [(potential(p + h * e, t) - potential(p - h * e, t)) / (2 * h) for e in np.eye(3)]
        np.testing.assert_allclose(up, grad, rtol=1e-6, atol=1e-9 * np.abs(grad).max())
