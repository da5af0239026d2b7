"""hydro.seabatch.components_many: many seas discretised together give each sea's own components
(the same draws from its seed, the same arithmetic elementwise: equal to the last bit on these
seas; the test allows 4 ulp where a vectorised libm might round otherwise), the same warnings and
the same errors."""
import math
import warnings

import numpy as np
import pytest

from hydro.seabatch import _band_fractions, components_many
from hydro.waves import Jonswap, PiersonMoskowitz, Regular, SeaStateWarning, Spreading


def _seas(n=40, seed=3):
    rng = np.random.default_rng(seed)
    seas = []
    for i in range(n):
        hs, tp = rng.uniform(0.5, 4.0), rng.uniform(5.0, 14.0)
        seas.append([
            Jonswap(hs=hs, tp=tp, gamma=rng.uniform(1.0, 7.0), seed=i),
            PiersonMoskowitz(hs=hs, tp=tp, seed=i, n_components=int(rng.integers(5, 300))),
            Jonswap(hs=hs, tp=tp, seed=i, normalisation="dnv", spreading=Spreading(s=10.0)),
            Jonswap(hs=hs, tp=tp, seed=i, repeat_period=300.0, omega_range=(0.2, 2.0)),
            Regular(height=hs, period=tp),
            None,
        ][i % 6])
    return seas


@pytest.mark.parametrize("depth", [math.inf, 40.0])
def test_components_many_equal_each_seas_own(depth):
    seas = _seas()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SeaStateWarning)
        one = [None if s is None else s.components(water_depth=depth) for s in seas]
        many = components_many(seas, water_depth=depth)
    assert len(many) == len(seas)
    for s, a, b in zip(seas, one, many):
        if s is None:
            assert b is None
            continue
        assert (b.water_depth, b.g, b.repeat_period) == (a.water_depth, a.g, a.repeat_period)
        for name in ("omega", "amplitude", "phase", "heading", "wavenumber"):
            x, y = getattr(a, name), getattr(b, name)
            assert y.shape == x.shape and not y.flags.writeable
            np.testing.assert_allclose(y, x, rtol=4 * np.finfo(float).eps, atol=0, err_msg=name)


def test_band_fractions_match_each_seas_quadrature():
    """The shared tables against each sea's own 4,001-point quadrature: within 1e-6 (that
    quadrature's own error against scipy's quad), for whole and cut bands, γ 1–7, both
    normalisations."""
    seas = [s for s in _seas() if isinstance(s, (Jonswap, PiersonMoskowitz))]
    seas += [Jonswap(hs=1.0, tp=8.0, gamma=g, omega_range=(0.2 + 0.05 * i, 0.6 + 0.1 * i),
                     normalisation=("exact", "dnv")[i % 2]) for i, g in
             enumerate(np.linspace(1.0, 7.0, 20))]
    own = np.array([s.band_energy_fraction() for s in seas])
    assert own.min() < 0.1 and own.max() > 0.99          # the cases span cut and whole bands
    np.testing.assert_allclose(_band_fractions(seas), own, rtol=0, atol=1e-6)


def test_components_many_warns_and_refuses_as_each_sea():
    cut = [Jonswap(hs=1.0, tp=8.0, omega_range=(0.2 + 0.05 * i, 0.6 + 0.1 * i), seed=i)
           for i in range(12)]
    with warnings.catch_warnings(record=True) as own:
        warnings.simplefilter("always")
        [s.components() for s in cut]
    with warnings.catch_warnings(record=True) as many:
        warnings.simplefilter("always")
        components_many(cut)
    assert len(own) > 3
    assert [str(w.message) for w in many] == [str(w.message) for w in own]
    with pytest.raises(ValueError, match="hs 30 m at a period of 3 s is past breaking"):
        components_many([Jonswap(hs=1.0, tp=8.0), Jonswap(hs=30.0, tp=3.0)])
