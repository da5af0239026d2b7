"""Integrators: measured convergence order, auxiliary states, long-run energy (ladder step 2)."""
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

import mfm
from mfm.io.config import parse_config
from mfm.loads import Load, LoadOutput

M, K, C = 2.0, 50.0, 1.5          # slider mass, spring, damper
K2, C2 = 30.0, 4.0                 # Maxwell element: spring K2 in series with damper C2


def slider(k=K, c=C):
    # prismatic along x: gravity (along −z) does no work on it
    return mfm.compile_tree(parse_config({"bodies": [
        {"name": "s", "mass": M, "com": [0, 0, 0], "principal_inertia": [1, 1, 1],
         "joint": {"type": "prismatic", "axis": [1, 0, 0], "stiffness": k, "damping": c}}]})[1])


class Maxwell(Load):
    """Spring K2 from the body to a massless node y, damper C2 from y to ground: z = (y,),
    ẏ = K2 (x − y)/C2, force on the body −K2 (x − y). A first-order state for the integrators."""
    k: float = K2
    c: float = C2

    @property
    def n_states(self):
        return 1

    def __call__(self, model, t, q, qd, z, kin, memory=(), qdd_guess=None):
        stretch = q[0] - z[0]
        return LoadOutput(tau=jnp.array([-self.k * stretch]), zd=jnp.array([self.k * stretch / self.c]))


def exact(t, x0, v0, y0=None):
    if y0 is None:
        A = np.array([[0, 1], [-K / M, -C / M]])
        return scipy.linalg.expm(A * t) @ np.array([x0, v0])
    A = np.array([[0, 1, 0], [-(K + K2) / M, -C / M, K2 / M], [K2 / C2, 0, -K2 / C2]])
    return scipy.linalg.expm(A * t) @ np.array([x0, v0, y0])


SCHEMES = {"rk4": (mfm.integrators.RK4(), 4), "beeman": (mfm.integrators.Beeman(tol=1e-13), 2),
           "newmark": (mfm.integrators.Newmark(), 2), "semi_implicit": (mfm.integrators.SemiImplicitEuler(), 1),
           "verlet": (mfm.integrators.Verlet(), 2)}


def measured_order(integ, with_state):
    model = slider()
    T = 2.0
    dts = np.array([0.02, 0.01, 0.005, 0.0025])
    errs = []
    for dt in dts:
        n = int(round(T / dt))
        loads = (Maxwell(),) if with_state else ()
        out = mfm.rollout(model, [0.1], [0.0], dt=dt, n_steps=n, integrator=integ, loads=loads)
        q, qd, z = out[1][-1, 0], out[2][-1, 0], out[4][-1]
        ref = exact(T, 0.1, 0.0, 0.0 if with_state else None)
        err = abs(q - ref[0]) + abs(qd - ref[1]) + (abs(z[0] - ref[2]) if with_state else 0.0)
        errs.append(float(err))
    return np.polyfit(np.log(dts), np.log(errs), 1)[0], errs


@pytest.mark.parametrize("name", sorted(SCHEMES))
@pytest.mark.parametrize("with_state", [False, True], ids=["mechanical", "with_aux_state"])
def test_convergence_order(name, with_state):
    integ, order = SCHEMES[name]
    slope, errs = measured_order(integ, with_state)
    # the slope of log error against log dt over a factor 8 in dt: within ±0.25 of the theory
    # (higher-order error terms bend the line a little at the coarse end)
    assert abs(slope - order) < 0.25, (name, slope, errs)


def test_beeman_with_seed_tolerance_counts_iterations():
    model = slider()
    out = mfm.rollout(model, [0.1], [0.0], dt=0.01, n_steps=100, integrator=mfm.integrators.Beeman(tol=0.01))
    iters = np.asarray(out[5])
    assert iters[1:].min() >= 1 and iters.max() <= 50
    # the seed's 1 % corrector on this smooth problem: a few iterations per step
    assert iters[1:].mean() < 5


