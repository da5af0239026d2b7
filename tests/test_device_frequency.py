"""Natural frequencies, equilibrium and frequency response against hand-assembled linear models.

Everything on the "hand" side is built here from the config's numbers (masses, centres of mass,
inertias, joint points) and the database's raw arrays (A(ω), B(ω), X(ω, β), the water-plane
stiffness, volumes, centres of buoyancy, reference points): the kinematics of the points as
functions of q (rotation matrices, jax for the derivatives), the stiffness as the Hessian of the
potential (weights at the CoMs, buoyancy ρgV at the centres of buoyancy, the water plane on the
reference points' ξ, joint springs), the mass matrix from the CoM Jacobians, A, B and X mapped by
the reference points' Jacobian H. Nothing is taken from mfm but the answer under test.
"""
import math
import tomllib

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import CONFIGS, ROOT

import mfm
from hydro.prepare import open_any_database

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

SPHERE_NC = ROOT / "hydro" / "data" / "sphere.nc"


def Ry(a):
    c, s = jnp.cos(a), jnp.sin(a)
    return jnp.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def sym(A):
    """Reciprocity: A_ij = A_ji (the BEM asymmetry is discretisation error)."""
    return 0.5 * (A + np.swapaxes(A, -1, -2))


class Hand:
    """A planar (x–z) tree given by functions point(body, p0, q) → position and angle(body, q) →
    pitch angle, with per body mass, Iyy, CoM, and per wet body its database index. Builds M, K,
    H, and the frequency-domain impedance at q = 0."""

    def __init__(self, n_q, point, angle, bodies, db, wet, g=9.81, joint_k=None, joint_c=None,
                 joint_rest=None, q_lin=None):
        self.n_q, self.point, self.angle, self.bodies, self.db, self.wet, self.g = (
            n_q, point, angle, bodies, db, wet, g)
        self.joint_k = np.zeros(n_q) if joint_k is None else np.asarray(joint_k, float)
        self.joint_c = np.zeros(n_q) if joint_c is None else np.asarray(joint_c, float)
        self.joint_rest = np.zeros(n_q) if joint_rest is None else np.asarray(joint_rest, float)
        q0 = jnp.zeros(n_q) if q_lin is None else jnp.asarray(q_lin, float)   # linearised here
        rho = float(db.attrs["rho"])
        # mass matrix: Σ m JᵀJ + Iyy aᵀa (planar: one angular velocity per body)
        M = np.zeros((n_q, n_q))
        for b, (m, Iyy, c) in bodies.items():
            J = np.asarray(jax.jacfwd(lambda q: point(b, c, q))(q0))
            a = np.asarray(jax.grad(lambda q: angle(b, q))(q0))
            M += m * J.T @ J + Iyy * np.outer(a, a)
        self.M = M
        # H: ξ = (displacement of the reference point, rotation vector) of each wet body
        Hs = []
        for b, k in wet:
            r = np.asarray(db.reference_point.values[k])
            Jr = np.asarray(jax.jacfwd(lambda q: point(b, r, q))(q0))
            a = np.asarray(jax.grad(lambda q: angle(b, q))(q0))
            Hs.append(np.vstack([Jr, np.zeros(n_q), a, np.zeros(n_q)]))   # (x, y, z, rx, ry, rz)
        self.H = np.vstack(Hs)
        order = np.concatenate([np.arange(6 * k, 6 * k + 6) for _, k in wet])
        self.order = order

        Cwp = np.asarray(db.waterplane_stiffness.values)[np.ix_(order, order)]

        def potential(q):
            """Weights, buoyancy ρgV at the centres of buoyancy, joint springs, and the water
            plane ½ ξᵀ C ξ on the reference points' exact ξ(q) (planar: rotation vector (0, θ, 0))."""
            V = 0.0
            for b, (m, _, c) in bodies.items():
                V = V + m * g * point(b, c, q)[2]
            xi = []
            for b, k in wet:
                cob = np.asarray(db.center_of_buoyancy.values[k])
                V = V - rho * g * float(db.displaced_volume.values[k]) * point(b, cob, q)[2]
                r = np.asarray(db.reference_point.values[k])
                xi.append(jnp.concatenate([point(b, r, q) - r, jnp.array([0.0, angle(b, q), 0.0])]))
            xi = jnp.concatenate(xi)
            return V + 0.5 * xi @ Cwp @ xi + 0.5 * jnp.sum(self.joint_k * (q - self.joint_rest) ** 2)

        self.potential = potential
        self.K = np.asarray(jax.hessian(potential)(q0))
        self.dV = np.asarray(jax.grad(potential)(q0))

    def equilibrium(self, free=()):
        """∇V(q) = 0 by Newton on the hand potential (coordinates in `free` held at 0)."""
        keep = [i for i in range(self.n_q) if i not in free]
        q = jnp.zeros(self.n_q)
        grad, hess = jax.jit(jax.grad(self.potential)), jax.jit(jax.hessian(self.potential))
        for _ in range(30):
            step = np.linalg.solve(np.asarray(hess(q))[np.ix_(keep, keep)], -np.asarray(grad(q))[keep])
            q = q.at[np.asarray(keep)].add(step)
        return np.asarray(q)

    def coefficients(self, omega, key):
        v = np.asarray(self.db[key].sel(omega=omega).values)
        return sym(v)[np.ix_(self.order, self.order)]

    def rao(self, omega):
        A = self.coefficients(omega, "added_mass")
        B = self.coefficients(omega, "radiation_damping")
        X = np.asarray(self.db.excitation.sel(omega=omega).isel(wave_direction=0).values)[self.order]
        Z = (-omega**2 * (self.M + self.H.T @ A @ self.H) - 1j * omega * (self.H.T @ B @ self.H + np.diag(self.joint_c))
             + self.K)
        return np.linalg.solve(Z, self.H.T @ X)

    def added_mass_q(self, omega):
        om = self.db.omega.values
        A = sym(np.asarray(self.db.added_mass.values))[:, self.order][:, :, self.order]
        Aw = np.array([[np.interp(omega, om, A[:, i, j]) for j in range(A.shape[2])]
                       for i in range(A.shape[1])])
        return self.H.T @ Aw @ self.H


