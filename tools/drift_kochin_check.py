"""The far-field mean drift of given motions (``hydro.drift.far_field_drift``, from the Kochin
functions ``hydro.bem.solve(drift="kochin")`` stores) against capytaine 3.0's own chain on the
same two bodies and mesh (``BEMSolver.fill_dataset`` with a fine ``theta`` coordinate,
``cpt.post_pro.rao``, ``cpt.post_pro.far_field_mean_drift_force``). Writes
hydro/data/drift_kochin_check.nc: the project's database of the layout (with its Kochin functions
on hydro.bem.KOCHIN_N_THETA directions) plus, from capytaine's chain with its Kochin functions on
0.25° (its derivative in θ is a central difference: fine, so that its error is below the check's
tolerance):

- ``motions_random`` (omega, wave_direction, radiating_dof): complex motions drawn once (seed 7);
  ``drift_capytaine_random`` (omega, wave_direction, drift_component): capytaine's far-field
  drift of those motions (surge, sway, yaw about the origin);
- ``drift_capytaine_free`` (same): of the two bodies freely floating (capytaine's ``rao`` with
  the block rigid mass matrix of MASS/COM/INERTIA below, hydro.bem's ``rigid_mass_matrix``, and
  the hydrostatic plus gravity stiffness);
- ``drift_capytaine_free_symmetric`` with ``motions_free_symmetric``: the same with A(ω) and B(ω)
  symmetrised (reciprocity) as mfm takes them: the motions an mfm model of the two free bodies
  makes.

tests/test_drift_kochin.py compares them.

    PYTHONPATH=. python tools/drift_kochin_check.py

Two truncated cylinders (R 1 m, draft 1.5 m; A at the origin, B at (3, 1.5)), centres of mass
0.9 m below the water line (stable: the metacentre is 0.58 m below it), headings 0 and 30
degrees, 3 frequencies, deep water, dx 0.3 m: about 20 s on one thread.
"""
import time
from pathlib import Path

import numpy as np
import xarray as xr

from hydro import bem

R, DRAFT, RHO, G = 1.0, 1.5, 1000.0, 9.81
SPECS = [
    {"name": "A", "shape": "cylinder", "radius": R, "draft": DRAFT, "origin": [0.0, 0.0, 0.0],
     "reference_point": [0.0, 0.0, -0.9]},
    {"name": "B", "shape": "cylinder", "radius": R, "draft": DRAFT, "origin": [3.0, 1.5, 0.0],
     "reference_point": [3.0, 1.5, -0.9]},
]
MASS = RHO * np.pi * R * R * DRAFT
INERTIA = {"A": [3000.0, 4500.0, 2400.0], "B": [3500.0, 3500.0, 2000.0]}
OMEGA = [1.5, 2.2, 3.0]
HEADINGS = [0.0, np.pi / 6]
DX = 0.3
FINE = 1440
OUT = Path(__file__).resolve().parents[1] / "hydro" / "data" / "drift_kochin_check.nc"


