"""simulate_batch with the water above linear potential flow (issue 53): the nonlinear level's
hulls (``[hydro] hydrostatics = "nonlinear"``), drag on the relative flow (``drag_flow =
"relative"``) and the wave drift (``drift = "mean" | "newman"``), each case's water carrying its
own sea's components (mfm.loads.water.build_water_batch).

Checked against the independent route, :func:`mfm.simulate` case by case (build_water's own
tables, wave fields of the sea's own components: no padding, no vmap), with cases of different
heights, periods, phases, ramps, headings (the drift's cylinder; the sphere's database has heading
0 only), seas of 1 and 4–5 components (the shorter padded with zero amplitudes) and still water.
Tolerance: 1e-9 of each output's range over the cases. The two routes do the same arithmetic in
another order (XLA's vmap and the batch's block sums of the tables reorder sums; measured
1e-14–6e-13 of the range over these 2–3 s runs), so 1e-9 leaves room for a platform's other
reduction order and still catches any physics (a padded component that added anything, another
case's sea, a ramp or a Froude–Krylov term missing: each 1e-3 of the range or more).
"""
from __future__ import annotations

import copy
import tomllib

import jax.numpy as jnp
import numpy as np
import pytest
from conftest import CONFIGS

import hydro
import mfm
from mfm.timedomain.rollout import TRACES

pytestmark = [pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning"),
              # the JONSWAP's component beyond the sphere database's grid (_sphere_seas)
              pytest.mark.filterwarnings("ignore:dropped 1 wave component:UserWarning")]

TOL = 1e-9
SPHERE = tomllib.loads((CONFIGS / "sphere.toml").read_text())
RUN = dict(dt=0.05, radiation="state_space")


def _sphere(**hydro_keys):
    """The floating sphere (surge, heave, pitch) with the given [hydro] keys; its hull's panels
    0.25 m (a quarter of the default count's cost per step: this file's runs stay short)."""
    cfg = copy.deepcopy(SPHERE)
    cfg["hydro"].update(hydro_keys)
    if hydro_keys.get("hydrostatics") == "nonlinear":
        cfg["bodies"][0]["hull"] = {"shape": "sphere", "radius": 1.0, "panel_size": 0.25}
    if hydro_keys.get("drag_flow") == "relative":
        cfg["bodies"][0]["hydro"] = {"drag_coefficient": [1.0, 1.0, 0.8],
                                     "drag_area": [3.1, 3.1, 3.1]}
    return mfm.load(cfg, base=CONFIGS)


def _sphere_seas():
    """A regular wave, another of another height, period and phase, a 4-component JONSWAP (the
    regular ones padded to 4; its highest component lies beyond the database's 6 rad/s: no
    diffraction there, its X_FK still taken out, as build_water does) and still water (4
    zero-amplitude components)."""
    return [hydro.Regular(height=0.4, period=4.0),
            hydro.Regular(height=0.8, period=5.0, phase=0.3),
            hydro.Jonswap(hs=0.5, tp=4.5, n_components=4, seed=3), None]


def _against_single_runs(model, seas, ramps, outputs, n_steps=40, lanes=None):
    """simulate_batch of ``seas`` against mfm.simulate of each: q, qd and ``outputs`` within
    TOL of each one's range over the cases. Returns the batch and the largest relative error.
    ``lanes``: the cases advanced together by one vmapped loop (a GPU's default: all of them;
    a CPU's: 1, the cases one after another in one compiled call)."""
    batch = mfm.simulate_batch(model, seas, n_steps=n_steps, ramp=ramps, outputs=outputs,
                               lanes=lanes, **RUN)
    singles = [mfm.simulate(model, sea, duration=n_steps * RUN["dt"], ramp=r,
                            check_stability=False, **RUN) for sea, r in zip(seas, ramps)]
    worst = 0.0
    for name in ("q", "qd") + tuple(outputs):
        scale = max(float(np.ptp(s[name].values)) for s in singles)
        assert scale > 0, name
        for i, single in enumerate(singles):
            err = float(np.abs(batch[name].isel(case=i).values - single[name].values).max())
            assert err <= TOL * scale, (name, i, err / scale)
            worst = max(worst, err / scale)
    return batch, worst


