"""Issue 54 item 12: two results the suite let through with a planted bug, each given a route that
does not go through the code under test, and each test shows, inside itself, that the planted bug
lands outside its tolerance (so neither can pass vacuously).

(a) A mooring table with NON-SQUARE steps. Every table elsewhere in the suite has hx = hz, where
    a spline interpolated with its two spacings swapped is the same spline. Here a line of the
    Wu & Yuan geometry (tests/test_catenary.py) gets ``table_step = [0.5, 2.0]`` m over
    ``table_extent = [12, 10]`` m (49 × 11 nodes), and the time loop's own path
    (:meth:`CatenaryLines.tensions` from fairlead positions in random azimuths: spans, table
    origin and steps from :meth:`CatenaryLines.from_parsed`, :func:`mfm.loads.catenary.interpolate`)
    is compared at 200 random off-grid points with MoorPy's own solve there: a ``moorpy.System``
    with one ``Line`` between two points, ``Line.staticSolve`` (tol 1e-10 m), (H, V) = −fB.

    Tolerance from the spacing: the error of interpolating between nodes h apart is at most
    h²/8 · max|f''| per axis (the linear interpolant's bound; the table's cubic spline does far
    better), so tol = hx²/8 · max|∂²F/∂x²| + hz²/8 · max|∂²F/∂z²|, the curvatures measured here by
    central second differences of MoorPy (δ = 0.25 m) on a 25 × 11 grid over the table, max over H
    and V. Measured: max|F_xx| 3.84e4 N/m², max|F_zz| 995 N/m² → tol 1.70e3 N; the table's actual
    error 1.4 N (7.6e-7 of the local tension: the cubic spline is ~1,000 × inside the linear
    bound). The planted bugs, built from the same table: the spacings swapped where the table is
    read (step = [hz, hx], as interpolate's u, w or from_parsed's step swapped: most points fall
    outside the table, NaN, the rest are off by up to ~8e5 N) and the spacings swapped in the
    nodal derivatives' scaling (make_table's hz ∂f/∂x, hx ∂f/∂z: median 3.0e3 N, max 3.2e4 N =
    19 × tol, 72 % of the points past it). Each is asserted past 10 × tol at its worst point and
    past tol at its median. All three source mutants (interpolate, from_parsed, make_table) were
    also planted one at a time outside the suite: this test fails on each.

(b) The spectral level's variance (``mfm.spectral_response(model, sea).q_rms``, σ_q² =
    Σ_j ½ a_j² |x̂_j|²) on configs/sphere.toml in a JONSWAP sea (Hs 0.1 m, Tp 3 s, 42 components
    on a 64 s repeat period) by two routes:

    - the closed form computed here from mfm.frequency_response's RAOs at the sea's own
      component frequencies and hydro's ``sea.components()`` amplitudes a_j: the same numbers
      summed another way, rtol 1e-9 (round-off of 42 terms);
    - the sample variance of the heave of ``mfm.simulate`` (time domain, convolution radiation,
      RK4, dt 0.05 s), which never forms an RAO or a ½: the last of three repeat periods. The
      sampling error of this finite record is zero: the components are distinct multiples of
      2π/64 s and the 1,280 samples of one whole period resolve the highest (51 cycles per
      period) with room, so every cross term averages to 0 exactly (Parseval). What remains is
      the time domain's departure from the linear frequency-domain model: the start-up transient
      left after two periods (heave std of period 2 against period 3: 2.2e-4), the convolution
      kernel's truncation and discretisation. Measured: 2.3e-3 of the variance; asked 2e-2.
      Surge (no restoring: it drifts from rest) and pitch (lightly damped, its transient 1.4e-2
      of the std after two periods) are left to the closed form.

    Without the ½ the variance doubles (q_rms × √2): 100 % against tolerances of 1e-9 and 2e-2
    (the mutant of spectral._sweep's q_rms line, planted outside the suite, fails both routes).

Runtime: the file ~16 s wall on 2 cores ((a) ~2 s with its 539-node table, (b) ~11 s, most of
it the simulate's compile).
"""
from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import CONFIGS

