"""Mutation check of the device modules: plants one plausible bug at a time on a temporary copy of
the repository, runs the tests that cover it, and reports which mutants the tests kill.

    python tools/mutation_check.py                 # every mutant
    python tools/mutation_check.py --only pto-gdot-sign,jonswap-sigma-swap
    python tools/mutation_check.py --list

Each mutant is a unique snippet of source text, its replacement, a one-line description and the
test files (or node ids) that should catch it. The file is found by searching the snippet in
mfm/**/*.py and hydro/**/*.py (not a fixed path: modules move), and the snippet must occur exactly
once there. A mutant is killed when pytest fails (exit 1); exit 5 (nothing collected), a missing
or ambiguous snippet, or a timeout is reported as an error, not a kill. Not run in CI (about an
hour on two cores).
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Mutant:
    name: str
    description: str
    snippet: str
    replacement: str
    tests: tuple[str, ...]
    equivalent: str = ""          # why the mutant cannot be observed (then a survivor is fine)


PTO = ("tests/test_device_ptos.py",)
MOOR = ("tests/test_device_moorings.py::test_stiffness_6x6_against_hand", "tests/test_device_moorings.py")
_F = "tests/test_device_frequency.py::"
FREQ = ("tests/test_device_frequency.py",)
NATFREQ = (_F + "test_sphere_heave_natural_frequency", _F + "test_hinged_float_natural_frequency")
FRESP = (_F + "test_hinged_float_damped_response_against_single_dof",
         _F + "test_m4_111_frequency_response_against_hand_assembly")
EQUIL = (_F + "test_sphere_equilibrium_heavy_and_off_centre",
         _F + "test_hinged_float_equilibrium_under_an_applied_moment")
LINEAR = (_F + "test_hinged_float_response_about_its_equilibrium",)
DRAG = ("tests/test_device_drag.py",)
SPEC = ("tests/test_device_spectra.py",)
_H = "tests/test_device_headings.py::"
HEAD = ("tests/test_device_headings.py",)
HEAD_REG = (_H + "test_regular_wave_excitation_at_heading", _H + "test_spread_sea_force_spectrum_against_hand_sum")
HEAD_SPREAD = (_H + "test_spreading_directions_follow_cos2s", _H + "test_spread_sea_force_spectrum_against_hand_sum")
HEAD_FR = (_H + "test_frequency_response_at_heading",)
PLUG = ("tests/test_loads_plugins.py",)

# issue 35 item 7: the independent routes (tests/test_independent_routes.py and one test beside
# the multi-heading sphere of tests/test_device_headings.py)
_IR = "tests/test_independent_routes.py::"
IR_WAMIT = (_IR + "test_wamit_ulen_scaling_of_a_second_body_by_hand",)
IR_CAPY = (_IR + "test_capytaine_two_bodies_of_different_mass_about_their_rotation_centres",)
IR_MINDET = (_IR + "test_min_det_refinement_against_the_analytic_root",)
IR_STABLE = (_IR + "test_largest_stable_dt_of_rk4_to_its_closed_form", "tests/test_stability.py")
IR_SPECTRAL = (_H + "test_spectral_statistics_of_a_spread_sea_by_two_routes",)

MUTANTS = [
    # ---------------------------------------------------------------- PTOs (issue 16 bugs 1, 2)
    Mutant("pto-gdot-sign", "planted bug 1: the sign of (|Δv|² − ẇ²)/L in the hydraulic PTO's ġq̇ flipped",
           "+ (jnp.sum(dv * dv, axis=1) - wd**2) / L", "- (jnp.sum(dv * dv, axis=1) - wd**2) / L", PTO),
    Mutant("pto-reaction-b-sign", "planted bug 2: the reaction on the PTO's second body with the wrong sign",
           "Wb = self.b.to_body_wrench((-Fa.reshape(P, 6)", "Wb = self.b.to_body_wrench((Fa.reshape(P, 6)", PTO),
    Mutant("pto-no-beta", "hydraulic damping β left out of the piston force",
           "f = self.mu * gdot_qd + self.beta * wd + self.kappa * w",
           "f = self.mu * gdot_qd + self.kappa * w", PTO),
    Mutant("pto-half-oil-mass", "oil mass μ g gᵀ halved in M*",
           'mass=jnp.einsum("p,pi,pj->ij", self.mu, g, g)', 'mass=0.5 * jnp.einsum("p,pi,pj->ij", self.mu, g, g)', PTO),
    Mutant("pto-row-sum", "stroke-rate row g = uᵀ(H_a + H_b) instead of uᵀ(H_a − H_b)",
           'g = jnp.einsum("pa,paq->pq", u, Ha - Hb)', 'g = jnp.einsum("pa,paq->pq", u, Ha + Hb)', PTO),
    Mutant("pto-power-abs", "absorbed power β|ẇ| instead of β ẇ²",
           '"hydraulic_power": absorbed_power(self.beta, wd)}',
           '"hydraulic_power": self.beta * jnp.abs(wd)}', PTO),
    Mutant("pto-bias-b-dropped", "the second end's velocity-product acceleration left out of ġq̇",
           "jnp.sum(u * (aa - ab), axis=1)", "jnp.sum(u * aa, axis=1)", PTO),
    # ------------------------------------------------------ moorings and point loads (bug 3)
    Mutant("mooring-lever-dropped", "planted bug 3: the mooring force applied at the CoM (lever arm dropped)",
           "return LoadOutput(body=self.points.to_body_wrench(F, ctx.kin, ctx.model.n_bodies))",
           "return LoadOutput(body=self.points.to_body_wrench(F, ctx.kin, ctx.model.n_bodies, "
           "point_offset=jnp.zeros_like(self.points.d_ref)))", MOOR),
    Mutant("mooring-axes-swapped", "mooring stiffness applied to the axes in reverse order (x ↔ z)",
           "f = -self.stiffness * (self.points.positions(ctx.kin)",
           "f = -self.stiffness[:, ::-1] * (self.points.positions(ctx.kin)", MOOR),
    Mutant("point-moment-sign", "moment of a point force about the CoM with the wrong sign (ρ × f)",
           "mb = se3.rotate_t(R, m + jnp.cross(rho, f))",
           "mb = se3.rotate_t(R, m - jnp.cross(rho, f))", MOOR),
    # ------------------------------------------ frequency domain and equilibrium (bug 4)
    Mutant("natfreq-stiffness-scaled", "planted bug 4: every natural frequency 10 % high (K × 1.21 inside natural_frequencies)",
           "    sys = linear_system(model, q0, loads=loads)\n    K = sys.K\n",
           "    sys = linear_system(model, q0, loads=loads)\n    K = 1.21 * sys.K\n", NATFREQ),
    Mutant("fr-damping-sign", "frequency response with +iω(B + C): the e^{+iωt} convention's impedance",
           "Z = np.einsum(\"ai,wab,bj->wij\", H0, -w**2 * A_rel - 1j * w * B, H0)",
           "Z = np.einsum(\"ai,wab,bj->wij\", H0, -w**2 * A_rel + 1j * w * B, H0)", FRESP),
    Mutant("fr-joint-damper-dropped", "frequency response without the joint dampers C",
           "- 1j * w * sys.C[None]", "- 0.0 * w * sys.C[None]", FRESP),
    Mutant("fr-excitation-conj", "frequency response with the conjugate excitation (WAMIT's convention)",
           'force=np.einsum("ai,wa->wi", H0, X))', 'force=np.einsum("ai,wa->wi", H0, X.conj()))', FRESP),
    Mutant("linearise-about-zero", "stiffness taken at q = 0 instead of the equilibrium",
           "    at = jet(model, q0, lds)\n",
           "    at = jet(model, jnp.zeros_like(jnp.asarray(q0)), lds)\n", LINEAR),
    Mutant("fr-heading-ignored", "frequency response in head seas whatever the heading",
           "heading=np.full_like(omega, heading)", "heading=np.full_like(omega, 0.0)", HEAD_FR),
    # -------------------------------------------------------------------------- hydrostatics
    Mutant("waterplane-scaled", "water-plane stiffness 10 % low in the time and frequency domains",
           "hydrostatic=-(self.C_wp[rows] @ xi),", "hydrostatic=-(0.9 * self.C_wp[rows] @ xi),", NATFREQ),
    Mutant("buoyancy-lever-fixed", "centre of buoyancy lever not turned with the body",
           "lever = se3.rotate(R, self.d_cob)", "lever = self.d_cob", NATFREQ + EQUIL),
    # the water load of one sea (build_water; simulate_batch's build_water_batch has its own line)
    Mutant("buoyancy-g", "buoyancy with g = 9.8 instead of the database's 9.81",
           "buoyancy=f64(spec.rho * spec.g * spec.volume), d_cob=f64(spec.d_cob),\n"
           "                 drag=f64(spec.drag), exc_t0=f64(t0), exc_step=f64(step)",
           "buoyancy=f64(spec.rho * 9.8 * spec.volume), d_cob=f64(spec.d_cob),\n"
           "                 drag=f64(spec.drag), exc_t0=f64(t0), exc_step=f64(step)", EQUIL),
    # ---------------------------------------------------------------------------------- drag
    Mutant("drag-no-abs", "drag −c u² (no |u|): pushes one way whatever the direction",
           "* (a < 3)) * jnp.abs(vr) * vr,", "* (a < 3)) * vr * vr,", DRAG),
    Mutant("drag-com-velocity", "drag on the CoM velocity instead of the hydro reference point's",
           "vr = v[rows]", "vr = kin.X[np.asarray(g.body_index)].reshape(-1)[rows]", DRAG),
    Mutant("drag-no-half", "drag coefficient without the ½ of ½ ρ C_D A",
           "self.drag = 0.5 * self.rho * np.asarray(drag, dtype=float)",
           "self.drag = self.rho * np.asarray(drag, dtype=float)", DRAG),
    # ------------------------------------------------------------------ waves and spectra (bug 5)
    Mutant("jonswap-sigma-swap", "planted bug 5: JONSWAP σ_a = 0.07 and σ_b = 0.09 swapped",
           "sigma = np.where(x <= 1.0, 0.07, 0.09)", "sigma = np.where(x <= 1.0, 0.09, 0.07)", SPEC),
    Mutant("pm-exponent", "Pierson–Moskowitz exponent −1.2 (ω_p/ω)⁴ instead of −5/4",
           "np.exp(-1.25 * r**4)", "np.exp(-1.2 * r**4)", SPEC),
    Mutant("amplitude-no-2", "component amplitude √(S Δω) instead of √(2 S Δω)",
           "amp = np.sqrt(2.0 * np.maximum(self.spectrum(w), 0.0) * dw)",
           "amp = np.sqrt(np.maximum(self.spectrum(w), 0.0) * dw)", SPEC),
    Mutant("dnv-agamma", "DNV normalisation 1 − 0.28 ln γ instead of 1 − 0.287 ln γ",
           "return 1.0 - 0.287 * math.log(gamma)", "return 1.0 - 0.28 * math.log(gamma)", SPEC),
    Mutant("deep-water-k", "deep-water wavenumber ω²/(2g)",
           "k_deep = w * w / g", "k_deep = w * w / (2.0 * g)", SPEC),
    Mutant("regular-amplitude", "regular wave amplitude H instead of H/2",
           "np.array([self.omega]), np.array([0.5 * self.height])", "np.array([self.omega]), np.array([self.height])", HEAD_REG),
    Mutant("spreading-half", "spread directions drawn at half their angle",
           "return sign * 2.0 * np.arcsin(np.sqrt(x))", "return sign * np.arcsin(np.sqrt(x))", HEAD_SPREAD),
    # ---------------------------------------------------------------------------- excitation
    Mutant("excitation-heading-ignored", "excitation interpolated at heading 0 whatever the sea's heading",
           "b = _map_headings(self.beta, self.periodic, heading, ~outside)",
           "b = _map_headings(self.beta, self.periodic, 0.0 * heading, ~outside)", HEAD_REG),
    Mutant("excitation-phase-interp", "phase interpolated the wrong way between database points",
           "np.exp(1j * (p0 + s * dp))", "np.exp(1j * (p0 - s * dp))", HEAD_REG),
    Mutant("excitation-time-sign", "excitation time series with e^{+iωt} (sin term sign)",
           "out[i:i + step] = np.cos(wt) @ cr + np.sin(wt) @ ci", "out[i:i + step] = np.cos(wt) @ cr - np.sin(wt) @ ci", HEAD_REG),
    # ------------------------------------------- the plug-in loads (body matrices, joint loads, points)
    Mutant("body-matrix-damping-sign", "a body matrix's damping pushing with the velocity (−K ξ + D ξ̇)",
           "+ jnp.einsum(\"pab,pb->pa\", self.damping, v.reshape(-1, 6)))",
           "- jnp.einsum(\"pab,pb->pa\", self.damping, v.reshape(-1, 6)))", PLUG),
    Mutant("critical-damping-factor", "critical damping without its factor 2 (c = ζ √(k m))",
           "return 2.0 * float(ratio) * math.sqrt(k * m)", "return float(ratio) * math.sqrt(k * m)", PLUG),
    Mutant("joint-load-sign", "a joint load acting against its stated direction",
           "return LoadOutput(tau=self.values)", "return LoadOutput(tau=-self.values)", PLUG),
    # the point probes' (mfm.loads.probes); the wind load's hub accelerometer has the same line
    Mutant("point-acceleration-bias-dropped", "a body point's acceleration without its Ḣ q̇ term",
           "v, bias = self.points.velocity_and_bias(ctx.kin)\n        acc = (H @ ctx.qdd + bias)",
           "v, bias = self.points.velocity_and_bias(ctx.kin)\n        acc = (H @ ctx.qdd)", PLUG),
    Mutant("free-coordinates-clamped", "natural frequencies with the coordinates without stiffness clamped",
           "return Mw[ix] + Mw[np.ix_(stiff, free)] @ G, G", "return Mw[ix], G", NATFREQ + (_F + "test_sphere_pitch_natural_frequency_with_surge_free",)),
    # ------------------------------------------- issue 35 item 7: tests that compared the code with itself
    # Against the module's existing tests alone 18 of these 22 survived; excitation-heading-long-arc
    # (the one-pass polar form against the two-step chain), equilibrium-early-stop (the heavy sphere's
    # equilibrium) and the two state-space order searches were already caught.
    # (a) derived statistics checked only against another path of the same code
    Mutant("pto-power-mean-half", "spectral pto_power_mean = Σ ½ a² ½ c ω² |G x̂|² (a² taken as the variance a²/2)",
           "power[i] = np.sum(a2 * mean_absorbed_power(c, cm.omega[:, None], x @ G.T), axis=0)",
           "power[i] = np.sum(0.5 * a2 * mean_absorbed_power(c, cm.omega[:, None], x @ G.T), axis=0)",
           ("tests/test_frequency_extras.py::test_linear_levels_report_the_piston_as_the_time_domain_does",)),
    Mutant("spectral-qrms-no-half", "spectral q_rms = √Σ a²|x̂|² (the ½ of a harmonic's variance dropped)",
           "q_rms[i] = np.sqrt(np.sum(0.5 * a2 * np.abs(x) ** 2, axis=0))",
           "q_rms[i] = np.sqrt(np.sum(a2 * np.abs(x) ** 2, axis=0))", IR_SPECTRAL),
    Mutant("spectral-raos-first-heading", "spectral RAOs of a spread sea all solved at its first heading",
           "x[sel] = _amplitudes(model, sys, union[sel, 1], float(beta), options)",
           "x[sel] = _amplitudes(model, sys, union[sel, 1], float(union[0, 0]), options)", IR_SPECTRAL),
    Mutant("user-spectrum-hs-rectangles", "UserSpectrum.hs by right rectangles instead of the trapezoid rule",
           "return 4.0 * math.sqrt(float(np.trapezoid(self.S, self.omega)))",
           "return 4.0 * math.sqrt(float(np.sum(self.S[1:] * np.diff(self.omega))))",
           (_IR + "test_user_spectrum_hs_is_the_area_of_its_table",) + SPEC),
    Mutant("welch-see-per-hz", "spectral_rao's S_ηη per Hz instead of per rad/s",
           "return 2 * math.pi * f, rao, S_ee / (2 * math.pi)", "return 2 * math.pi * f, rao, S_ee",
           (_IR + "test_welch_elevation_spectrum_integrates_to_its_variance",)),
    Mutant("reduce-error-own-scale", "reduce's PTO error against its own mean power, not the total",
           'scale = total if k.startswith("pto_power") else (abs(ref) or 1.0)',
           "scale = abs(ref) or 1.0",
           (_IR + "test_reduce_errors_are_against_the_total_power",)),
    # (b) readers and tables tested only on the shipped shapes
    Mutant("wamit-x-rot-by-mode-number", "WAMIT .3: a later body's forces scaled by ULEN³ as moments (mode > 3)",
           "rot = (im % 6) >= 3", "rot = im >= 3", IR_WAMIT),
    Mutant("wamit-kab-by-mode-number", "WAMIT .1/.hst: ULEN exponents by the mode number, not the mode of its body",
           "rot = (np.arange(n) % 6) >= 3", "rot = np.arange(n) >= 3", IR_WAMIT),
    Mutant("wamit-hst-ulen", "WAMIT .hst scaled by ULEN^k (the k of A, B) instead of ULEN^(k−1)",
           "C = C * rho * g * L ** (k_ab - 1)", "C = C * rho * g * L ** k_ab", IR_WAMIT),
    Mutant("nemoh-added-mass-transposed", "NEMOH A(ω) read transposed (zone = influenced dof)",
           "A = np.transpose(R[:, :, 1::2], (1, 2, 0))[order]",
           "A = np.transpose(R[:, :, 1::2], (1, 0, 2))[order]",
           (_IR + "test_nemoh_radiation_zones_read_back_entry_by_entry",)),
    Mutant("nemoh-excitation-reshape", "NEMOH excitation zones (heading, ω) reshaped, not transposed, to (ω, heading)",
           "return np.transpose(Xc, (1, 0, 2))[order], np.deg2rad(beta)",
           "return Xc.reshape(Xc.shape[1], Xc.shape[0], -1)[order], np.deg2rad(beta)",
           (_IR + "test_nemoh_excitation_of_three_headings_by_hand",)),
    Mutant("excitation-heading-long-arc", "excitation phase between headings along the long arc",
           "dP = xp.remainder(P1 - P0 + math.pi, 2.0 * math.pi) - math.pi", "dP = P1 - P0",
           (_IR + "test_heading_interpolation_takes_the_short_way_across_the_cut",)),
    Mutant("heading-two-periodic", "two headings taken for a full circle (periodic interpolation)",
           "covers = n >= 3 and", "covers = n >= 2 and",
           (_IR + "test_two_headings_are_not_a_full_circle",)),
    Mutant("power-matrix-reshape", "plot_batch's power matrix by reshaping the cases (Hs-major order assumed)",
           "M[np.searchsorted(H, hs), np.searchsorted(T, tp)] = P.values",
           "M[:] = P.values.reshape(len(H), len(T))",
           (_IR + "test_power_matrix_of_a_rectangular_sweep_in_any_case_order",)),
    Mutant("capytaine-mass-first-body", "capytaine hydrostatics: every body's gravity term with the first body's mass",
           'm = Mfile[o, o] if Mfile is not None and Mfile[o, o] > 0 else rho * h["volume"]',
           'm = Mfile[0, 0] if Mfile is not None and Mfile[0, 0] > 0 else rho * h["volume"]', IR_CAPY),
    Mutant("capytaine-rotation-centre-first-body", "capytaine: every body's rotation centre the first body's",
           "ref[b] = rc[b]", "ref[b] = rc[0]", IR_CAPY),
    # (c) refinements checked only to stay within the step they refine
    Mutant("min-det-unrefined", "min |det Λ| at the grid point, the parabolic refinement dropped",
           "mins.append(grid[i] + (0.5 * h * (y0 - y2) / den if den > 0 else 0.0))",
           "mins.append(grid[i])", IR_MINDET),
    Mutant("min-det-refined-backwards", "min |det Λ|: the parabola's vertex taken on the wrong side",
           "0.5 * h * (y0 - y2) / den", "0.5 * h * (y2 - y0) / den", IR_MINDET),
    Mutant("stable-dt-short-bisection", "largest_stable_dt: a third of the bisection halvings",
           "            for _ in range(iterations):\n                mid = 0.5 * (lo + hi)\n                lo, hi = (lo, mid) if unstable(mid)",
           "            for _ in range(iterations // 3):\n                mid = 0.5 * (lo + hi)\n                lo, hi = (lo, mid) if unstable(mid)",
           IR_STABLE),
    Mutant("stable-dt-loose-stop", "largest_stable_dt's bisection stopped at 1e-6 of dt, not 1e-12",
           "if hi - lo < 1e-12 * hi:", "if hi - lo < 1e-6 * hi:", IR_STABLE),
    Mutant("equilibrium-early-stop", "equilibrium's Newton stopped at a residual of 1e-6 of the weights, not 1e-10",
           "if np.abs(g).max() < tol * scale:", "if np.abs(g).max() < 1e4 * tol * scale:",
           (_IR + "test_equilibrium_newton_to_the_analytic_angle",) + EQUIL),
    Mutant("statespace-entry-first-passive-order", "per-entry fit: the first passive order, whatever its error",
           "if err < target and pas:", "if pas:", ("tests/test_hydro_radiation.py",)),
    Mutant("statespace-common-first-order", "common-pole fit: the first order of the list, whatever its error",
           "        if err < target:\n            break", "        if True:\n            break",
           ("tests/test_statespace_speed.py::test_common_fit_is_passive_and_within_its_error",)),
]

IGNORE = shutil.ignore_patterns(".git", ".venv", "__pycache__", "*.pyc", ".pytest_cache", "out",
                                "figures", "*.egg-info")


def locate(root: Path, snippet: str) -> tuple[Path | None, str]:
    hits = []
    for pkg in ("mfm", "hydro"):
        for f in sorted((root / pkg).rglob("*.py")):
            n = f.read_text().count(snippet)
            if n:
                hits.append((f, n))
    if not hits:
        return None, "snippet not found"
    if len(hits) > 1 or hits[0][1] > 1:
        return None, "snippet not unique: " + ", ".join(f"{f.relative_to(root)} ×{n}" for f, n in hits)
    return hits[0][0], ""


def run_mutant(copy: Path, m: Mutant, timeout: float) -> tuple[str, str, float]:
    # the tests as they are now in the working tree (they may be edited while this runs)
    shutil.rmtree(copy / "tests")
    shutil.copytree(ROOT / "tests", copy / "tests", ignore=IGNORE)
    path, err = locate(copy, m.snippet)
    if path is None:
        return "error", err, 0.0
    original = path.read_text()
    path.write_text(original.replace(m.snippet, m.replacement))
    env = dict(os.environ, PYTHONPATH=str(copy), MPLBACKEND="Agg")
    t0 = time.perf_counter()
    try:
        r = subprocess.run([sys.executable, "-m", "pytest", "-x", "-q", "-n", "0", "-p", "no:cacheprovider",
                            *m.tests], cwd=copy, env=env, capture_output=True, text=True,
                           timeout=timeout)
        rc = r.returncode
        tail = (r.stdout.strip().splitlines() or [""])[-1]
    except subprocess.TimeoutExpired:
        rc, tail = None, f"timeout after {timeout:.0f} s"
    finally:
        path.write_text(original)
    wall = time.perf_counter() - t0
    where = str(path.relative_to(copy))
    if rc == 1:
        failed = [ln.split(" ")[1] for ln in (r.stdout.splitlines()) if ln.startswith("FAILED ")]
        return "killed", f"{where}: {failed[0] if failed else tail}", wall
    if rc == 0:
        return "survived", f"{where}: {tail}", wall
    return "error", f"{where}: exit {rc}: {tail}", wall


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", help="comma-separated mutant names")
    ap.add_argument("--list", action="store_true", help="list the mutants and exit")
    ap.add_argument("--timeout", type=float, default=1200.0, help="seconds per mutant (default 1200)")
    args = ap.parse_args(argv)
    mutants = MUTANTS
    if args.only:
        names = args.only.split(",")
        unknown = sorted(set(names) - {m.name for m in MUTANTS})
        if unknown:
            ap.error(f"unknown mutants {unknown}")
        mutants = [m for m in MUTANTS if m.name in names]
    if args.list:
        for m in mutants:
            print(f"{m.name:28s} {m.description}  [{' '.join(m.tests)}]")
        return 0
    results = []
    with tempfile.TemporaryDirectory(prefix="mfm-mutants-") as tmp:
        copy = Path(tmp) / "repo"
        shutil.copytree(ROOT, copy, ignore=IGNORE)
        for m in mutants:
            status, detail, wall = run_mutant(copy, m, args.timeout)
            note = f"  (equivalent: {m.equivalent})" if status == "survived" and m.equivalent else ""
            print(f"{status:8s} {m.name:28s} {wall:6.0f} s  {detail}{note}", flush=True)
            results.append((m, status))
    killed = sum(s == "killed" for _, s in results)
    scored = [r for r in results if r[1] != "error"]
    print(f"\nkilled {killed} of {len(scored)} mutants ({100 * killed / max(len(scored), 1):.0f} %); "
          f"{len(results) - len(scored)} errors")
    for m, s in results:
        if s != "killed":
            print(f"  {s}: {m.name}: {m.description}" + (f" (equivalent: {m.equivalent})" if m.equivalent else ""))
    return 0 if killed == len(results) else 1


if __name__ == "__main__":
    sys.exit(main())