def test_the_nonlinear_level_in_a_batch_is_each_case_s_run():
    """[hydro] hydrostatics = "nonlinear": each case's hulls feel its own sea's wave pressure and
    its tables keep the diffraction (the database's excitation less the hulls' X_FK at its own
    components); q, qd and the recorded hydro_force (its excitation row holds the cut hull's
    Froude–Krylov force) are each case's mfm.simulate to TOL, the cases vmapped together (a GPU's
    form). A second batch of other heights,
    periods and ramps (as many components) runs on the first one's compilation."""
    model = _sphere(hydrostatics="nonlinear")
    seas = _sphere_seas()[:3]       # still water: test_a_padded_component_changes_nothing
    # every case in one vmapped loop: the GPU's form
    batch, worst = _against_single_runs(model, seas, [1.0, 0.5, 1.5], ("hydro_force",), lanes=3)
    assert batch.attrs["hydrostatics"] == "nonlinear"
    assert worst < 1e-11             # measured 4e-14: the runs are the same arithmetic
    before = TRACES["rollout"]
    other = [hydro.Regular(height=0.6, period=3.5), None,
             hydro.Jonswap(hs=0.3, tp=4.0, n_components=4, seed=5)]
    again = mfm.simulate_batch(model, other, n_steps=40, ramp=2.0, outputs=("hydro_force",),
                               lanes=3, **RUN)
    assert TRACES["rollout"] == before
    assert np.isfinite(again.q.values).all() and np.ptp(again.q.values[0, :, 1]) > 0.05


@pytest.mark.parametrize("lanes", [3, 1])
def test_the_held_nonlinear_level_in_a_batch_is_each_case_s_run(lanes):
    """[hydro] nonlinear_dt (the hull pressure sampled every 2 steps, HeldHulls): each case's
    samples carry its own sea's linear Froude–Krylov force (its X_FK at its own components, the
    tables keeping the whole excitation); q, qd and hydro_force are each case's mfm.simulate to
    TOL, the cases vmapped together (the step counter shared: one branch taken) and one after
    another."""
    model = _sphere(hydrostatics="nonlinear", nonlinear_dt=0.1)
    seas = _sphere_seas()
    batch, worst = _against_single_runs(model, seas, [1.0, 0.5, 1.5, 0.0], ("hydro_force",),
                                        lanes=lanes)
    assert batch.attrs["hull_pressure"].startswith("sampled every 2 steps")
    assert worst < 1e-11
    with pytest.raises(ValueError, match=r"hydro.nonlinear_dt: 0.1 s is \[1, 2\] steps"):
        mfm.simulate_batch(model, seas[:2], n_steps=4, dt=[0.05, 0.1], radiation="state_space")


