"""Mechanics without water against analytic solutions (validation ladder step 2)."""
import jax
import jax.numpy as jnp
import numpy as np

import mfm
from mfm.io.config import parse_config

G = 9.81


def build(bodies, gravity=G, name="t"):
    return mfm.compile_tree(parse_config({"model": {"gravity": gravity}, "bodies": bodies})[1], name=name,
                            gravity=gravity)


def zero_crossing_period(t, y):
    """Mean period from upward zero crossings (linear interpolation between samples)."""
    i = np.where((y[:-1] < 0) & (y[1:] >= 0))[0]
    tc = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    return np.mean(np.diff(tc))


def test_compound_pendulum_period():
    # T = 2π √(I_O / (m g L)), I_O = I_cm + m L², small amplitude (0.01 rad: the amplitude
    # correction θ₀²/16 = 6e-6 is below the 1e-5 tolerance, which also covers the zero-crossing
    # interpolation at dt = T/1000).
    m_, L, Icm = 3.0, 0.8, 0.25
    model = build([{"name": "rod", "mass": m_, "com": [0, 0, -L], "principal_inertia": [Icm, Icm, 0.01],
                    "joint": {"type": "revolute", "axis": [0, 1, 0], "point": [0, 0, 0]}}])
    T_exact = 2 * np.pi * np.sqrt((Icm + m_ * L**2) / (m_ * G * L))
    ds = mfm.simulate(model, duration=10 * T_exact, dt=T_exact / 1000, q0=[0.01])
    T = zero_crossing_period(ds.time.values, ds.q.values[:, 0])
    assert abs(T / T_exact - 1) < 1e-5


def test_double_pendulum_normal_modes():
    # Two point masses m on massless links of length L: ω² = (g/L)(2 ∓ √2). In mode 1 the absolute
    # angles are (1, √2); our second coordinate is relative to link 1: (1, √2 − 1). Tiny inertias
    # (1e-9 kg m²) stand in for point masses; their effect is ~1e-9 relative.
    L, mass = 1.0, 1.0
    tiny = [1e-9, 1e-9, 1e-9]
    model = build([
        {"name": "m1", "mass": mass, "com": [0, 0, -L], "principal_inertia": tiny,
         "joint": {"type": "revolute", "axis": [0, 1, 0], "point": [0, 0, 0]}},
        {"name": "m2", "parent": "m1", "mass": mass, "com": [0, 0, -2 * L], "principal_inertia": tiny,
         "joint": {"type": "revolute", "axis": [0, 1, 0], "point": [0, 0, -L]}}])
    for sign, shape in ((-1, [1.0, np.sqrt(2) - 1]), (+1, [1.0, -np.sqrt(2) - 1])):
        w = np.sqrt(G / L * (2 + sign * np.sqrt(2)))
        T_exact = 2 * np.pi / w
        q0 = 1e-3 * np.array(shape)
        ds = mfm.simulate(model, duration=8 * T_exact, dt=T_exact / 1000, q0=q0)
        T = zero_crossing_period(ds.time.values, ds.q.values[:, 0])
        assert abs(T / T_exact - 1) < 1e-5
        # a pure mode keeps its shape: the ratio of the coordinates stays constant
        ratio = ds.q.values[:, 1] / shape[1] - ds.q.values[:, 0] / shape[0]
        assert np.abs(ratio).max() < 1e-7


def test_free_fall_with_spin():
    # CoM falls as z₀ − ½ g t², moves on with its initial velocity, whatever the body's rotation.
    model = build([{"name": "b", "mass": 2.0, "com": [0, 0, 1.0],
                    "inertia": [[1.0, 0.1, 0], [0.1, 2.0, 0.05], [0, 0.05, 2.5]], "joint": {"type": "free"}}])
    qd0 = [0.5, -0.2, 3.0, 0.3, 0.2, -0.4]
    ds = mfm.simulate(model, duration=1.0, dt=1e-3, qd0=qd0)
    t = ds.time.values
    pos = ds.body_position.sel(body="b").values
    expected = np.stack([0.5 * t, -0.2 * t, 1.0 + 3.0 * t - 0.5 * G * t**2], axis=1)
    # RK4 integrates a quadratic exactly; what remains is round-off (≈1e-14 per step)
    np.testing.assert_allclose(pos, expected, atol=1e-10)


