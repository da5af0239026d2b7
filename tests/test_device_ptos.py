"""The hydraulic PTO of seed 000 (f = μ ẅ + β ẇ + κ w resisting the stroke), oblique and between two
hinged bodies as the seed 000 platform and M4 use it, against an independent model: the Lagrangian
of the same system written here from the positions of the points (jax for the derivatives), with
the oil mass as the kinetic energy ½ μ ẇ², κ as ½ κ w², β as the Rayleigh function ½ β ẇ².

Checked: the trajectory (mfm vs the Lagrangian's ODE), the stroke and piston force, the energy
balance (work of the applied loads = ΔE + ∫ β ẇ² dt) and Newton's third law on the two ends (the
joint reactions mfm reports against the Newton equations of each body with ±f u at the ends).
The PTO line is out of the plane of motion and at an angle to everything, so the geometric term
(|Δv|² − ẇ²)/L of ẅ and the reaction on the second body are both exercised.
"""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mfm
from mfm.loads import BodyWrench

G = 9.81
BASE = dict(m=8.0, c=np.array([0.0, 0.0, 0.0]), Iyy=1.2, k=np.array([40.0, 60.0, 30.0]))
ARM = dict(m=3.0, c=np.array([1.0, 0.0, -0.2]), Iyy=0.4, k=5.0)
HINGE = np.array([0.4, 0.0, 0.1])
P_ARM = np.array([1.5, 0.3, -0.1])       # on the arm
P_BASE = np.array([-0.3, -0.2, -0.8])    # on the base: the line leaves the x–z plane
MU, BETA, KAPPA = 2.5, 6.0, 40.0
F_BASE = np.array([5.0, 0.0, 3.0])       # applied force on the base CoM, N (inertial)
M_ARM = 0.7                              # applied moment about y on the arm, N m

CONFIG = f"""
[model]
name = "hinged pto"
gravity = {G}

[[bodies]]
name = "base"
mass = {BASE['m']}
com = {BASE['c'].tolist()}
principal_inertia = [1.0, {BASE['Iyy']}, 1.0]
[bodies.joint]
type = "planar"
stiffness = {BASE['k'].tolist()}

[[bodies]]
name = "arm"
parent = "base"
mass = {ARM['m']}
com = {ARM['c'].tolist()}
principal_inertia = [0.3, {ARM['Iyy']}, 0.3]
[bodies.joint]
type = "revolute"
axis = [0.0, 1.0, 0.0]
point = {HINGE.tolist()}
stiffness = {ARM['k']}

[[ptos]]
name = "piston"
body = "arm"
point = {P_ARM.tolist()}
anchor_body = "base"
anchor = {P_BASE.tolist()}
mu = {MU}
beta = {BETA}
kappa = {KAPPA}
"""


# ------------------------------------------------------------ the independent model (q = x, z, θ, φ)
def Ry(a):
    c, s = jnp.cos(a), jnp.sin(a)
    return jnp.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def base_point(q, p0):
    """A point fixed on the base: the CoM moves by (x, 0, z), the body turns by R_y(θ)."""
    return BASE["c"] + jnp.array([q[0], 0.0, q[1]]) + Ry(q[2]) @ (p0 - BASE["c"])


def arm_point(q, p0):
    """A point fixed on the arm: it turns by R_y(θ + φ) about the hinge carried by the base."""
    return base_point(q, HINGE) + Ry(q[2] + q[3]) @ (p0 - HINGE)


def stroke(q):
    d = arm_point(q, P_ARM) - base_point(q, P_BASE)
    return jnp.linalg.norm(d) - np.linalg.norm(P_ARM - P_BASE)


def kinetic(q, qd):
    vb = jax.jvp(lambda s: base_point(s, BASE["c"]), (q,), (qd,))[1]
    va = jax.jvp(lambda s: arm_point(s, ARM["c"]), (q,), (qd,))[1]
    wd = jax.jvp(stroke, (q,), (qd,))[1]
    return (0.5 * BASE["m"] * vb @ vb + 0.5 * BASE["Iyy"] * qd[2] ** 2 + 0.5 * ARM["m"] * va @ va
            + 0.5 * ARM["Iyy"] * (qd[2] + qd[3]) ** 2 + 0.5 * MU * wd**2)