import hydro
import mfm
from mfm.io.config import parse_config
from mfm.loads import CatenaryLines

mp = pytest.importorskip("moorpy")

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


# ================================================================ (a) a non-square mooring table
W = 303.0 * 9.81                       # N/m in water (Wu & Yuan's chain)
L, EA = 800.0, 1.243e9
X0, Z0 = 830.0 - 54.5, 15.0 + 60.0     # rest span and height
DEPTH = 60.0
EXTENT = (12.0, 10.0)                  # m: half-widths in span x and height z
STEP = (0.5, 2.0)                      # m: hx ≠ hz (the point of the test)


class MoorPyLine:
    """MoorPy's own solve of one line: a System with the anchor on the seabed and the fairlead a
    fixed point moved to (x, 0, z − depth); (H, V) = −fB (the line's force on its end B)."""

    def __init__(self):
        ms = mp.System(depth=DEPTH)
        ms.lineTypes["chain"] = dict(name="chain", d_vol=0.0, w=W, m=303.0, EA=EA,
                                     material="chain", d_nom=0.12)
        ms.addPoint(1, [0.0, 0.0, -DEPTH])
        ms.addPoint(1, [X0, 0.0, Z0 - DEPTH])
        ms.addLine(L, "chain", pointA=1, pointB=2)
        ms.initialize()
        self.line, self.fairlead = ms.lineList[0], ms.pointList[1]

    def __call__(self, x, z):
        self.fairlead.setPosition([float(x), 0.0, float(z) - DEPTH])
        self.line.staticSolve(tol=1e-10)
        return np.array([-self.line.fB[0], -self.line.fB[2]])


def _table_tensions(lines, p):
    """(H, V) (N, 2) of the one line at fairlead positions p (N, 3): the time loop's path."""
    f = jax.jit(jax.vmap(lambda ld, r: jnp.stack(ld.tensions(r[None])[:2], axis=1)[0],
                         in_axes=(None, 0)))
    return np.asarray(f(lines, jnp.asarray(p)))


def test_non_square_mooring_table_against_moorpys_own_solve():
    model = mfm.compile_tree(parse_config({"bodies": [{
        "name": "hull", "mass": 1e6, "com": [0.0, 0.0, 0.0], "principal_inertia": [1e8] * 3,
        "joint": {"type": "free", "dofs": ["surge", "sway", "heave"]}}]})[1])
    anchor = np.array([-X0, 0.0, 15.0 - Z0])
    lines = CatenaryLines.create(model, [{
        "name": "L1", "body": "hull", "fairlead": [0.0, 0.0, 15.0], "anchor": list(anchor),
        "length": L, "weight": W, "EA": EA, "table_extent": list(EXTENT), "table_step": list(STEP)}])
    hx, hz = (float(v) for v in np.asarray(lines.step[0]))
    nx, nz = (int(v) for v in np.asarray(lines.n[0]))
    # the table really is non-square, in spacing and in node count (else a swap is invisible)
    assert (hx, hz) == pytest.approx(STEP, rel=1e-12) and (nx, nz) == (49, 11)
    moorpy = MoorPyLine()

    # off-grid points over the whole table, the fairlead in random azimuths about the anchor
    rng = np.random.default_rng(54)
    N = 200
    x = X0 + rng.uniform(-EXTENT[0], EXTENT[0], N)
    z = Z0 + rng.uniform(-EXTENT[1], EXTENT[1], N)
    az = rng.uniform(0.0, 2 * math.pi, N)
    p = anchor + np.stack([x * np.cos(az), x * np.sin(az), z], axis=1)
    ref = np.array([moorpy(a, b) for a, b in zip(x, z)])

    # the tolerance from the spacing: h²/8 · max|f''| per axis, f'' measured on MoorPy
    d = 0.25
    cxx = czz = 0.0
    for a in X0 + np.linspace(-EXTENT[0], EXTENT[0], 25):
        for b in Z0 + np.linspace(-EXTENT[1], EXTENT[1], 11):
            f0 = moorpy(a, b)
            cxx = max(cxx, np.max(np.abs(moorpy(a + d, b) - 2 * f0 + moorpy(a - d, b))) / d**2)
            czz = max(czz, np.max(np.abs(moorpy(a, b + d) - 2 * f0 + moorpy(a, b - d))) / d**2)
    tol = hx**2 / 8 * cxx + hz**2 / 8 * czz

    def worst(table_lines):
        err = np.max(np.abs(_table_tensions(table_lines, p) - ref), axis=1)
        return np.where(np.isfinite(err), err, np.inf)       # a point read outside: NaN → inf

    err = worst(lines)
    print(f"non-square table ({nx} × {nz}, steps {hx} × {hz} m): max|F_xx| {cxx:.3g}, "
          f"max|F_zz| {czz:.3g} N/m² → tol {tol:.3g} N; error max {err.max():.3g} N "
          f"({np.max(err / np.hypot(*ref.T)):.2g} of the local tension)")
    assert err.max() <= tol

    # the planted bugs, from the same table: (1) the spacings swapped where the table is read
    # (interpolate's u, w or from_parsed's step); (2) swapped in the nodal derivatives' scaling
    # (make_table's hx ∂f/∂x, hz ∂f/∂z)
    swapped_read = dataclasses.replace(lines, step=lines.step[:, ::-1])
    c = np.array(lines.coef)
    c[..., 1, :] *= hz / hx
    c[..., 2, :] *= hx / hz
    swapped_scale = dataclasses.replace(lines, coef=jnp.asarray(c))
    for name, bad in (("read", swapped_read), ("derivative scaling", swapped_scale)):
        e = worst(bad)
        print(f"spacings swapped ({name}): median {np.median(e):.3g} N, "
              f"max {e.max():.3g} N, {np.mean(e > tol):.0%} of points past tol")
        assert e.max() > 10 * tol, name
        assert np.median(e) > tol, name


