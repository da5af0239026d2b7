"""A batch's cases prepared together (issue 34): ``simulate_batch`` makes what its cases share once
and what differs vectorised — the radiation for every distinct time step at once, the wave
components placed on the excitation table in one call, the interpolation of X and the wave tables
on the device (:func:`mfm.loads.water.build_water_batch`, :class:`mfm.loads.water.WaveSum`).

Checked against the independent route, each case's loads made alone by :func:`build_water` (the
path ``simulate_batch`` takes with ``vary_loads``): the tables to their round-off bound, the
radiation arrays to round-off, the runs to what round-off moves in them; and one compilation for
batches that differ only in numbers (a counter, not a timer).
"""
import dataclasses

import numpy as np
import pytest

import hydro
import mfm
from conftest import CONFIGS
from mfm.loads.assembly import carried_loads, carried_loads_batch
from mfm.loads.radiation import ExactStateSpace, StateSpace, strategy_many
from mfm.timedomain.rollout import TRACES
from mfm.timedomain.setup import stage_offsets

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

EPS = np.finfo(float).eps
KW = dict(integrator="verlet", radiation="state_space_exact")


@pytest.fixture(scope="module")
def m4():
    return mfm.load(CONFIGS / "m4_134.toml")


def _cases():
    """Seas of several kinds and counts of components (JONSWAP, spread, regular, still water),
    time steps and ramps of their own."""
    spread = hydro.Jonswap(hs=0.03, tp=1.3, gamma=2.0, seed=4, omega_range=(1.0, 25.0),
                           heading=0.3, spreading=hydro.Spreading(s=100), n_components=150)
    seas = [hydro.Jonswap(hs=0.04, tp=1.0, gamma=3.3, seed=1, omega_range=(1.0, 25.0)),
            spread, hydro.Regular(height=0.03, period=1.1), None,
            hydro.Jonswap(hs=0.02, tp=1.6, gamma=1.0, seed=9, omega_range=(1.0, 25.0))]
    dts = np.array([1.0, 1.3, 1.1, 1.0, 1.6]) / 200
    ramps = np.array([1.0, 0.0, 2.0, 1.0, 0.5])
    return seas, dts, ramps


@pytest.mark.parametrize("n_steps", [120, 1100])
def test_each_case_gets_the_water_build_water_makes_alone(m4, n_steps):
    """Case b's water (its tables made as a batch makes them, for a short grid and for one of the
    block form's many blocks) against build_water's for seas[b], dts[b], ramps[b]:
    the radiation arrays to 1e-13 of their scale (the same elementwise formulas, the block sums
    in another order), the tables to their round-off bound: a value of Re Σ_j c_j e^{−iω_j t}
    (n_c terms, each made of a few roundings) is off by at most ~10 ε Σ_j |c_j| per column,
    whichever order the sums take."""
    from mfm.runner.batch import _tables

    seas, dts, ramps = _cases()
    offs = stage_offsets("verlet")
    cases = carried_loads_batch(m4, seas, dts=dts, ramps=ramps, n_steps=n_steps,
                                radiation="state_space_exact", stage_offsets=offs)
    exc, eta = _tables(cases.waves, cases.polar, np.arange(len(seas)))
    for b, (sea, dt, ramp) in enumerate(zip(seas, dts, ramps)):
        alone = carried_loads(m4, sea, dt=dt, duration=n_steps * dt, ramp=ramp,
                              radiation="state_space_exact", stage_offsets=offs)[0]
        one = cases.case(b)[0]
        for name in ("E", "G", "H", "CE", "RM", "CG", "CH", "dt", "p", "C", "A_inf"):
            a, r = np.asarray(getattr(one.rad, name)), np.asarray(getattr(alone.rad, name))
            np.testing.assert_allclose(a, r, rtol=0, atol=1e-13 * max(np.abs(r).max(), 1e-300),
                                       err_msg=name)
        assert float(one.exc_step) == float(alone.exc_step)
        if sea is None:
            assert not np.any(exc[b]) and not np.any(eta[b])
            continue
        c = sea.components(water_depth=m4.hydro.water_depth, g=m4.hydro.g)
        X = hydro.excitation.excitation_coefficients(m4.hydro.database(), c)
        bound = 10 * EPS * np.abs(c.complex_amplitude[:, None] * X).sum(0)
        assert np.all(np.abs(np.asarray(exc[b]) - np.asarray(alone.exc_values)) <= bound + 1e-300)
        assert np.abs(np.asarray(eta[b]) - np.asarray(alone.eta_values)).max() \
            <= 10 * EPS * c.amplitude.sum()
        # the host's copy of the case (its tables by build_water's numpy route) is build_water's
        np.testing.assert_array_equal(one.exc_values, alone.exc_values)


def test_radiation_for_many_steps_equals_one_step_at_a_time(m4):
    """The exact state space for D time steps at once (vectorised over dt) against D single
    builds: the same numbers (elementwise formulas), and only what follows dt has a case axis."""
    spec = m4.hydro
    offs = stage_offsets("rk4")
    dts = np.array([0.004, 0.007, 0.004, 0.009])
    rad, batched = strategy_many(spec, "state_space_exact", dts, stage_offsets=offs)
    assert batched.E and batched.CE and batched.dt and not batched.p and not batched.A_inf \
        and not batched.RM
    ss = StateSpace.build(spec, None)
    for b, dt in enumerate(dts):
        one = ExactStateSpace.from_state_space(ss, dt, offs)
        for name in ("E", "G", "H", "CE", "CG", "CH", "dt"):
            np.testing.assert_array_equal(np.asarray(getattr(rad, name))[b],
                                          np.asarray(getattr(one, name)), err_msg=name)
        np.testing.assert_array_equal(rad.RM, one.RM)   # the output map: one for every dt
    # the strategies that do not follow dt are shared whole
    _, shared = strategy_many(spec, "state_space", dts, stage_offsets=offs)
    assert not any(np.asarray(x).any() for x in __import__("jax").tree_util.tree_leaves(shared))


