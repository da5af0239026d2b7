"""mfm.stability: the amplification matrix of the engine's own step against closed forms, the
predicted stability boundary against runs, Floquet multipliers against independent answers.

The whole map (7 schemes × 11 added-mass ratios) and the RM3 Floquet study are measured by
tools/stability_study.py (docs/stability.md); here a few points of each."""

import math
import warnings

import jax.numpy as jnp
import numpy as np
import pytest

import mfm
from hydro.database import HydroDatabaseWarning
from mfm.studies import floquet as fq
from mfm.studies import stability as st
from mfm.loads.base import Load, LoadOutput


# -- the amplification matrix against closed forms ------------------------------------------

def test_rk4_spectral_radius_is_its_stability_polynomial():
    # RK4 on q̈ = −ω² q: the step multiplies the modes by R(±iωdt), R(z) = 1 + z + z²/2 + z³/6 +
    # z⁴/24 (Hairer & Wanner II §IV.2); the jacobian of the engine's step must give |R| to
    # round-off (1e-12: a few operations on O(1) numbers)
    for y in (0.3, 1.0, 2.0, 2.8, 3.0):
        z = 1j * y
        R = 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
        G = st.amplification_matrix("rk4", y, 1.0, 0.0, 1.0)
        assert st.spectral_radius(G) == pytest.approx(abs(R), abs=1e-12)


def test_stability_limits_against_closed_forms():
    # undamped oscillator, ω = 1: RK4 |R(iy)| = 1 at y = 2√2; semi-implicit Euler and Störmer–
    # Verlet: eigenvalues on the unit circle while (ωdt)² < 4; Beeman (converged corrector on an
    # undamped system: one iteration, Verlet) likewise; Newmark average acceleration
    # unconditionally stable. Bisection to 1e-12, the eigenvalue's sensitivity at the double root
    # -1 is √ε ≈ 1e-8: 1e-6.
    for name, limit in (("rk4", 2 * math.sqrt(2)), ("semi_implicit", 2.0), ("verlet", 2.0),
                        ("beeman", 2.0)):
        assert st.largest_stable_dt(name, 1.0, 0.0, 1.0) == pytest.approx(limit, rel=1e-6), name
    assert st.largest_stable_dt("newmark", 1.0, 0.0, 1.0) == math.inf
    # added mass in M*: the limit is that of ω = √(K/(M + A∞)): scaling M + A∞ by 4 doubles it
    assert st.largest_stable_dt("rk4", 1.0, 0.0, 1.0, A_inf=3.0) == pytest.approx(
        4 * math.sqrt(2), rel=1e-6)


def test_lagged_added_mass_is_unstable_at_every_dt_when_it_exceeds_the_mass():
    # the seed's A∞ q̈ on the right-hand side with no corrector: q̈ₙ₊₁ = −(A∞/m) q̈ₙ + …, so a
    # root −A∞/m as dt → 0: unstable at every dt once A∞ > m; with the corrector the fixed-point
    # iteration a ← −(A∞/m) a + … diverges there too
    for integ in (mfm.integrators.Beeman(max_iter=0), mfm.integrators.Beeman()):
        assert st.largest_stable_dt(integ, 1.0, 0.05, 2.0, A_inf=1.2, added_mass="rhs") == 0.0
        G = st.amplification_matrix(integ, 1e-4, 1.0, 0.0, 1.0, A_inf=1.2, added_mass="rhs")
        assert st.spectral_radius(G) > 1.19
    # below it the corrector restores Verlet's limit ω dt = 2 at A∞/m = 0.5 (2 % damping: ρ < 1
    # inside), and the lagged one loses half of it (map: 1.0775 against 1.9999, ω = 1)
    z = 0.02
    c = 2 * z * 1.5
    with_c = st.largest_stable_dt(mfm.integrators.Beeman(), 1.0, c, 1.5, A_inf=0.5,
                                  added_mass="rhs")
    lagged = st.largest_stable_dt(mfm.integrators.Beeman(max_iter=0), 1.0, c, 1.5, A_inf=0.5,
                                  added_mass="rhs")
    assert with_c == pytest.approx(2.0, rel=0.01) and lagged < 0.6 * with_c


# -- predicted against measured: runs of the engine on a heave model -------------------------

@pytest.fixture(scope="module")
def heave():
    with warnings.catch_warnings():
        # the hemisphere's database, as configs/sphere.toml uses it
        warnings.simplefilter("ignore", HydroDatabaseWarning)
        return st.heave_model(0.02)


@pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")
@pytest.mark.parametrize("name, added_mass, ratio", [
    ("verlet", "lhs", 4.0), ("beeman", "rhs", 0.5), ("beeman0", "rhs", 0.9)])