def potential(q):
    springs = 0.5 * jnp.sum(BASE["k"] * q[:3] ** 2) + 0.5 * ARM["k"] * q[3] ** 2
    return (G * (BASE["m"] * base_point(q, BASE["c"])[2] + ARM["m"] * arm_point(q, ARM["c"])[2])
            + springs + 0.5 * KAPPA * stroke(q) ** 2)


def generalised_applied(q):
    """Generalised loads of F_BASE at the base CoM and M_ARM about y on the arm (virtual work)."""
    Jb = jax.jacfwd(lambda s: base_point(s, BASE["c"]))(q)
    return Jb.T @ F_BASE + M_ARM * jnp.array([0.0, 0.0, 1.0, 1.0])


@jax.jit
def qdd_lagrange(q, qd):
    M = jax.hessian(kinetic, argnums=1)(q, qd)
    dTdq = jax.grad(kinetic, argnums=0)(q, qd)
    mixed = jax.jacfwd(jax.grad(kinetic, argnums=1), argnums=0)(q, qd)
    gw = jax.grad(stroke)(q)
    rhs = (dTdq - mixed @ qd - jax.grad(potential)(q) - BETA * (gw @ qd) * gw
           + generalised_applied(q))
    return jnp.linalg.solve(M, rhs)


Q0 = np.array([0.05, -0.1, 0.15, -0.3])
QD0 = np.array([0.4, -0.3, 1.0, 3.0])
DT, DURATION = 1e-3, 2.0
SUB = 4                                   # reference steps per mfm step


def reference(t_end):
    """The Lagrangian's ODE by classical RK4 at DT/SUB (its own loop, not mfm's integrator), saved
    every DT: global error ~ (DT/SUB)⁴ ≈ 1e-14 relative."""
    h = DT / SUB

    def f(y):
        return jnp.concatenate([y[4:], qdd_lagrange(y[:4], y[4:])])

    def step(y, _):
        k1 = f(y)
        k2 = f(y + 0.5 * h * k1)
        k3 = f(y + 0.5 * h * k2)
        k4 = f(y + h * k3)
        return y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), None

    def saved(y, _):
        y = jax.lax.scan(step, y, None, length=SUB)[0]
        return y, y

    y0 = jnp.concatenate([jnp.asarray(Q0), jnp.asarray(QD0)])
    _, ys = jax.jit(lambda y: jax.lax.scan(saved, y, None, length=int(round(t_end / DT))))(y0)
    return np.vstack([np.asarray(y0)[None], np.asarray(ys)])


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    path = tmp_path_factory.mktemp("pto") / "hinged_pto.toml"
    path.write_text(CONFIG)
    model = mfm.load(path)
    assert model.coordinates == ("base.surge", "base.heave", "base.pitch", "arm.angle")
    wrench = np.zeros((2, 6))
    wrench[0, :3] = F_BASE
    wrench[1, 4] = M_ARM                   # body axes: y stays y in planar motion
    ds = mfm.simulate(model, duration=DURATION, dt=DT, q0=Q0, qd0=QD0,
                      loads=[BodyWrench(wrench=jnp.asarray(wrench))])
    return model, ds, reference(DURATION)


def test_trajectory_matches_the_lagrangian(runs):
    _, ds, ref = runs
    # 1e-7: mfm's rk4 at dt = 1 ms (error ~1e-9 here) against the reference at dt/4; a flipped
    # geometric term of ẅ changes q by ~1e-3 within the 2 s
    np.testing.assert_allclose(ds.q.values, ref[:, :4], atol=1e-7, rtol=0)
    np.testing.assert_allclose(ds.qd.values, ref[:, 4:], atol=1e-6, rtol=0)