# ================================================================ (b) the spectral level's variance
T_R, DT = 64.0, 0.05


def test_spectral_variance_against_closed_form_and_time_domain_sample_variance():
    model = mfm.load(CONFIGS / "sphere.toml")
    sea = hydro.Jonswap(hs=0.1, tp=3.0, repeat_period=T_R, omega_range=(0.8, 5.0), seed=3)
    comps = sea.components(water_depth=model.hydro.water_depth, g=model.hydro.g)
    assert len(comps.omega) > 30
    sp = mfm.spectral_response(model, sea)
    names = [str(v) for v in sp.coordinate.values]
    q_rms = sp.q_rms.values
    q0 = sp.equilibrium.values

    # route 1, the closed form σ² = Σ_k ½ a_k² |x̂_k|², x̂ from mfm.frequency_response
    x = mfm.frequency_response(model, comps.omega, heading=float(comps.heading[0]), q0=q0,
                               joint_reactions=False).rao.values
    var_closed = np.sum(0.5 * comps.amplitude[:, None] ** 2 * np.abs(x) ** 2, axis=0)
    np.testing.assert_allclose(q_rms**2, var_closed, rtol=1e-9)

    # route 2, the sample variance of the time domain's heave over the last of three repeat
    # periods (whole periods: no sampling error; module docstring)
    ds = mfm.simulate(model, sea, duration=3 * T_R, dt=DT, q0=q0, radiation="convolution")
    n = int(round(T_R / DT))
    k = names.index("sphere.heave")
    heave = ds.q.values[2 * n:3 * n, k]
    assert heave.size == n and np.isclose(ds.time.values[2 * n], 2 * T_R)
    var_sim = np.var(heave)
    print(f"heave variance: spectral {q_rms[k]**2:.6g}, closed form {var_closed[k]:.6g}, "
          f"simulate {var_sim:.6g} m² (rel {var_sim / q_rms[k]**2 - 1:+.2e})")
    assert abs(var_sim / q_rms[k] ** 2 - 1) < 2e-2

    # the planted bug, the ½ dropped: q_rms² × 2, outside both tolerances by far
    wrong = 2 * q_rms**2
    assert np.all(np.abs(wrong / var_closed - 1) > 1e3 * 1e-9)
    assert abs(wrong[k] / var_sim - 1) > 10 * 2e-2
