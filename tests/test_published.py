"""Published results and the notebooks' stated findings, asserted.

- Seed 001 (Lande-Sudall et al., MFM for M4), §6.4, Fig. 12 discussion: "T = 1 s ... corresponds
  to the device's eigenfrequency". notebooks/m4_study.ipynb states the periods with the free
  surge condensed out (its correction after the layouts): 111 at 1.088, 0.952 and 0.748 s, the
  mode near 1 s at 0.95 s. Asserted here on M4 111 (134's and 132's modes cost a minute each).
- notebooks/quickstart.ipynb: "The elbow damper drains energy; the total energy can only go down."

Not asserted here (too slow for the suite): m4_study's TD–FD table on 134 ("22 of 24 periods
within 1 %", 24 runs of 50 T on the eight-float model) and its power and CWR findings (100 Tp
JONSWAP sweeps); the TD–FD agreement is covered on smaller models by tests/test_water.py.
"""
import numpy as np
import pytest
from conftest import CONFIGS

import mfm

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


@pytest.fixture(scope="module")
def m4_111_periods():
    model = mfm.load(CONFIGS / "m4_111.toml")
    # about q = 0: the equilibrium of 111 is within 5e-5 rad of it (a 1e-5 change of the periods);
    # min |det| on a 10-point grid only (its cost is one A(ω) interpolation a point)
    nat = mfm.natural_frequencies(model, q0=np.zeros(model.n_coordinates),
                                  omega_grid=np.linspace(4.0, 8.5, 10))
    nat = {k: v.values for k, v in nat.items()}     # the labelled Dataset's arrays
    T = 2 * np.pi / nat["eigen"]
    hinge = model.coordinate_index("float3.angle")
    modes = nat["modes"] / np.abs(nat["modes"]).max(axis=0)
    return T, modes, hinge


def test_m4_device_eigenperiod_seed_001(m4_111_periods):
    T, modes, hinge = m4_111_periods
    # the seed's "eigenfrequency at T = 1 s": its regular waves are 0.1 s apart near there, so
    # ±5 %. The seed names no mode shape; with the free surge condensed out, the mode near 1 s
    # (0.952 s) is the one in which the stern hinge moves most (the whole frame pitches with it)
    assert any(abs(t - 1.0) < 0.05 for t in T), T


def test_m4_study_natural_periods_as_stated(m4_111_periods):
    T, modes, hinge = m4_111_periods
    # notebook (corrected): "111: 1.088, 0.952, 0.748 s", stated to 3 decimals (±0.0005 and the
    # 1e-5 of linearising about q = 0 rather than the equilibrium). The clamped-surge values of
    # the first run (1.384, 0.979, 0.754 s) came from the bug test_device_frequency.py guards.
    np.testing.assert_allclose(np.sort(T), [0.748, 0.952, 1.088], atol=6e-4)


def test_quickstart_energy_only_goes_down():
    model = mfm.load(CONFIGS / "double_pendulum.toml")
    ds = mfm.simulate(model, duration=5.0, dt=0.005, q0={"upper.angle": 1.0}, integrator="rk4")
    E = (ds.kinetic_energy + ds.potential_energy).values
    # never up beyond rk4's energy error at dt = 5 ms (1e-9 J a step, where the damper is idle)
    assert np.all(np.diff(E) < 1e-9)
    # and what goes is what the damper absorbs, ∫ c q̇² dt (trapezoid on the 5 ms grid: 1e-4)
    P = ds.pto_power.sum("pto").values
    absorbed = np.sum(0.5 * (P[1:] + P[:-1]) * np.diff(ds.time.values))
    assert absorbed > 1e-3
    assert E[0] - E[-1] == pytest.approx(absorbed, rel=1e-4)


def test_rm3_config_matches_the_published_mass_properties():
    """WEC-Sim's RM3 tutorial (WEC-Sim/WEC-Sim, source/tutorials.rst, "Float/Plate Full Scale
    Properties"): float 727.01 t, CG z 0 → −0.72 m, inertia (20,907,301; 21,306,091; 37,085,481)
    kg m²; plate 878.30 t, CG −21.29 m, inertia (94,419,615; 94,407,091; 28,542,225) kg m²; its
    input file sets mass = 'equilibrium' (ρV). configs/rm3.toml takes ρV from the shipped rm3.out
    instead: within 1 % of the published masses (the plate's WAMIT volume is 0.95 % above them)."""
    import tomllib

    cfg = {b["name"]: b for b in tomllib.loads((CONFIGS / "rm3.toml").read_text())["bodies"]}
    published = {"float": (727.01e3, -0.72, (20_907_301, 21_306_091, 37_085_481)),
                 "spar": (878.30e3, -21.29, (94_419_615, 94_407_091, 28_542_225))}
    for name, (mass, zg, inertia) in published.items():
        assert cfg[name]["mass"] == pytest.approx(mass, rel=0.01)
        assert cfg[name]["com"][2] == pytest.approx(zg, abs=1e-9)
        # the tutorial rounds to 1 kg m²
        np.testing.assert_allclose(cfg[name]["principal_inertia"], inertia, atol=1.0)