def _torque_free(I, w0, duration, dt):
    model = build([{"name": "b", "mass": 1.0, "com": [0, 0, 0], "principal_inertia": list(I),
                    "joint": {"type": "free", "dofs": ["roll", "pitch", "yaw"]}}], gravity=0.0)
    # root angles roll/pitch/yaw: body rates from the B-matrix rows at q = 0 equal (φ̇, θ̇, ψ̇)
    ds = mfm.simulate(model, duration=duration, dt=dt, qd0=w0)
    q, qd = ds.q.values, ds.qd.values
    B = jax.vmap(lambda q: mfm.b_matrix(model, q))(jnp.asarray(q))
    w = np.einsum("tij,tj->ti", np.asarray(B), qd)[:, 3:]          # body-axis ω
    R = jax.vmap(lambda q: mfm.body_poses(model, q)[1][0])(jnp.asarray(q))
    L = np.einsum("tij,tj->ti", np.asarray(R), w * np.asarray(I))   # inertial angular momentum
    E = 0.5 * np.sum(np.asarray(I) * w**2, axis=1)
    return ds.time.values, w, L, E


def test_torque_free_body_conserves_energy_and_angular_momentum():
    I = (1.0, 2.0, 3.0)
    t, w, L, E = _torque_free(I, [0.3, 0.2, 0.5], duration=20.0, dt=2e-3)
    # RK4 at ω dt ≈ 1e-3: the drift over 1e4 steps is O(dt⁴) ≈ 1e-12 relative; 1e-9 is generous
    assert np.abs(E / E[0] - 1).max() < 1e-9
    assert np.abs(L - L[0]).max() / np.linalg.norm(L[0]) < 1e-9


def test_intermediate_axis_instability():
    # Spin Ω about a principal axis plus a small perturbation. About the intermediate axis the
    # perturbation grows as e^{λt}, λ = Ω √((I₂−I₁)(I₃−I₂)/(I₁I₃)); about the others it stays bounded.
    # The spin axis is body x (roll), so the Euler angles stay away from pitch = ±90° while small.
    Omega, eps = 2.0, 1e-6
    cases = {"intermediate": (2.0, 1.0, 3.0), "minor": (1.0, 2.0, 3.0), "major": (3.0, 2.0, 1.0)}
    for label, I in cases.items():
        t, w, L, E = _torque_free(I, [Omega, eps, eps], duration=6.0, dt=2e-3)
        perturbation = np.hypot(w[:, 1], w[:, 2])
        if label == "intermediate":
            I2, I1, I3 = I  # I[0] is the intermediate moment
            lam = Omega * np.sqrt((I2 - I1) * (I3 - I2) / (I1 * I3))
            # growth rate fitted on the linear phase (perturbation still < 1e-2 of Ω); the
            # perturbation is a mix of the growing and decaying eigenvector: fit after 1/λ
            sel = (t > 1.5 / lam) & (perturbation < 1e-2 * Omega)
            rate = np.polyfit(t[sel], np.log(perturbation[sel]), 1)[0]
            assert abs(rate / lam - 1) < 0.01
        else:
            assert perturbation.max() < 10 * eps


def test_intermediate_axis_flip():
    # Past the linear phase the body flips: ω_x reverses sign (Dzhanibekov effect).
    t, w, L, E = _torque_free((2.0, 1.0, 3.0), [2.0, 1e-3, 1e-3], duration=10.0, dt=2e-3)
    assert w[:, 0].min() < -1.9 and w[0, 0] > 1.9
    assert np.abs(E / E[0] - 1).max() < 1e-8