def capytaine_chain(ds):
    """(random motions, drift of them, drift of the free bodies), capytaine's own chain."""
    import capytaine as cpt

    specs = bem.geo.normalize_specs(SPECS)
    body, _, _ = bem.build_body(specs, DX, lid=True)
    d = 2 * np.pi / FINE
    theta = d * np.arange(-1, FINE + 2)
    dofs = list(body.dofs)
    test = xr.Dataset(coords={"omega": OMEGA, "wave_direction": HEADINGS, "radiating_dof": dofs,
                              "water_depth": [np.inf], "rho": RHO, "g": G, "theta": theta})
    data = cpt.BEMSolver().fill_dataset(test, body, n_threads=1, progress_bar=False,
                                      hydrostatics=False)
    data = data.squeeze("water_depth", drop=False) if "water_depth" in data.dims else data
    M = np.zeros((12, 12))
    C = ds["hydrostatic_stiffness"].sel(influenced_dof=dofs, radiating_dof=dofs).values.copy()
    for k, s in enumerate(specs):
        ref = s["reference_point"]
        M[6 * k:6 * k + 6, 6 * k:6 * k + 6] = bem.rigid_mass_matrix(
            MASS, ref, np.diag(INERTIA[s["name"]]), ref)
        C[6 * k:6 * k + 6, 6 * k:6 * k + 6] += bem.gravity_stiffness(MASS, ref, ref, G)
    data["inertia_matrix"] = (("influenced_dof", "radiating_dof"), M)
    data["hydrostatic_stiffness"] = (("influenced_dof", "radiating_dof"), C)
    free = cpt.post_pro.rao(data).transpose("omega", "wave_direction", "radiating_dof")
    # the same motions with A(ω) and B(ω) symmetrised (reciprocity), as mfm's database() takes
    # them: what an mfm model of the two free bodies makes (capytaine's rao leaves the BEM's
    # asymmetry, which moves these motions by up to 0.15 % near heave resonance)
    sym = np.empty(free.shape, complex)
    for i, w in enumerate(OMEGA):
        A = data["added_mass"].sel(omega=w).transpose("influenced_dof", "radiating_dof").values
        B = data["radiation_damping"].sel(omega=w).transpose("influenced_dof",
                                                             "radiating_dof").values
        Z = -w * w * (M + 0.5 * (A + A.T)) - 1j * w * 0.5 * (B + B.T) + C
        F = data["excitation_force"].sel(omega=w).transpose("wave_direction",
                                                            "influenced_dof").values
        sym[i] = np.linalg.solve(Z, F.T).T
    sym = xr.DataArray(sym, dims=free.dims, coords=free.coords)
    rng = np.random.default_rng(7)
    shape = (len(OMEGA), len(HEADINGS), len(dofs))
    scale = np.array([1.0, 1.0, 1.0, 0.3, 0.3, 0.3] * 2)
    rand = (rng.normal(size=shape) + 1j * rng.normal(size=shape)) * scale
    rand = xr.DataArray(rand, dims=free.dims, coords=free.coords)

    def drift(X):
        f = cpt.post_pro.far_field_mean_drift_force(X, data)
        out = np.zeros((len(OMEGA), len(HEADINGS), 3))
        for i, name in enumerate(("drift_force_surge", "drift_force_sway", "drift_force_yaw")):
            v = f[name].transpose("omega", "wave_direction_k", "wave_direction_l").values
            out[:, :, i] = np.real(np.diagonal(v, axis1=1, axis2=2))
        return out

    return rand.values, drift(rand), drift(free), drift(sym), sym.values


def main():
    t0 = time.perf_counter()
    ds = bem.solve(SPECS, omega=OMEGA, dx=DX, wave_directions=HEADINGS, rho=RHO, g=G,
                   drift="kochin", cache=False, progress=False, n_threads=1)
    rand, d_rand, d_free, d_sym, x_sym = capytaine_chain(ds)
    fin = np.isfinite(ds["omega"].values)
    n_w = ds.sizes["omega"]

    def full(a, dtype=float):
        out = np.full((n_w,) + a.shape[1:], np.nan, dtype=dtype)
        out[fin] = a
        return out

    ds = ds.assign_coords(drift_component=["surge", "sway", "yaw"])
    ds["motions_random"] = (("omega", "wave_direction", "radiating_dof"), full(rand, complex),
                            {"meaning": "complex motions per unit wave amplitude, drawn once "
                                        "(numpy default_rng(7))"})
    ds["drift_capytaine_random"] = (("omega", "wave_direction", "drift_component"), full(d_rand),
                                    {"meaning": "capytaine 3.0's far_field_mean_drift_force of "
                                                "motions_random, yaw about the origin"})
    ds["drift_capytaine_free"] = (("omega", "wave_direction", "drift_component"), full(d_free),
                                  {"meaning": "capytaine 3.0's chain for the two bodies freely "
                                              "floating (post_pro.rao, far_field_mean_drift_force), "
                                              "yaw about the origin"})
    ds["drift_capytaine_free_symmetric"] = (
        ("omega", "wave_direction", "drift_component"), full(d_sym),
        {"meaning": "capytaine 3.0's far_field_mean_drift_force of the two bodies freely floating "
                    "with A(ω), B(ω) symmetrised (motions_free_symmetric), yaw about the origin"})
    ds["motions_free_symmetric"] = (("omega", "wave_direction", "radiating_dof"),
                                    full(x_sym, complex),
                                    {"meaning": "the two free bodies' motions, [−ω²(M + A_s) − iω "
                                                "B_s + C] X = F with A_s, B_s the symmetric parts "
                                                "of capytaine's A(ω), B(ω)"})
    ds.attrs["generated_by"] = "PYTHONPATH=. python tools/drift_kochin_check.py"
    ds.attrs["inertia"] = repr({"mass": MASS, "principal_inertia_about_reference_point": INERTIA})
    bem.save(ds, OUT)
    print(f"wrote {OUT} in {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
