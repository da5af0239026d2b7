"""The freely floating body's far-field mean drift of ``hydro.bem.solve(drift="free")`` against
capytaine 3.0's own pipeline on the same body and mesh (``BEMSolver.fill_dataset`` with a
``theta`` coordinate, ``cpt.post_pro.rao``, ``cpt.post_pro.far_field_mean_drift_force``, as its
documentation chains them), with this project's mass matrix and restoring (hydro.bem's
``rigid_mass_matrix`` + ``hydrostatic_stiffness`` + ``gravity_stiffness``; the mass matrix is
checked on its own in the tests). What it checks: the project's wiring (the Kochin functions of
each frequency and its depth, the motions, the heading mapping, the yaw moved to the reference
point). Writes hydro/data/drift_free_check.nc: the project's database plus
``mean_drift_capytaine`` (omega, wave_direction, influenced_dof; surge, sway, yaw about the
ORIGIN as capytaine gives it), compared by tests/test_drift_53.py.

    PYTHONPATH=. python tools/drift_free_check.py

A truncated cylinder (R 1 m, draft 1.5 m) off the origin (reference point (2, 1, -0.3) m, its
centre of mass there too), unequal roll and pitch inertias, headings 0 and 30 degrees, 3
frequencies, deep water, dx 0.3 m: about 6 s on one thread.
"""
import time
from pathlib import Path

import numpy as np
import xarray as xr

from hydro import bem

R, DRAFT, RHO, G = 1.0, 1.5, 1000.0, 9.81
REF = [2.0, 1.0, -0.3]
SPEC = {"name": "float", "shape": "cylinder", "radius": R, "draft": DRAFT, "origin": [2.0, 1.0, 0.0],
        "reference_point": REF}
MASS = RHO * np.pi * R * R * DRAFT
INERTIA = {"mass": MASS, "com": REF, "inertia": [[3000.0, 0, 0], [0, 4500.0, 0], [0, 0, 2400.0]]}
OMEGA = [1.5, 2.2, 3.0]
HEADINGS = [0.0, np.pi / 6]
DX = 0.3
OUT = Path(__file__).resolve().parents[1] / "hydro" / "data" / "drift_free_check.nc"


def capytaine_pipeline(ds):
    import capytaine as cpt

    body, _, _ = bem.build_body([bem.geo.normalize_specs([SPEC])[0]], DX, lid=True)
    theta = np.linspace(-np.pi / 180, 2 * np.pi + np.pi / 180, 363)
    test = xr.Dataset(coords={"omega": OMEGA, "wave_direction": HEADINGS,
                              "radiating_dof": list(body.dofs), "water_depth": [np.inf],
                              "rho": RHO, "g": G, "theta": theta})
    data = cpt.BEMSolver().fill_dataset(test, body, n_threads=1, progress_bar=False,
                                      hydrostatics=False)
    data = data.squeeze("water_depth", drop=False) if "water_depth" in data.dims else data
    dofs = list(body.dofs)
    M = bem.rigid_mass_matrix(INERTIA["mass"], INERTIA["com"], INERTIA["inertia"], REF)
    C = ds["hydrostatic_stiffness"].sel(influenced_dof=dofs, radiating_dof=dofs).values \
        + bem.gravity_stiffness(INERTIA["mass"], INERTIA["com"], REF, G)
    data["inertia_matrix"] = (("influenced_dof", "radiating_dof"), M)
    data["hydrostatic_stiffness"] = (("influenced_dof", "radiating_dof"), C)
    X = cpt.post_pro.rao(data)
    f = cpt.post_pro.far_field_mean_drift_force(X, data)
    out = np.zeros((len(OMEGA), len(HEADINGS), 6))
    for i, name in ((0, "drift_force_surge"), (1, "drift_force_sway"), (5, "drift_force_yaw")):
        v = f[name].transpose("omega", "wave_direction_k", "wave_direction_l").values
        out[:, :, i] = np.real(np.diagonal(v, axis1=1, axis2=2))
    return out


def main():
    t0 = time.perf_counter()
    ds = bem.solve([SPEC], omega=OMEGA, dx=DX, wave_directions=HEADINGS, rho=RHO, g=G,
                   drift="free", drift_inertia=INERTIA, cache=False, progress=False, n_threads=1)
    ref = capytaine_pipeline(ds)
    full = np.full((ds.sizes["omega"], len(HEADINGS), 6), np.nan)
    full[np.isfinite(ds["omega"].values)] = ref
    ds["mean_drift_capytaine"] = (("omega", "wave_direction", "influenced_dof"), full)
    ds["mean_drift_capytaine"].attrs["meaning"] = (
        "capytaine 3.0's own pipeline (fill_dataset with theta, post_pro.rao, "
        "far_field_mean_drift_force), yaw about the origin (0, 0)")
    ds.attrs["generated_by"] = "PYTHONPATH=. python tools/drift_free_check.py"
    bem.save(ds, OUT)
    ours = ds["mean_drift"].values[np.isfinite(ds["omega"].values)]
    print(f"wrote {OUT} in {time.perf_counter() - t0:.1f} s; surge/sway drift ours vs capytaine's "
          f"pipeline, largest relative difference: "
          f"{np.max(np.abs(ours[..., :2] - ref[..., :2])) / np.max(np.abs(ref[..., :2])):.2e}")


if __name__ == "__main__":
    main()
