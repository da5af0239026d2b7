"""The jax contract: static topology, dynamic parameters (no recompiles), vmap and grad."""
import copy

import jax
import jax.numpy as jnp
import numpy as np
from conftest import CONFIGS

import hydro
from hydro.prepare import HydroSpec
import mfm
from mfm.timedomain.rollout import TRACES

MODEL = mfm.load(CONFIGS / "m4_111.toml", hydro=False)  # mechanics in vacuum
Q0 = np.array([0.0, 0.0, 0.05, -0.1])
QD0 = np.array([0.0, 0.0, 0.0, 0.8])  # a hinge rate, so that the damper works
DT, N = 0.005, 200


def final_angle(model, integrator="rk4"):
    out = mfm.rollout(model, Q0, QD0, dt=DT, n_steps=N, integrator=integrator)
    return out[1][-1, 3]


def test_changing_parameters_does_not_recompile():
    final_angle(MODEL)
    before = TRACES["rollout"]
    a = final_angle(MODEL.set_damping("float3.angle", 9.0))
    b = final_angle(MODEL.set_mass("float3", 20.0))
    c = final_angle(MODEL.replace(gravity=9.7))
    assert TRACES["rollout"] == before, "a parameter change recompiled the rollout"
    assert len({float(a), float(b), float(c), float(final_angle(MODEL))}) == 4  # they did change it
    # and the front door too: simulate with another mass reuses both compiled functions
    mfm.simulate(MODEL, duration=N * DT, dt=DT, q0=Q0)
    before = dict(TRACES)
    mfm.simulate(MODEL.set_mass("float1", 3.0), duration=N * DT, dt=DT, q0=Q0)
    assert dict(TRACES) == before


def test_vmap_over_damping_gives_batched_results():
    dampings = jnp.array([0.0, 3.0, 6.0, 12.0])
    k = MODEL.coordinate_index("float3.angle")
    batched = jax.vmap(lambda d: final_angle(MODEL.replace(damping=MODEL.damping.at[k].set(d))))(dampings)
    single = [final_angle(MODEL.set_damping("float3.angle", float(d))) for d in dampings]
    # the same arithmetic batched: equal to round-off
    np.testing.assert_allclose(batched, single, rtol=1e-12, atol=1e-14)
    assert len(set(np.round(np.asarray(batched), 12))) == 4


def test_gradient_wrt_pto_damping_matches_finite_difference():
    k = MODEL.coordinate_index("float3.angle")

    def f(d):
        return final_angle(MODEL.replace(damping=MODEL.damping.at[k].set(d)))

    d0 = 6.0
    g = jax.grad(f)(d0)
    h = 1e-4  # central difference: truncation O(h²) ~ 1e-9 relative, round-off ~ 1e-16/h
    fd = (f(d0 + h) - f(d0 - h)) / (2 * h)
    assert abs(g) > 1e-6
    np.testing.assert_allclose(g, fd, rtol=1e-6)
    # the implicit scheme is differentiable too
    g_nm = jax.grad(lambda d: final_angle(MODEL.replace(damping=MODEL.damping.at[k].set(d)), "newmark"))(d0)
    fd_nm = (final_angle(MODEL.set_damping("float3.angle", d0 + h), "newmark")
             - final_angle(MODEL.set_damping("float3.angle", d0 - h), "newmark")) / (2 * h)
    np.testing.assert_allclose(g_nm, fd_nm, rtol=1e-6)


def test_the_same_config_loaded_twice_compiles_once():
    # a second load of the config reuses the first one's compilation (the solvers are handed the
    # model without its HydroSpec: test_models_differing_only_in_numbers_share_one_compilation);
    # the HydroSpec itself compares by content (the fit cache and the batch's checks use it)
    import hydro

    a, b = mfm.load(CONFIGS / "sphere.toml"), mfm.load(CONFIGS / "sphere.toml")
    assert a.hydro is not b.hydro and a.hydro == b.hydro and hash(a.hydro) == hash(b.hydro)
    sea = hydro.Regular(height=0.2, period=3.0)
    ra = mfm.simulate(a, sea, duration=1.0, dt=0.05)
    before = dict(TRACES)
    rb = mfm.simulate(b, sea, duration=1.0, dt=0.05)
    assert dict(TRACES) == before, "a second load of the same config compiled the rollout again"
    np.testing.assert_array_equal(ra.q.values, rb.q.values)
    # any difference in the data makes another spec: other drag, or an attribute set after the
    # spec was made (its hash is not frozen at construction)
    spec = a.hydro
    other = HydroSpec(spec.db, spec.body_index, spec.config_names, spec.ref0 - spec.d_ref,
                      np.array([[0.0, 0.0, 1.0]]))
    assert other != spec
    changed = copy.copy(spec)
    assert changed == spec
    changed.C_wp = 0.5 * changed.C_wp
    assert changed != spec and hash(changed) != hash(spec)
    salt = copy.copy(spec)
    salt.db = spec.db.assign_attrs(rho=1025.0)
    salt._cache = {}
    assert salt != spec
    # an array attribute is hashed by its bytes, not its repr (which elides a large array's middle)
    big = np.zeros(5000)
    other_big = big.copy()
    other_big[2500] = 1.0
    assert repr(big) == repr(other_big)
    a, b = copy.copy(spec), copy.copy(spec)
    a.db, b.db = spec.db.assign_attrs(table=big), spec.db.assign_attrs(table=other_big)
    a._cache, b._cache = {}, {}
    assert a != b


def test_models_differing_only_in_numbers_share_one_compilation():
    # issue 34: a model's name, config path and hash, its HydroSpec (compared by its database's
    # content), a fit's report are static fields, so part of jit's key: a model with other numbers
    # (here the water-plane stiffness halved, another name and path) compiled everything again.
    # The solvers are handed the model and loads without them (loads.assembly.compile_view):
    # counted, not timed, no new compilation; and the reused program gives the bits of a fresh one
    import copy
    import dataclasses

    from mfm.frequency import response, rest

    a = mfm.load(CONFIGS / "rm3.toml")
    spec = copy.copy(a.hydro)
    spec.C_wp = 0.5 * spec.C_wp
    b = dataclasses.replace(a, hydro=spec, name="rm3, softer", source="elsewhere.toml",
                            source_sha256="0" * 64)
    assert b.hydro != a.hydro and b.name != a.name
    om = [0.6, 0.9]
    sea = hydro.Regular(height=1.0, period=8.0)
    fa = mfm.frequency_response(a, om)
    sa = mfm.simulate(a, sea, duration=2.0, dt=0.1)
    # the run's programs, however simulate makes them (one program, or a pipeline's two)
    counts = (rest._static_jet._cache_size(), response._reaction_derivatives._cache_size(),
              dict(TRACES))
    fb = mfm.frequency_response(b, om)
    sb = mfm.simulate(b, sea, duration=2.0, dt=0.1)
    assert (rest._static_jet._cache_size(), response._reaction_derivatives._cache_size(),
            dict(TRACES)) == counts, "a numbers-only variant compiled again"
    assert not np.array_equal(fa.rao.values, fb.rao.values)         # other numbers, other RAOs
    assert not np.array_equal(sa.q.values, sb.q.values)
    assert fb.attrs["model"] == "rm3, softer"                          # the labels are the model's
    jax.clear_caches()
    fresh_f = mfm.frequency_response(b, om)
    fresh_s = mfm.simulate(b, sea, duration=2.0, dt=0.1)
    for new, old in ((fresh_f, fb), (fresh_s, sb)):
        for v in new.data_vars:
            assert np.array_equal(new[v].values, old[v].values, equal_nan=True), v