# ------------------------------------------------------------------------------- floating sphere
SPHERE = tomllib.loads((CONFIGS / "sphere.toml").read_text())["bodies"][0]


@pytest.fixture(scope="module")
def sphere_db():
    return open_any_database(SPHERE_NC)


@pytest.fixture(scope="module")
def sphere_modes():
    # min |det| on a short grid around the two modes (its cost is one A(ω) interpolation a point)
    # about q = 0, the sphere's equilibrium (m = ρV, CoM above the CoB): no Newton solve
    nf = mfm.natural_frequencies(mfm.load(CONFIGS / "sphere.toml"), q0=np.zeros(3),
                                 omega_grid=np.linspace(2.3, 3.5, 241))
    return {k: v.values for k, v in nf.items()}       # a labelled Dataset: its arrays


def sphere_hand(db, mass=SPHERE["mass"], com=SPHERE["com"]):
    c0 = np.asarray(com, float)

    def point(b, p0, q):      # planar root: CoM moves by (x, 0, z), turns by R_y(θ)
        return c0 + jnp.array([q[0], 0.0, q[1]]) + Ry(q[2]) @ (jnp.asarray(p0) - c0)

    def angle(b, q):
        return q[2]

    return Hand(3, point, angle, {"sphere": (mass, SPHERE["principal_inertia"][1], c0)}, db,
                [("sphere", 0)])


def test_sphere_heave_natural_frequency(sphere_db, sphere_modes):
    """ω = √(C33 / (m + A33(ω))), A33 interpolated on the database grid, iterated by hand."""
    db = sphere_db
    C33 = float(db.waterplane_stiffness.values[2, 2])
    om, A33 = db.omega.values, sym(np.asarray(db.added_mass.values))[:, 2, 2]
    w = 1.0
    for _ in range(100):
        w = math.sqrt(C33 / (SPHERE["mass"] + np.interp(w, om, A33)))
    nf = sphere_modes
    heave = int(np.argmax(np.abs(nf["modes"][1])))      # the mode that moves the heave coordinate
    # 1e-8: the same fixed point of the same interpolated A33; a 10 % error of K or M shows as 5 %
    assert nf["eigen"][heave] == pytest.approx(w, rel=1e-8)
    # the min |det| route on its 5 mm/s grid: within the step (|det| has a cusp at a root, which
    # the parabola through three points of log|det| locates to a fraction of the step)
    assert np.min(np.abs(nf["min_det"] - w)) < 0.005


def test_sphere_pitch_natural_frequency_with_surge_free(sphere_db, sphere_modes):
    hand = sphere_hand(sphere_db)
    Kt = hand.K[2, 2]
    assert abs(hand.K[0]).max() == 0.0                    # surge has no stiffness: it moves freely
    w = 2.0
    for _ in range(100):
        M = hand.M + hand.added_mass_q(w)
        w = math.sqrt(Kt / (M[2, 2] - M[0, 2] ** 2 / M[0, 0]))   # surge condensed out
    nf = sphere_modes
    pitch = int(np.argmax(np.abs(nf["modes"][2])))
    assert nf["eigen"][pitch] == pytest.approx(w, rel=1e-6)