def test_stroke_and_piston_force(runs):
    _, ds, _ = runs
    q, qd, qdd = (jnp.asarray(ds[v].values) for v in ("q", "qd", "qdd"))

    def force(q, qd, qdd):
        w = stroke(q)
        gw = jax.grad(stroke)(q)
        wd = gw @ qd
        wdd = gw @ qdd + qd @ jax.hessian(stroke)(q) @ qd     # ẅ = g q̈ + q̇ᵀ ∇²w q̇
        return w, MU * wdd + BETA * wd + KAPPA * w

    w, f = jax.vmap(force)(q, qd, qdd)
    # 1e-10 m / 1e-8 N: the same function of mfm's own (q, q̇, q̈), float64 rounding only
    np.testing.assert_allclose(ds.pto_displacement.sel(pto="piston").values, w, atol=1e-10)
    np.testing.assert_allclose(ds.pto_force.sel(hydraulic_pto="piston").values, f, atol=1e-8)
    assert np.abs(f).max() > 5.0          # the test is not vacuous: the piston works hard


def test_energy_balance(runs):
    _, ds, _ = runs
    q, qd = jnp.asarray(ds.q.values), jnp.asarray(ds.qd.values)
    w = jax.vmap(stroke)(q)
    wd = jax.vmap(lambda a, b: jax.grad(stroke)(a) @ b)(q, qd)
    # mfm's energies (bodies, gravity, joint springs) + the piston's oil mass and spring
    E = (ds.kinetic_energy.values + ds.potential_energy.values + 0.5 * MU * np.asarray(wd) ** 2
         + 0.5 * KAPPA * np.asarray(w) ** 2)
    xb = ds.body_position.sel(body="base").values
    work_in = (xb - xb[0]) @ F_BASE + M_ARM * (ds.q.values[:, 2] + ds.q.values[:, 3] - Q0[2] - Q0[3])
    p = ds.pto_power.sel(pto="piston").values                  # β ẇ² as mfm records it
    np.testing.assert_allclose(p, BETA * np.asarray(wd) ** 2, rtol=1e-8, atol=1e-9)
    t = ds.time.values
    dissipated = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(t))])
    # 1e-5 J: the trapezoid rule on the 1 ms grid (error ≲ dt² max|d²P/dt²| t / 12 ≈ 1e-6 J) and
    # the rk4 energy drift; the balance involves energies of ~20 J and a dissipation of several J
    assert dissipated[-1] > 1.0
    np.testing.assert_allclose(work_in - (E - E[0]) - dissipated, 0.0, atol=1e-5)


def test_newton_third_law_on_the_two_ends(runs):
    """joint_force of the arm = m a − m g − (−f u) and of the base = m a − m g − (+f u) +
    joint_force of the arm: the piston pulls the two ends with equal and opposite forces."""
    _, ds, _ = runs
    q, qd, qdd = (jnp.asarray(ds[v].values) for v in ("q", "qd", "qdd"))

    def accel(point_fn, c):
        def a(q, qd, qdd):
            J = jax.jacfwd(lambda s: point_fn(s, c))(q)
            Jd = jax.jvp(lambda s: jax.jacfwd(lambda r: point_fn(r, c))(s) @ qd, (q,), (qd,))[1]
            return J @ qdd + Jd
        return jax.vmap(a)(q, qd, qdd)

    a_base, a_arm = accel(base_point, BASE["c"]), accel(arm_point, ARM["c"])
    d = jax.vmap(lambda s: arm_point(s, P_ARM) - base_point(s, P_BASE))(q)
    u = d / jnp.linalg.norm(d, axis=1, keepdims=True)          # from the base end to the arm end
    f = ds.pto_force.sel(hydraulic_pto="piston").values[:, None]
    gvec = np.array([0.0, 0.0, -G])
    F_arm = ARM["m"] * (a_arm - gvec) + f * u                  # the arm end feels −f u
    F_base = BASE["m"] * (a_base - gvec) - f * u - F_BASE + F_arm
    # 1e-8 N on forces of 10–100 N: the same kinematics, rounding only
    np.testing.assert_allclose(ds.joint_force.sel(body="arm").values, F_arm, atol=1e-8)
    np.testing.assert_allclose(ds.joint_force.sel(body="base").values, F_base, atol=1e-8)
    # the piston's out-of-plane (y) pull on the two ends cancels: no y load on the planar root
    # beyond the bodies' own (zero) y inertia
    np.testing.assert_allclose(ds.joint_force.sel(body="base", axis="y").values, 0.0, atol=1e-8)
