"""The scheme of seed 001 §5 (A∞ ξ̈ on the right-hand side, iterated in Beeman's corrector to 1 %)
against ours (A∞ in M*), and where the seed's iteration cannot work."""

import pytest
from conftest import CONFIGS

import hydro
import mfm

# per module, not session-wide: a database warning is expected here (the shipped BEM data)
pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


def test_seed_scheme_matches_ours_on_m4_111():
    # JONSWAP Hs 0.04 m, Tp 1 s, γ 1 (a validation sea of seed 001 Table 2), dt = Tp/200, 40 Tp.
    # Both schemes solve the same equations; the seed's stops its corrector at a 1 % change of
    # the acceleration, so the statistics agree to well within the 1 % asked (measured 0.015 %).
    m = mfm.load(CONFIGS / "m4_111.toml")
    sea = hydro.Jonswap(hs=0.04, tp=1.0, gamma=1.0, seed=2, omega_range=(1.0, 25.0))
    kw = dict(duration=40.0, dt=1.0 / 200, ramp=5.0, radiation="state_space")
    ours = mfm.simulate(m, sea, integrator="rk4", **kw)
    seed = mfm.simulate(m, sea, integrator="beeman", added_mass="rhs", **kw)
    half = slice(20.0, None)
    for ds in (ours, seed):
        ds["theta"] = ds.q.sel(coordinate="float3.angle")
    th_o, th_s = (float(ds.theta.sel(time=half).std()) for ds in (ours, seed))
    p_o, p_s = (float(ds.pto_power.sel(time=half).mean()) for ds in (ours, seed))
    assert abs(th_s / th_o - 1) < 0.01 and abs(p_s / p_o - 1) < 0.01, (th_o, th_s, p_o, p_s)
    # the iteration counts are reported per step (the seed: about 10, up to 12)
    it = seed.iterations.values[1:]
    assert 1 <= it.mean() < 20 and it.max() <= 50
    assert ours.iterations.values.max() == 0


def test_seed_scheme_needs_beeman_and_fails_loudly_where_added_mass_dominates():
    m = mfm.load(CONFIGS / "rm3.toml")
    sea = hydro.Regular(height=1.0, period=8.0)
    with pytest.raises(ValueError, match="integrator='beeman'"):
        mfm.simulate(m, sea, duration=8.0, dt=0.08, added_mass="rhs")
    # RM3: A∞ exceeds the structural mass (spectral radius of M*⁻¹ Hᵀ A∞ H ≈ 10): the fixed-point
    # iteration diverges at once; the error says why and what to use instead
    with pytest.raises(mfm.SimulationError, match=r"spectral radius of M\*⁻¹ Hᵀ A∞ H is [0-9.]+ ≥ 1"):
        mfm.simulate(m, sea, duration=8.0, dt=0.08, ramp=4.0, integrator="beeman", added_mass="rhs")