def test_sphere_equilibrium_heavy_and_off_centre(sphere_db, tmp_path):
    """m = 0.98 ρV with the CoM 3 mm forward: sinkage (m − ρV) g / C33 (negative: it rises) and
    trim from the buoyancy's moment about the CoM, by the hand 2×2 (heave, pitch) linear solve."""
    db = sphere_db
    rho, g = float(db.attrs["rho"]), float(db.attrs["g"])
    V = float(db.displaced_volume[0])
    mass, com = 0.98 * rho * V, [0.003, 0.0, SPHERE["com"][2]]
    text = (CONFIGS / "sphere.toml").read_text()
    text = text.replace('"../hydro/data/sphere.nc"', f'"{SPHERE_NC}"')
    text = text.replace(f"mass = {SPHERE['mass']}", f"mass = {mass!r}").replace(
        "com = [0.0, 0.0, -0.3]", f"com = {com}")
    path = tmp_path / "sphere_light.toml"
    path.write_text(text)
    q0, info = mfm.equilibrium(mfm.load(path))
    hand = sphere_hand(db, mass=mass, com=com)
    # the textbook sinkage (m − ρV) g / C33 (downwards; heave is up)
    C33 = float(db.waterplane_stiffness.values[2, 2])
    assert q0[1] == pytest.approx(-(mass - rho * V) * g / C33, rel=2e-3)
    # heave and trim by the hand potential's exact equilibrium (surge has no stiffness: held);
    # 1e-7: two Newton solutions of the same statics
    np.testing.assert_allclose(q0[1:], hand.equilibrium(free=(0,))[1:], rtol=1e-7)
    # and the linear hand solve K x = −∇V at q = 0: within 3 %, the pre-load's geometric term
    # (the 410 N net water-plane force on a lever that turns by 0.3 m · θ) being 2 % of the moment
    np.testing.assert_allclose(q0[1:], np.linalg.solve(hand.K[1:, 1:], -hand.dV[1:]), rtol=0.03)
    assert abs(q0[2]) > 1e-3 and info["free"] == ["sphere.surge"]


# ------------------------------------------------------------------ a float hinged to the ground
HINGE = np.array([-2.5, 0.0, 0.6])
K_JOINT, REST, C_JOINT = 3000.0, 0.05, 4000.0


def hinged_config():
    return f"""
[model]
name = "hinged sphere"
gravity = 9.81

[hydro]
database = "{SPHERE_NC}"

[[bodies]]
name = "sphere"
mass = {SPHERE['mass']}
com = {SPHERE['com']}
principal_inertia = {SPHERE['principal_inertia']}
[bodies.joint]
type = "revolute"
axis = [0.0, 1.0, 0.0]
point = {HINGE.tolist()}
stiffness = {K_JOINT}
rest = {REST}
damping = {C_JOINT}
"""


@pytest.fixture(scope="module")
def hinged(sphere_db, tmp_path_factory):
    path = tmp_path_factory.mktemp("hinged") / "hinged_sphere.toml"
    path.write_text(hinged_config())
    c0 = np.asarray(SPHERE["com"], float)

    def point(b, p0, q):
        return jnp.asarray(HINGE) + Ry(q[0]) @ (jnp.asarray(p0) - HINGE)

    def angle(b, q):
        return q[0]

    def hand(q_lin=None):
        return Hand(1, point, angle, {"sphere": (SPHERE["mass"], SPHERE["principal_inertia"][1], c0)},
                    sphere_db, [("sphere", 0)], joint_k=[K_JOINT], joint_c=[C_JOINT],
                    joint_rest=[REST], q_lin=q_lin)

    return mfm.load(path), hand(), hand


def test_hinged_float_natural_frequency(hinged):
    model, hand, _ = hinged
    w = 1.0
    for _ in range(100):
        w = math.sqrt(hand.K[0, 0] / (hand.M[0, 0] + hand.added_mass_q(w)[0, 0]))
    nf = mfm.natural_frequencies(model, q0=np.zeros(1), omega_grid=np.linspace(1.0, 1.1, 3)).eigen.values
    # 1e-8: the same fixed point; K holds the water plane moved to the hinge (lever 2.5 m), the
    # buoyancy and weight levers and the joint spring
    assert nf[0] == pytest.approx(w, rel=1e-8)


