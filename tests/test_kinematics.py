"""B-matrix and equations-of-motion algebra (validation ladder step 1)."""
import jax
import numpy as np
import pytest
from conftest import CONFIGS

import mfm
from mfm.mechanics import se3
from mfm.io.config import parse_config

RNG = np.random.default_rng(3)
# All comparisons below are between exact expressions evaluated in float64 on O(1)–O(10) numbers;
# 1e-10 leaves room for the round-off of a few chained 4×4 products and a linear solve.
TOL = 1e-10


def tilted_free_tree():
    """A free root with two branches, tilted hinge axes, a slider, off-diagonal inertias."""
    J1 = [[2.0, 0.3, -0.1], [0.3, 1.5, 0.2], [-0.1, 0.2, 1.8]]
    J2 = [[0.5, -0.05, 0.02], [-0.05, 0.4, 0.01], [0.02, 0.01, 0.3]]
    data = {"bodies": [
        {"name": "hull", "mass": 10.0, "com": [0.1, -0.2, -0.3], "inertia": J1, "joint": {"type": "free"}},
        {"name": "arm", "parent": "hull", "mass": 2.0, "com": [1.2, 0.3, -0.1], "inertia": J2,
         "joint": {"type": "revolute", "axis": [0.2, 1.0, 0.3], "point": [0.8, 0.1, 0.2], "damping": 1.0}},
        {"name": "tip", "parent": "arm", "mass": 1.0, "com": [1.9, 0.5, -0.4], "inertia": J2,
         "joint": {"type": "revolute", "axis": [1.0, -0.4, 0.5], "point": [1.6, 0.4, -0.2]}},
        {"name": "slider", "parent": "hull", "mass": 3.0, "com": [-0.7, 0.2, -0.5], "inertia": J2,
         "joint": {"type": "prismatic", "axis": [0.1, 0.2, 1.0], "stiffness": 50.0}},
        {"name": "rigid", "parent": "slider", "mass": 0.5, "com": [-1.0, 0.6, -0.8], "inertia": J2,
         "joint": {"type": "fixed"}},
    ]}
    return mfm.compile_tree(parse_config(data)[1], name="tilted")


def models():
    out = {f"m4_{k}": mfm.load(CONFIGS / f"m4_{k}.toml", hydro=False) for k in ("111", "132", "134")}
    out["tilted"] = tilted_free_tree()
    return out


MODELS = models()


def random_state(m, scale=0.5):
    return RNG.normal(size=m.n_coordinates) * scale, RNG.normal(size=m.n_coordinates)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_b_qdot_equals_jvp_of_forward_kinematics(name):
    m = MODELS[name]
    for _ in range(3):
        q, qd = random_state(m)
        (x, R), (xd, Rd) = jax.jvp(lambda q: mfm.body_poses(m, q), (q,), (qd,))
        X = np.asarray(mfm.b_matrix(m, q) @ qd).reshape(m.n_bodies, 6)
        np.testing.assert_allclose(X[:, :3], xd, atol=TOL)
        w_body = np.stack([se3.vee(np.asarray(R[i]).T @ np.asarray(Rd[i])) for i in range(m.n_bodies)])
        np.testing.assert_allclose(X[:, 3:], w_body, atol=TOL)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_mass_matrix_spd_and_coriolis_matches_lagrangian(name):
    m = MODELS[name]
    for _ in range(3):
        q, qd = random_state(m)
        Ms = np.asarray(mfm.mass_matrix(m, q))
        np.testing.assert_allclose(Ms, Ms.T, atol=TOL)
        assert np.linalg.eigvalsh(Ms).min() > 0
        # Independent route: Lagrange's equations with T = ½ q̇ᵀ M*(q) q̇ give the velocity terms
        # c = Ṁ* q̇ − ∂T/∂q, with Ṁ* and ∂T/∂q by jax derivatives of M*(q) alone.
        Mdot = jax.jvp(lambda q: mfm.mass_matrix(m, q), (q,), (qd,))[1]
        dTdq = jax.grad(lambda q: 0.5 * qd @ mfm.mass_matrix(m, q) @ qd)(q)
        c_lagrange = np.asarray(Mdot @ qd - dTdq)
        c_mfm = np.asarray(mfm.coriolis_matrix(m, q, qd) @ qd)
        np.testing.assert_allclose(c_mfm, c_lagrange, atol=1e-9 * max(1, np.abs(c_lagrange).max()))


@pytest.mark.parametrize("name", sorted(MODELS))
def test_b_dot_is_time_derivative(name):
    m = MODELS[name]
    q, qd = random_state(m)
    h = 1e-6  # central difference: error O(h²) ≈ 1e-12 relative, round-off ≈ 1e-10/h·eps
    fd = (np.asarray(mfm.b_matrix(m, q + h * qd)) - np.asarray(mfm.b_matrix(m, q - h * qd))) / (2 * h)
    np.testing.assert_allclose(mfm.b_matrix_dot(m, q, qd), fd, atol=1e-7)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_walk_velocities_and_bias_equal_jvp(name):
    # the walk's X and Ḃ q̇ (from ȧ = ω × a) against jax's jvp of B along q̇
    m = MODELS[name]
    q, qd = random_state(m)
    kin = mfm.kinematics(m, q, qd)
    X = np.asarray(mfm.b_matrix(m, q) @ qd).reshape(m.n_bodies, 6)
    np.testing.assert_allclose(kin.X, X, atol=TOL)
    bias = np.asarray(mfm.b_matrix_dot(m, q, qd) @ qd).reshape(m.n_bodies, 6)
    np.testing.assert_allclose(kin.bias, bias, atol=TOL * max(1, np.abs(bias).max()))