def branched_tree():
    J = [[0.2, 0.01, 0.0], [0.01, 0.3, 0.02], [0.0, 0.02, 0.25]]
    return mfm.compile_tree(parse_config({"bodies": [
        {"name": "a", "mass": 2.0, "com": [0.3, 0.1, -1.0], "inertia": J,
         "joint": {"type": "revolute", "axis": [0.1, 1.0, 0.2], "point": [0, 0, 0]}},
        {"name": "b", "parent": "a", "mass": 1.0, "com": [0.8, 0.0, -1.6], "inertia": J,
         "joint": {"type": "revolute", "axis": [1.0, 0.3, 0.0], "point": [0.4, 0.1, -1.1]}},
        {"name": "c", "parent": "a", "mass": 1.5, "com": [-0.3, 0.2, -1.7], "inertia": J,
         "joint": {"type": "prismatic", "axis": [0.2, 0.0, 1.0], "stiffness": 200.0}},
        {"name": "d", "parent": "b", "mass": 0.5, "com": [1.2, 0.3, -2.0], "inertia": J,
         "joint": {"type": "revolute", "axis": [0.0, 1.0, 0.0], "point": [1.0, 0.2, -1.8]}}]})[1])


@pytest.mark.parametrize("name,bound", [("rk4", 1e-8), ("newmark", 1e-5)])
def test_energy_of_undamped_tree_over_1e4_steps(name, bound):
    # 10⁴ steps of dt = 1 ms on a branched, undamped 4-body tree swinging through ±0.5 rad.
    # RK4: its O(dt⁴) drift stays below 1e-8 of the energy scale (measured 2.8e-10).
    # Newmark average acceleration conserves energy exactly only for linear systems; here its
    # error stays bounded (no drift) at 5.7e-7 of the energy scale (measured); the bound is 1e-5.
    model = branched_tree()
    ds = mfm.simulate(model, duration=10.0, dt=1e-3, q0=[0.5, -0.3, 0.05, 0.4], integrator=name,
                      save_every=10)
    E = (ds.kinetic_energy + ds.potential_energy).values
    scale = float(ds.kinetic_energy.max())
    assert np.abs(E - E[0]).max() / scale < bound
    if name == "newmark":  # bounded, not drifting: the last tenth is no worse than the first
        n = len(E) // 10
        assert np.abs(E[-n:] - E[0]).max() < 3 * np.abs(E[:n] - E[0]).max() + 1e-12 * scale


def test_rk4_rolled_stages_equal_the_textbook_step():
    """RK4's four evaluations run as one rolled loop over a single f (one copy of the dynamics in
    the compiled time loop; compile of M4 134's RK4 rollout 29.5 → 7.8 s, benchmarks/
    step_profile.py). One step on a nonlinear, time-dependent f with a first-order state must equal
    the classical stages written out (Hairer, Nørsett & Wanner, Table 1.2): 1e-14, round-off."""
    import mfm.integrators as integ

    def f(t, q, qd, z):
        return (-jnp.sin(q) - 0.3 * qd + jnp.cos(2.0 * t) + 0.5 * z,
                -1.5 * z + q * qd)

    q0, v0, z0 = jnp.array([0.7, -1.1]), jnp.array([0.4, 2.0]), jnp.array([0.2, -0.5])
    t0, h = 0.3, 0.05
    rk = integ.RK4()
    s = rk.step(f, rk.init(f, t0, q0, qd0=v0, z0=z0), h)

    x = np.concatenate([q0, v0, z0])

    def F(t, x):
        a, zd = f(t, x[:2], x[2:4], x[4:])
        return np.concatenate([x[2:4], a, zd])

    k1 = F(t0, x)
    k2 = F(t0 + h / 2, x + h / 2 * k1)
    k3 = F(t0 + h / 2, x + h / 2 * k2)
    k4 = F(t0 + h, x + h * k3)
    x1 = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    a1, zd1 = f(t0 + h, x1[:2], x1[2:4], x1[4:])
    got = np.concatenate([s.q, s.qd, s.z, s.qdd, s.zd])
    want = np.concatenate([x1, a1, zd1])
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=1e-14)
    assert float(s.t) == pytest.approx(t0 + h, abs=1e-15)