def test_hinged_float_equilibrium_under_an_applied_moment(hinged):
    model, hand, _ = hinged
    # the joint spring's rest angle applies k·rest at φ = 0; weight and buoyancy balance there
    grad_gravity_buoyancy = hand.dV[0] + K_JOINT * REST
    assert abs(grad_gravity_buoyancy) < 1e-6 * K_JOINT * REST
    q0, _ = mfm.equilibrium(model)
    # 1e-7: the hand potential's exact equilibrium; 1 %: the linear φ = k rest / K
    assert q0[0] == pytest.approx(hand.equilibrium()[0], rel=1e-7)
    assert q0[0] == pytest.approx(K_JOINT * REST / hand.K[0, 0], rel=0.01)


def test_hinged_float_damped_response_against_single_dof(hinged, sphere_db):
    """x̂ = Hᵀ X / (K − ω² (I_h + Hᵀ A H) − iω (Hᵀ B H + c)): the damped single-dof system."""
    model, hand, _ = hinged
    omega = sphere_db.omega.values[4:56:3]                # database points: no interpolation
    rao = mfm.frequency_response(model, omega, q0=np.zeros(1)).rao.values[:, 0]
    ref = np.array([hand.rao(w)[0] for w in omega])
    # 1e-9: linear algebra on the same numbers
    np.testing.assert_allclose(rao, ref, rtol=1e-9)
    k = np.argmax(np.abs(ref))
    assert 0 < k < len(omega) - 1                          # the resonance lies inside the band


# ------------------------------------------------------------------ M4 111: a hinged multi-body
def m4_hand(db):
    cfg = tomllib.loads((CONFIGS / "m4_111.toml").read_text())
    bodies = {b["name"]: b for b in cfg["bodies"]}
    c1 = np.asarray(bodies["float1"]["com"], float)
    h3 = np.asarray(bodies["float3"]["joint"]["point"], float)

    def root(p0, q):          # a point fixed on the bow/mid frame (float1 planar root, float2 fixed)
        return c1 + jnp.array([q[0], 0.0, q[1]]) + Ry(q[2]) @ (jnp.asarray(p0) - c1)

    def point(b, p0, q):
        if b == "float3":      # turns about its hinge, carried by the frame
            return root(h3, q) + Ry(q[2] + q[3]) @ (jnp.asarray(p0) - h3)
        return root(p0, q)

    def angle(b, q):
        return q[2] + (q[3] if b == "float3" else 0.0)

    inertial = {n: (b["mass"], b["principal_inertia"][1], np.asarray(b["com"], float))
                for n, b in bodies.items()}
    names = [str(b) for b in db.body.values]
    return Hand(4, point, angle, inertial, db, [(n, names.index(n)) for n in ("float1", "float2", "float3")],
                g=cfg["model"]["gravity"], joint_c=[0, 0, 0, bodies["float3"]["joint"]["damping"]])


def test_m4_111_frequency_response_against_hand_assembly():
    model = mfm.load(CONFIGS / "m4_111.toml")
    assert model.coordinates == ("float1.surge", "float1.heave", "float1.pitch", "float3.angle")
    db = open_any_database(ROOT / "hydro" / "data" / "m4_111.nc")
    hand = m4_hand(db)
    omega = db.omega.values[2:60:4]                        # 1–15 rad/s, database points
    rao = mfm.frequency_response(model, omega, q0=np.zeros(4)).rao.values
    ref = np.array([hand.rao(w) for w in omega])
    # 1e-8 of the largest response: linear algebra on the same numbers (coupled 18×18 hydro)
    np.testing.assert_allclose(rao, ref, rtol=0, atol=1e-8 * np.abs(ref).max())
    assert np.abs(ref[:, 3]).max() > 0.5                   # the hinge responds: not vacuous


def test_hinged_float_response_about_its_equilibrium(hinged, sphere_db):
    """Without q0, mfm linearises about its equilibrium (φ₀ ≈ 7e-4 rad under the spring's rest
    angle): M, K, H and the excitation at φ₀, against the hand model linearised there."""
    model, hand0, hand_at = hinged
    hand = hand_at(q_lin=hand0.equilibrium())
    omega = sphere_db.omega.values[4:56:6]
    rao = mfm.frequency_response(model, omega).rao.values[:, 0]
    ref = np.array([hand.rao(w)[0] for w in omega])
    # 1e-7: the two equilibria agree to 1e-10 rad; K at φ₀ differs from K at 0 by 5e-4
    np.testing.assert_allclose(rao, ref, rtol=1e-7)
    assert np.abs(hand.K - hand0.K).max() > 1e-4 * np.abs(hand0.K).max()   # 5e-4: visible