def test_predicted_boundary_within_ten_percent_of_runs(heave, name, added_mass, ratio):
    # the acceptance: the dt of ρ(G) = 1 (the linear heave equation of the model's own numbers)
    # against rollouts of the engine (its water load, A∞ scaled to A∞/m = ratio): a run at 0.9 of
    # the predicted dt stays bounded and one at 1.1 of it grows (2000 steps; > 1e3 × its start).
    # Three points (each integrator costs a compilation of the rollout, 5–10 s); the whole map,
    # every integrator × 11 ratios, is measured by tools/stability_study.py map (docs/stability.md)
    model, p = heave
    integ = mfm.integrators.Beeman(max_iter=0) if name == "beeman0" else name
    m, K, c = p["m"], p["K"], p["c"]
    dt = st.largest_stable_dt(integ, m, c, K, A_inf=ratio * m, added_mass=added_mass)
    assert 0 < dt < math.inf
    assert not st.run_grows(model, ratio, 0.9 * dt, integrator=integ, added_mass=added_mass)
    assert st.run_grows(model, ratio, 1.1 * dt, integrator=integ, added_mass=added_mass)


@pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")
def test_unstable_at_every_dt_measured(heave):
    # A∞/m = 2 on the right-hand side: predicted 0 (unstable at every dt); a run at T_min/100 grows.
    # (Newmark's "no limit", measured bounded at 2 T_min for every ratio, is in the map.)
    model, p = heave
    T_min = 2 * math.pi * math.sqrt(3 * p["m"] / p["K"])
    assert st.run_grows(model, 2.0, T_min / 100, integrator="beeman", added_mass="rhs")


# -- Floquet multipliers -----------------------------------------------------------------------

OSCILLATOR = """
[model]
name = "oscillator"
gravity = 0.0
[[bodies]]
name = "b"
mass = {m!r}
com = [0.0, 0.0, 0.0]
principal_inertia = [1.0, 1.0, 1.0]
[bodies.joint]
type = "free"
dofs = ["heave"]
stiffness = [{k!r}]
damping = [{c!r}]
"""


@pytest.fixture(scope="module")
def oscillator(tmp_path_factory):
    """A one-coordinate spring–damper; set m, k, c with :func:`_osc` (one model, so the Floquet
    tests share their compiled flow maps)."""
    p = tmp_path_factory.mktemp("osc") / "osc.toml"
    p.write_text(OSCILLATOR.format(m=1.0, k=1.0, c=0.0))
    return mfm.load(p)


def _osc(model, m, k, c):
    return model.replace(mass=jnp.asarray([m]), stiffness=jnp.asarray([k]),
                         damping=jnp.asarray([c]))


class _Mathieu(Load):
    """τ = −k ε cos(Ω t) q on the single coordinate: a time-periodic stiffness."""
    k: float
    eps: float
    Omega: float

    def evaluate(self, ctx):
        return LoadOutput(tau=-self.k * self.eps * jnp.cos(self.Omega * ctx.t) * ctx.q)

    def static_load(self):
        return None


def test_floquet_of_the_damped_mathieu_equation_against_scipy(oscillator):
    # m q̈ + c q̇ + k (1 + ε cos 2ω₀t) q = 0 in its first instability tongue: the monodromy over
    # the forcing period π/ω₀ by scipy's solve_ivp (rtol 1e-11, an independent integrator) against
    # the engine's (RK4, dt = T/400: RK4's error over one period ≈ 1e-9); 1e-7 on the multipliers.
    # The period-doubling multiplier is real and < −1 (the response oscillates at 2T), and
    # σ ≈ ε ω₀/4 − ζ ω₀ (first-order perturbation theory) to 10 %.
    from scipy.integrate import solve_ivp

    m, k, zeta, eps = 1.0, 1.0, 0.01, 0.2
    w0 = math.sqrt(k / m)
    c = 2 * zeta * w0 * m
    T = math.pi / w0
    model = _osc(oscillator, m, k, c)
    load = _Mathieu(k=k, eps=eps, Omega=2 * w0)
    dt = T / 400
    r = fq.floquet(model, None, period=T, dt=dt, t_start=0.0, integrator="rk4", loads=[load],
                   refine=0)

    def rhs(t, y):
        return [y[1], -(c * y[1] + k * (1 + eps * math.cos(2 * w0 * t)) * y[0]) / m]

    Phi = np.column_stack([solve_ivp(rhs, (0, T), e, rtol=1e-11, atol=1e-13).y[:, -1]
                           for e in np.eye(2)])
    mu_ref = np.sort_complex(np.linalg.eigvals(Phi))
    mu = np.sort_complex(r.multipliers[np.abs(r.multipliers) > 1e-8])
    np.testing.assert_allclose(mu, mu_ref, atol=1e-7)
    assert abs(r.multipliers[0].imag) < 1e-12 and r.multipliers[0].real < -1
    assert r.growth_rates[0] == pytest.approx(eps * w0 / 4 - zeta * w0, rel=0.1)


