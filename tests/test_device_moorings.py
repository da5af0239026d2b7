"""Linear moorings (point springs) attached off the centre of mass, against hand values:

- the 6×6 stiffness about the CoM: for a spring of stiffness diag(k) at d = p − c,
  K = [[k, −k[d]×], [[d]×k, −[d]×k[d]×]]; for a surge spring at a height ℓ = z_p − z_G its
  surge–pitch block is the textbook k [[1, ℓ], [ℓ, ℓ²]];
- the time-domain surge and pitch periods of a moored floating sphere against 2π/ω from the hand
  2×2 problem det(K − ω² (M + Hᵀ A∞ H)) = 0, with K from the springs, the database's water plane
  and the buoyancy lever, M and A∞ from the config and the database.
"""
import math

import numpy as np
import pytest
import scipy.linalg
from conftest import ROOT

import mfm
from hydro.prepare import open_any_database

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


def skew(d):
    return np.array([[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]])


COM = np.array([0.3, -0.2, -0.5])
SPRINGS = [  # (point, stiffness): a surge spring straight below the CoM, and an oblique one
    (COM + np.array([0.0, 0.0, -1.2]), np.array([800.0, 0.0, 0.0])),
    (COM + np.array([0.7, 0.4, 0.25]), np.array([300.0, 500.0, 200.0])),
]


def mechanics_config():
    moorings = "".join(f"\n[[moorings]]\nbody = \"buoy\"\npoint = {p.tolist()}\nstiffness = {k.tolist()}\n"
                       for p, k in SPRINGS)
    return f"""
[model]
name = "moored buoy, no gravity"
gravity = 0.0

[[bodies]]
name = "buoy"
mass = 50.0
com = {COM.tolist()}
principal_inertia = [4.0, 5.0, 6.0]
[bodies.joint]
type = "free"
{moorings}"""


def test_stiffness_6x6_against_hand(tmp_path):
    path = tmp_path / "moored.toml"
    path.write_text(mechanics_config())
    model = mfm.load(path)
    assert model.coordinates[3:] == ("buoy.roll", "buoy.pitch", "buoy.yaw")

    def Q(q):
        # the springs' generalised load = M*(q) q̈ at rest (no gravity, no other load)
        ds = mfm.simulate(model, duration=1e-3, dt=1e-3, q0=q, check_stability=False)
        return np.asarray(mfm.mass_matrix(model, q)) @ ds.qdd.values[0]

    eps = 1e-5
    K = np.zeros((6, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = eps
        K[:, j] = -(Q(e) - Q(-e)) / (2 * eps)
    # hand: the first spring in the textbook surge–pitch form, the second by the general formula
    (p1, k1), (p2, k2) = SPRINGS
    ell = p1[2] - COM[2]
    hand = np.zeros((6, 6))
    hand[np.ix_([0, 4], [0, 4])] = k1[0] * np.array([[1.0, ell], [ell, ell**2]])
    d, k = p2 - COM, np.diag(k2)
    hand += np.block([[k, -k @ skew(d)], [skew(d) @ k, -skew(d) @ k @ skew(d)]])
    # 1e-6 relative: central differences of linear springs with exact (nonlinear) rotations, step
    # 1e-5 (truncation ~1e-10) plus rounding ~1e-16/1e-5; a dropped lever arm changes the pitch
    # entries by 100 %
    np.testing.assert_allclose(K, hand, atol=1e-6 * np.abs(hand).max())


# ----------------------------------------------------------------- time-domain periods with water
SPHERE_NC = ROOT / "hydro" / "data" / "sphere.nc"
M_SPHERE, I_SPHERE, ZG = 2092.29322, 833.3, -0.3        # configs/sphere.toml
K_SPRING, ELL = 2000.0, 0.5                              # two surge springs at z_G ± ℓ


def sphere_config():
    springs = "".join(f"\n[[moorings]]\nbody = \"sphere\"\npoint = [0.0, 0.0, {ZG + s * ELL}]\n"
                      f"stiffness = [{K_SPRING}, 0.0, 0.0]\n" for s in (1.0, -1.0))
    return f"""
[model]
name = "moored sphere"
gravity = 9.81

[hydro]
database = "{SPHERE_NC}"
added_mass_inf = "database"        # the database's A∞ as it is: the hand value below

[[bodies]]
name = "sphere"
mass = {M_SPHERE}
com = [0.0, 0.0, {ZG}]
principal_inertia = [{I_SPHERE}, {I_SPHERE}, {I_SPHERE}]
[bodies.joint]
type = "planar"
{springs}"""


def hand_surge_pitch():
    """ω² and mode shapes of the (surge, pitch) problem, all from hand values."""
    db = open_any_database(SPHERE_NC)
    rho, g = db.attrs["rho"], db.attrs["g"]
    V = float(db.displaced_volume[0])
    zB = float(db.center_of_buoyancy[0, 2])
    zr = float(db.reference_point[0, 2])
    C55 = float(db.waterplane_stiffness.values[4, 4])
    A = np.asarray(db.added_mass_inf.values)[np.ix_([0, 4], [0, 4])]
    A = 0.5 * (A + A.T)
    # pitch restoring about the CoM: water plane + buoyancy ρgV at z_B (weight at the CoM has no
    # moment about it); the two springs at ±ℓ add 2kℓ² and no surge–pitch coupling
    K = np.diag([2 * K_SPRING, 2 * K_SPRING * ELL**2 + C55 + rho * g * V * (zB - ZG)])
    H = np.array([[1.0, zr - ZG], [0.0, 1.0]])   # (ξ_surge, ξ_pitch) of the reference point
    M = np.diag([M_SPHERE, I_SPHERE]) + H.T @ A @ H
    lam, vec = scipy.linalg.eigh(K, M)
    return np.sqrt(lam), vec


def measured_period(t, x):
    """Mean period from the upward zero crossings (linear interpolation)."""
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    tc = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    assert len(tc) >= 3
    return (tc[-1] - tc[0]) / (len(tc) - 1)


@pytest.fixture(scope="module")
def moored_sphere(tmp_path_factory):
    path = tmp_path_factory.mktemp("moor") / "moored_sphere.toml"
    path.write_text(sphere_config())
    return mfm.load(path)


def test_surge_and_pitch_periods_against_hand(moored_sphere):
    model = moored_sphere
    omega, modes = hand_surge_pitch()
    iq = [model.coordinate_index("sphere.surge"), model.coordinate_index("sphere.pitch")]
    duration = 4 * 2 * math.pi / omega.min()     # one length for both runs: one compilation
    for m in range(2):
        q0 = np.zeros(model.n_coordinates)
        q0[iq] = 1e-3 * modes[:, m] / np.abs(modes[:, m]).max()   # small: linear regime
        T_hand = 2 * math.pi / omega[m]
        # radiation "none": A∞ only, no damping, so the released mode oscillates at exactly the
        # hand frequency
        ds = mfm.simulate(model, duration=duration, dt=0.01, q0=q0, radiation="none")
        k = iq[int(np.argmax(np.abs(modes[:, m])))]
        T_td = measured_period(ds.time.values, ds.q.values[:, k])
        # 2e-4: the zero-crossing interpolation at dt = 0.01 s and the 1e-3 amplitude (the exact
        # buoyancy's nonlinearity); the lever arm of the springs is 14 % of the pitch stiffness
        assert T_td == pytest.approx(T_hand, rel=2e-4), (m, T_td, T_hand)