def test_a_padded_component_changes_nothing():
    """A regular sea padded to 4 components (zero amplitudes, a wavenumber of 1 rad/s) in the
    batch's water against build_water's one component: the hulls' hydrostatic and Froude–Krylov
    loads at a heaved, pitched pose, and the relative flow's velocity at the reference point, at
    times on and after the ramp, to 1e-15 of their scale (each padded term is 0 · cos = 0
    exactly; what is left is the sums' order); still water as 4 zero-amplitude components is
    build_water's still water (no components) to the bit."""
    from mfm.loads.assembly import carried_loads_batch
    from mfm.loads.water import build_water
    from mfm.mechanics.kinematics import kinematics
    from mfm.timedomain.setup import stage_offsets

    model = _sphere(hydrostatics="nonlinear", drag_flow="relative")
    seas = _sphere_seas()
    cases = carried_loads_batch(model, seas, dts=np.full(4, 0.05), ramps=np.full(4, 1.0),
                                n_steps=20, radiation="state_space",
                                stage_offsets=stage_offsets("rk4"))
    padded = cases.case(1)[0]
    alone = build_water(model, model.hydro, seas[1], dt=0.05, duration=1.0, ramp=1.0,
                        radiation="state_space")
    assert padded.hulls.wave.amplitude.shape == (4,) and alone.hulls.wave.amplitude.shape == (1,)
    q = jnp.asarray([0.1, 0.3, 0.2])
    kin = kinematics(model, q, jnp.zeros(3))
    geo, ref = alone.geometry, alone.geometry.positions(kin)
    for t in (0.4, 1.7, 3.1):
        for a, b in zip(padded.hulls.loads(geo, kin, t), alone.hulls.loads(geo, kin, t)):
            a, b = np.asarray(a), np.asarray(b)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-15 * np.abs(b).max())
        u_a = np.asarray(padded.flow.velocity(ref, t))
        u_b = np.asarray(alone.flow.velocity(ref, t))
        np.testing.assert_allclose(u_a, u_b, rtol=0, atol=1e-15 * max(np.abs(u_b).max(), 1e-300))
    # still water as four zero-amplitude components: the hydrostatic load of still water and no
    # flow, exactly
    still = cases.case(3)[0]
    calm = build_water(model, model.hydro, None, dt=0.05, duration=1.0, radiation="state_space")
    for a, b in zip(still.hulls.loads(geo, kin, 1.7), calm.hulls.loads(geo, kin, 1.7)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    assert not np.any(np.asarray(still.flow.velocity(ref, 1.7)))


def test_drag_on_the_relative_flow_in_a_batch_is_each_case_s_run():
    """[hydro] drag_flow = "relative": each case's drag acts on the velocity relative to its own
    sea's flow (a regular wave padded to 4 components, a 4-component JONSWAP); q, qd and
    hydro_force (its drag row) are each case's mfm.simulate to TOL."""
    model = _sphere(drag_flow="relative")
    seas = _sphere_seas()
    # still water (padded) against build_water's: test_a_padded_component_changes_nothing
    batch, worst = _against_single_runs(model, [seas[1], seas[2]], [0.5, 1.5], ("hydro_force",),
                                        lanes=2)
    assert batch.attrs["drag_flow"] == "relative"
    assert worst < 1e-11


@pytest.mark.filterwarnings("ignore::hydro.waves.SeaStateWarning")     # the band cut to the table's
@pytest.mark.parametrize("mode", ["mean", "newman"])
def test_wave_drift_in_a_batch_is_each_case_s_run(mode):
    """[hydro] drift = "mean" | "newman" on the moored cylinder (tests/test_drift_53.py): a head
    sea, a beam sea (heading π/2: no surge drift), a 5-component JONSWAP heading 0.4 rad and still
    water; the recorded drift_force, hydro_force, q and qd are each case's mfm.simulate to TOL,
    and the head sea's drift is D a² after its ramp."""
    from test_drift_53 import _drift_db, _moored_cylinder

    model = _moored_cylinder(mode)
    seas = [hydro.Regular(height=0.4, period=2 * np.pi / 2.5),
            hydro.Regular(height=0.6, period=2 * np.pi / 2.8, heading=np.pi / 2, phase=0.3),
            hydro.Jonswap(hs=0.3, tp=2 * np.pi / 2.6, omega_range=(2.05, 3.45), n_components=5,
                          seed=2, heading=0.4), None]
    batch, worst = _against_single_runs(model, seas, [1.0, 0.5, 2.0, 0.0],
                                        ("drift_force", "hydro_force"), n_steps=60)
    assert worst < 1e-11
    assert batch.drift_force.attrs["drift"] == mode
    D = float(_drift_db()["mean_drift"].sel(omega=2.5, wave_direction=0.0,
                                            influenced_dof="cylinder__Surge"))
    late = batch.time.values[0] >= 1.0
    np.testing.assert_allclose(batch.drift_force.values[0, late, 0], D * 0.2**2, rtol=1e-12)
    assert not np.any(batch.drift_force.values[3])


def test_vary_loads_names_seas_of_different_counts():
    """With vary_loads each case's loads are made alone (build_water: no padding): a relative
    drag's flow of 1 and 4 components cannot stack, and the error names the leaf, its shapes and
    what to do (without vary_loads the same seas run: the test above)."""
    model = _sphere(drag_flow="relative")
    seas = _sphere_seas()
    with pytest.raises(ValueError, match=r"flow\.wave\.amplitude differ in shape \(\[\(1,\), "
                                         r"\(4,\)\]\).*leave vary_loads out"):
        mfm.simulate_batch(model, [seas[0], seas[2]], n_steps=10, threads=1,
                           vary_loads=lambda i, loads: loads, **RUN)