# --- seed 001 eqs. 29–40, written out by hand in numpy ------------------------------------------

def Ry(a):
    return np.asarray(se3.rot_y(a))


def skewT(s):
    """s̄ᵀ of the seed: the transpose of the skew matrix, so s̄ᵀ ω = ω × s."""
    return np.asarray(se3.hat(s)).T


E1, E2, E3 = np.eye(3)
Z = np.zeros(3)


def seed_b_matrix(m, q, stern_parent, printed=False):
    """B of seed 001 eqs. 29–40 for an M4 layout, rows per body in seed numbering, columns
    (surge, heave, pitch, θ of each stern float in seed order).

    Inconsistencies of the printed equations (``printed=True`` reproduces them):
    - eq. 35 gives float 6's column with R^(3/2) and s^(3/h), float 3's quantities; by eqs. 22–23 it
      is R^(6/5) s̄^(6/h)ᵀ e2 (the two agree only when θ3 = θ6);
    - eqs. 37–38 write s^(h/4) + s^(4/1) for floats 7 and 8, whose parents are floats 2 and 5 by
      eqs. 24 and 26. The mid row is rigid, so s^(h/k) + s^(k/1) = (hinge − CoM of float 1) for any mid
      float k: the printed form is equal in value, only its labels differ.
    """
    com = {b.name: np.asarray(b.com) for b in m.bodies}
    hinge = {b.name: np.asarray(b.joint.point) for b in m.bodies if b.joint.kind == "revolute"}
    sterns = sorted(stern_parent, key=lambda n: int(n[5:]))
    col = {n: 3 + k for k, n in enumerate(sterns)}
    theta = {n: q[m.coordinate_index(f"{n}.angle")] for n in sterns}
    R1 = Ry(q[2])
    nq = 3 + len(sterns)
    rows = {}
    for b in m.bodies:
        n = b.name
        lin, ang = np.zeros((3, nq)), np.zeros((3, nq))
        lin[:, 0], lin[:, 1] = E1, E3
        if n == "float1":
            ang[:, 2] = E2
        elif n in ("float2", "float4", "float5"):
            lin[:, 2] = R1 @ skewT(com[n] - com["float1"]) @ E2          # eqs. 16–18
            ang[:, 2] = E2                                               # eq. 19
        else:
            p = stern_parent[n]
            if printed and n == "float6":
                Rr, s_ch = Ry(theta["float3"]), com["float3"] - hinge["float3"]
            else:
                Rr, s_ch = Ry(theta[n]), com[n] - hinge[n]
            s_hp, s_p1 = hinge[n] - com[p], com[p] - com["float1"]
            lin[:, 2] = R1 @ (skewT(s_hp) + skewT(s_p1) + Rr @ skewT(s_ch) @ Rr.T) @ E2   # eqs. 30, 34, 37, 38
            lin[:, col[n]] = R1 @ Rr @ skewT(s_ch) @ E2                                 # eqs. 31, 35, 39, 40
            ang[:, 2] = Rr.T @ E2                                                       # eq. 21 etc.
            ang[:, col[n]] = E2
        rows[n] = np.vstack([lin, ang])
    order = sorted(rows, key=lambda n: int(n[5:]))
    return np.vstack([rows[n] for n in order]), order, [f"{n}.angle" for n in sterns]


PARENTS = {"111": {"float3": "float2"},
           "132": {"float3": "float2", "float6": "float5"},
           "134": {"float3": "float2", "float6": "float5", "float7": "float2", "float8": "float5"}}


@pytest.mark.parametrize("layout", ["111", "132", "134"])
def test_m4_b_matrix_matches_seed_equations(layout):
    m = MODELS[f"m4_{layout}"]
    for _ in range(3):
        q = RNG.normal(size=m.n_coordinates) * 0.4
        ref, body_order, stern_coords = seed_b_matrix(m, q, PARENTS[layout])
        B = np.asarray(mfm.b_matrix(m, q)).reshape(m.n_bodies, 6, m.n_coordinates)
        rows = np.vstack([B[m.body_index(n)] for n in body_order])
        cols = [0, 1, 2] + [m.coordinate_index(c) for c in stern_coords]
        np.testing.assert_allclose(rows[:, cols], ref, atol=TOL)


def test_printed_eq35_differs_when_stern_angles_differ():
    """Documents the misprint of seed eq. 35 (float 3's rotation used for float 6)."""
    m = MODELS["m4_132"]
    q = np.array([0.0, 0.0, 0.1, 0.3, -0.2])
    printed, _, _ = seed_b_matrix(m, q, PARENTS["132"], printed=True)
    fixed, _, _ = seed_b_matrix(m, q, PARENTS["132"])
    assert np.abs(printed - fixed).max() > 1e-3
    q[4] = q[3]
    printed, _, _ = seed_b_matrix(m, q, PARENTS["132"], printed=True)
    fixed, _, _ = seed_b_matrix(m, q, PARENTS["132"])
    np.testing.assert_allclose(printed, fixed, atol=TOL)


def test_bodies_view():
    m = MODELS["m4_111"]
    b = m.bodies[2]
    assert b.name == "float3" and b.parent == "float2" and b.joint.kind == "revolute"
    np.testing.assert_allclose(b.joint.axis, [0, 1, 0])
    np.testing.assert_allclose(b.joint.point, [1.05, 0, 0.21])
    np.testing.assert_allclose(b.com, [2.10, 0, -0.1227])
    assert m.bodies[0].parent is None and m.bodies[0].joint.kind == "planar"
    np.testing.assert_allclose(m.bodies[0].inertia, np.diag([0.204] * 3))