def test_batch_equals_its_cases_made_one_by_one(m4):
    """The vectorised preparation against the per-case one (``vary_loads`` takes that path) and
    against one ``simulate`` per case: equal to what round-off moves in these runs (M4 134's
    floats have no surge restoring: a few ulps of the forcing move q by about 1e-16 m here; the
    tolerance is 10 × that change, measured in the test, or 1e-12 of the scale)."""
    seas, dts, ramps = _cases()
    kw = dict(dt=dts, ramp=ramps, n_steps=300, **KW)
    fast = mfm.simulate_batch(m4, seas, **kw)
    slow = mfm.simulate_batch(m4, seas, vary_loads=lambda i, loads: loads, **kw)

    def nudged(i, loads):
        w = loads[0]
        return (dataclasses.replace(w, exc_values=w.exc_values * (1 + 2.0**-50)),) + loads[1:]

    floor = mfm.simulate_batch(m4, seas, vary_loads=nudged, **kw)
    for name in slow.data_vars:
        a, b, c = (np.asarray(d[name]) for d in (fast, slow, floor))
        tol = max(1e-12 * np.abs(b).max(), 10 * np.abs(c - b).max())
        assert np.abs(a - b).max() <= tol, (name, np.abs(a - b).max(), tol)
    assert fast.attrs.keys() == slow.attrs.keys()
    assert {k: v for k, v in fast.attrs.items() if k != "created"} == \
        {k: v for k, v in slow.attrs.items() if k != "created"}
    one = mfm.simulate(m4, seas[1], duration=300 * dts[1], dt=dts[1], ramp=ramps[1],
                       **{k: v for k, v in KW.items()})
    np.testing.assert_allclose(fast.q.values[1], one.q.values, rtol=0,
                               atol=max(1e-12 * np.abs(one.q.values).max(),
                                        10 * np.abs(floor.q.values[1] - slow.q.values[1]).max()))


def test_a_batch_without_outputs_makes_the_moved_dofs_excitation_alone(m4):
    """With nothing of the water recorded the time step reads only the moved dofs' excitation
    (Water._forces): a batch makes those columns alone (half of M4 134's 48) and its runs are the
    ones of full tables (build_water's, the per-case route) to what round-off moves in them (10 ×
    the change of a 4-ulp nudge of the forcing, as above); asked for the water's forces, it makes
    every column."""
    seas, dts, ramps = _cases()
    kw = dict(dt=dts[:2], ramp=ramps[:2], n_steps=1100, **KW)
    lean = mfm.simulate_batch(m4, seas[:2], **kw)
    full = mfm.simulate_batch(m4, seas[:2], vary_loads=lambda i, loads: loads, **kw)

    def nudged(i, loads):
        w = loads[0]
        return (dataclasses.replace(w, exc_values=w.exc_values * (1 + 2.0**-50)),) + loads[1:]

    floor = np.abs(mfm.simulate_batch(m4, seas[:2], vary_loads=nudged, **kw).q.values
                   - full.q.values).max()
    assert np.abs(lean.q.values - full.q.values).max() <= max(10 * floor,
                                                              1e-12 * np.abs(full.q.values).max())
    forces = mfm.simulate_batch(m4, seas[:2], outputs=("hydro_force",), **kw)
    one = mfm.simulate(m4, seas[0], duration=1100 * dts[0], dt=dts[0], ramp=ramps[0],
                       **KW)
    np.testing.assert_allclose(forces.hydro_force.values[0], one.hydro_force.values, rtol=0,
                               atol=1e-9 * np.abs(one.hydro_force.values).max())


def test_batches_differing_in_numbers_compile_once(m4):
    """Other seas, other time steps (one for every case, or one each), other ramps: the same
    compiled rollout (the structure of what the compiled call is handed does not follow the
    values)."""
    seas, dts, ramps = _cases()
    live = [s for s in seas if s is not None]
    mfm.simulate_batch(m4, live[:2], dt=dts[:2], ramp=ramps[:2], n_steps=40, **KW)
    before = TRACES["rollout"]
    mfm.simulate_batch(m4, live[2:4], dt=0.006, ramp=0.0, n_steps=40, **KW)
    mfm.simulate_batch(m4, [live[0], None], dt=[0.004, 0.008], ramp=1.0, n_steps=40, **KW)
    assert TRACES["rollout"] == before


def test_a_heading_outside_the_database_is_named_for_its_case(m4):
    """A bad sea among many: the error names its heading and component, as a single run's does."""
    seas, dts, _ = _cases()
    bad = hydro.Regular(height=0.02, period=1.2, heading=1.9)       # the database stops at 1.57
    with pytest.raises(ValueError, match="wave heading 1.9 rad"):
        mfm.simulate_batch(m4, [seas[0], bad], dt=0.005, n_steps=10, **KW)