def test_floquet_of_a_time_invariant_system_is_the_step_power(oscillator):
    # LTI (the Mathieu load below with ε = 0: the same compiled flow map): the flow map over n
    # steps is Gⁿ, so the multipliers are R(λ dt)ⁿ for RK4 (λ the eigenvalues of the oscillator),
    # which tend to e^{λT}: exact to round-off against the discrete form (1e-10), to RK4's error
    # against the continuous one (ω dt = 0.016: 1e-8 over the period; 1e-6)
    m, k, c = 2.0, 8.0, 0.4
    model = _osc(oscillator, m, k, c)
    T, n = math.pi, 400
    dt = T / n
    r = fq.floquet(model, None, period=T, dt=dt, t_start=0.0, integrator="rk4", refine=0,
                   loads=[_Mathieu(k=k, eps=0.0, Omega=2.0)])
    lam = np.roots([m, c, k])
    z = lam * dt
    R = 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
    nonzero = np.sort_complex(r.multipliers[np.abs(r.multipliers) > 1e-8])
    np.testing.assert_allclose(nonzero, np.sort_complex(R ** n), atol=1e-10)
    np.testing.assert_allclose(nonzero, np.sort_complex(np.exp(lam * T)), atol=1e-6)
    np.testing.assert_allclose(r.growth_rates[0], lam.real[0], rtol=1e-6)


def test_envelope_growth_rate_of_a_synthetic_run():
    # a T-periodic forced part plus a growing period-doubled one: the fit must return σ (1e-3:
    # the per-period peak of a sampled sinusoid is within 0.02 % of its envelope at 40 samples)
    T, sigma = 8.0, 0.01
    t = np.arange(0, 800, 0.2)
    y = 0.03 * np.sin(2 * np.pi * t / T) + 1e-4 * np.exp(sigma * t) * np.cos(np.pi * t / T)
    s, mids, peaks = fq.envelope_growth_rate(t, y, T, 100.0, 500.0)
    assert s == pytest.approx(sigma, rel=1e-3)


# -- bad arguments --------------------------------------------------------------------------------

def test_bad_arguments_name_the_argument_value_and_what_is_accepted(oscillator):
    with pytest.raises(ValueError, match=r"added_mass='middle'; accepted: 'lhs'.*'rhs'"):
        st.amplification_matrix("rk4", 0.1, 1.0, 0.0, 1.0, added_mass="middle")
    with pytest.raises(ValueError, match=r"integrator='euler' is not known; accepted"):
        st.amplification_matrix("euler", 0.1, 1.0, 0.0, 1.0)
    with pytest.raises(ValueError, match=r"dt: -0.1; give a positive finite number"):
        st.amplification_matrix("rk4", -0.1, 1.0, 0.0, 1.0)
    with pytest.raises(ValueError, match=r"K: shape \(2, 3\); give a square matrix"):
        st.amplification_matrix("rk4", 0.1, np.eye(2), np.zeros((2, 2)), np.ones((2, 3)))
    with pytest.raises(ValueError, match=r"added_mass='rhs' with integrator='rk4'.*accepted: "
                                         r"integrator='beeman'"):
        st.largest_stable_dt("rk4", 1.0, 0.0, 1.0, A_inf=0.5, added_mass="rhs")
    model = _osc(oscillator, 1.0, 1.0, 0.1)
    with pytest.raises(ValueError, match=r"period: 1.05 s is not a whole number of steps of "
                                         r"dt = 0.1 s"):
        fq.floquet(model, None, period=1.05, dt=0.1, t_start=0.0, integrator="rk4")
    with pytest.raises(ValueError, match=r"radiation='fast'; accepted"):
        fq.floquet(model, None, period=1.0, dt=0.1, t_start=0.0, radiation="fast")
    with pytest.raises(ValueError, match=r"t_start: -1.0; give a time ≥ 0"):
        fq.floquet(model, None, period=1.0, dt=0.1, t_start=-1.0)
    with pytest.raises(ValueError, match=r"mass_ratio: -1.0; give A∞/m ≥ 0"):
        st.heave_loads(model, -1.0, dt=0.1, n_steps=10)