def test_reactions_of_a_hanging_pendulum_and_free_root():
    # hanging at rest: the pivot carries the weight
    model = build([{"name": "bob", "mass": 2.0, "com": [0, 0, -1.0], "principal_inertia": [0.1, 0.1, 0.1],
                    "joint": {"type": "revolute", "axis": [0, 1, 0], "point": [0, 0, 0], "damping": 0.7}}])
    ev = mfm.evaluate(model, np.zeros(1), np.zeros(1))
    f, m = mfm.reaction_loads(model, ev)
    np.testing.assert_allclose(f[0], [0, 0, 2.0 * G], atol=1e-12)
    np.testing.assert_allclose(m[0], 0, atol=1e-12)
    # swinging: the moment about the hinge axis equals the damper torque −c θ̇ (Bᵀ r = Q)
    ev = mfm.evaluate(model, np.array([0.4]), np.array([1.3]))
    f, m = mfm.reaction_loads(model, ev)
    np.testing.assert_allclose(m[0][1], -0.7 * 1.3, atol=1e-12)
    # centripetal + gravity: radial force = m (g cos θ + L θ̇²) towards the pivot
    th, thd = 0.4, 1.3
    radial = np.array([np.sin(th), 0, np.cos(th)])  # from the bob to the pivot
    np.testing.assert_allclose(np.dot(f[0], radial), 2.0 * (G * np.cos(th) + 1.0 * thd**2), rtol=1e-12)


def test_free_root_transmits_nothing_and_hinges_transmit_their_torque():
    from test_kinematics import tilted_free_tree
    model = tilted_free_tree()
    rng = np.random.default_rng(0)
    for _ in range(3):
        q, qd = rng.normal(size=model.n_coordinates) * 0.3, rng.normal(size=model.n_coordinates)
        wrench = rng.normal(size=(model.n_bodies, 6))
        tau = rng.normal(size=model.n_coordinates)
        ev = mfm.evaluate(model, q, qd, tau=tau, body_loads=wrench)
        f, m = mfm.reaction_loads(model, ev)
        kin = mfm.kinematics(model, q)
        root_cols = model.joint_coordinates("hull")
        for name in ("arm", "tip"):
            i = model.body_index(name)
            axis = np.asarray(kin.joint_frame[i, :3, :3]) @ np.asarray(model.motion_axes[i][0])
            k = model.coordinate_index(f"{name}.angle")
            np.testing.assert_allclose(np.dot(m[i], axis), ev.Q[k], atol=1e-9)
        i = model.body_index("slider")
        axis = np.asarray(kin.joint_frame[i, :3, :3]) @ np.asarray(model.motion_axes[i][0])
        np.testing.assert_allclose(np.dot(f[i], axis), ev.Q[model.coordinate_index("slider.stroke")],
                                   atol=1e-9)
        # a full free root with no load on its own coordinates receives nothing from the inertial
        # frame, however the rest of the tree is loaded
        tau0 = tau.copy()
        tau0[list(root_cols)] = 0.0
        ev0 = mfm.evaluate(model, q, qd, tau=tau0, body_loads=wrench)
        f0, m0 = mfm.reaction_loads(model, ev0)
        np.testing.assert_allclose(f0[0], 0, atol=1e-9)
        np.testing.assert_allclose(m0[0], 0, atol=1e-9)


def test_spd_solve_matches_lapack_across_the_unrolled_threshold():
    # the unrolled elimination (n ≤ 12) and the Cholesky path (n > 12) against numpy's LU solve on
    # SPD matrices with condition numbers up to 1e8 (M4 134's M* + HᵀA∞H is ~1e4): backward
    # stable, so the relative error is a few ε·cond
    from mfm.mechanics.dynamics import spd_solve
    rng = np.random.default_rng(3)
    for n in (1, 2, 7, 12, 13, 20):
        for cond in (1.0, 1e4, 1e8):
            Q, _ = np.linalg.qr(rng.normal(size=(n, n)))
            A = (Q * np.logspace(0, np.log10(cond), n)) @ Q.T
            A = 0.5 * (A + A.T)
            b = rng.normal(size=n)
            x = np.asarray(jax.jit(spd_solve)(jnp.asarray(A), jnp.asarray(b)))
            ref = np.linalg.solve(A, b)
            assert np.linalg.norm(x - ref) <= 1e-13 * cond * np.linalg.norm(ref), (n, cond)
    # a zero pivot gives non-finite values (a run's non-finite check then stops it), never a
    # finite answer
    assert not np.all(np.isfinite(np.asarray(spd_solve(jnp.zeros((3, 3)), jnp.ones(3)))))
