"""capytaine NetCDF files written by other capytaine versions (1.x, 2.x, 3.x without ``mfm hydro``)
brought to the form :func:`hydro.database.from_capytaine` converts.

What other versions' files differ in (checked on the WEC-Sim BEMIO examples, capytaine 2.3.1, and
on hand-made variants in tests/test_bem_formats.py):

- complex values split into a ``complex`` dim (first or last, coordinates "re"/"im"), rejoined;
- ``g``, ``rho``, ``water_depth`` as scalar coordinates, length-1 dims, data variables or global
  attributes (all read; missing rho or g is an error, missing depth is infinite; rho and g must be
  finite and > 0, depth > 0);
- headings named ``wave_direction`` or ``angle`` (capytaine 0.x/1.0);
- dofs prefixed ``<body>__`` (multi-body) or bare (single body: the name is the ``body_name``
  coordinate, else the file's stem);
- no ω = ∞ (most runs): ``added_mass_inf`` is estimated by Ogilvie's relation
  (:func:`hydro.radiation.estimate_added_mass_inf`; attrs["added_mass_inf_source"] says so);
- only ``excitation_force`` (no Froude–Krylov/diffraction split), or only the split;
- no ``waterplane_stiffness``, ``displaced_volume``, ``center_of_buoyancy`` or rotation centre:
  taken from the NEMOH-format files capytaine's ``export_hydrostatics`` writes beside the data
  (``KH[_b].dat``, ``Hydrostatics[_b].dat``, read by :mod:`hydro.nemoh`; the file's own
  ``hydrostatic_stiffness`` is preferred to KH where present). capytaine's rigid-body stiffness is
  about the rotation centre c with, in 44/55, rho g V (z_B − z_c) − m g (z_G − z_c)
  (m: the body's mass in ``inertia_matrix`` where present, else rho V); both are removed
  (:func:`hydro.nemoh.waterplane_part`). Without a ``rotation_center`` in the file the rotation
  centre is taken as the centre of gravity XG of Hydrostatics.dat (capytaine writes the body's
  ``center_of_mass`` there; the WEC-Sim examples rotate about it) — attrs["reference_point_source"].

Phase convention: capytaine's e^{−iωt} in every version: no conversion.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from .database import MODES, _SEP, from_capytaine, merge_complex
from .nemoh import hydrostatics_files, read_hydrostatics, read_kh, waterplane_part


def _scalar(ds, name, path):
    """A scalar setting of a capytaine file: a coordinate, a data variable (size 1) or an attr."""
    if name in ds.variables:
        v = np.asarray(ds[name].values).ravel()
        if v.size != 1:
            v = np.unique(v)
            if v.size != 1:
                raise ValueError(f"{path}: {name} takes several values {v.tolist()}; accepted: one "
                                 "value per file (split the dataset by ds.sel)")
        return float(v[0])
    if name in ds.attrs:
        return float(ds.attrs[name])
    return None


def normalise_capytaine(ds: xr.Dataset, path) -> xr.Dataset:
    """A capytaine dataset of any version → the form of capytaine 3 (complex rejoined, settings
    as scalar coordinates, ``wave_direction``, dims without length-1 settings)."""
    ds = merge_complex(ds)
    if "angle" in ds.dims and "wave_direction" not in ds.dims:
        ds = ds.rename(angle="wave_direction")
    for d in ("g", "rho", "water_depth", "forward_speed", "body_name"):
        if d in ds.dims:
            if ds.sizes[d] != 1:
                raise ValueError(f"{path}: dimension {d!r} has {ds.sizes[d]} values "
                                 f"{np.asarray(ds[d].values).tolist()}; accepted: one value per file "
                                 f"(e.g. ds.sel({d}=...) before saving)")
            ds = ds.squeeze(d)
    settings = {}
    for name in ("rho", "g", "water_depth"):
        v = _scalar(ds, name, path)
        settings[name] = v
    if settings["rho"] is None or settings["g"] is None:
        raise ValueError(f"{path}: no rho or g (as a coordinate, variable or attribute); accepted: "
                         "a capytaine dataset saved with its settings (cpt.export_dataset)")
    for name, v, ok, acc in (("rho", settings["rho"], settings["rho"] > 0, "> 0 kg/m^3"),
                             ("g", settings["g"], settings["g"] > 0, "> 0 m/s^2")):
        if not (np.isfinite(v) and ok):
            raise ValueError(f"{path}: {name} = {v!r}; accepted: a finite value {acc}")
    depth = settings["water_depth"]
    depth = np.inf if depth is None or depth == 0 else depth
    if not depth > 0:
        raise ValueError(f"{path}: water_depth = {depth!r}; accepted: > 0 m or inf")
    drop = [n for n in ("rho", "g", "water_depth") if n in ds.variables]
    ds = ds.drop_vars(drop)
    return ds.assign_coords(rho=settings["rho"], g=settings["g"], water_depth=float(depth))


def from_other_capytaine(raw: xr.Dataset, path, names=None) -> xr.Dataset:
    """A capytaine NetCDF of another version (module docstring) → the internal database.

    `names`: the bodies in file order (renames them; e.g. ["float", "spar"] for WEC-Sim's
    "rm3_float", "rm3_spar").
    """
    from .radiation import estimate_added_mass_inf

    path = Path(path)
    ds = normalise_capytaine(raw, path)
    if "excitation_force" in ds and not ("Froude_Krylov_force" in ds and "diffraction_force" in ds):
        ds["Froude_Krylov_force"] = ds["excitation_force"]
        ds["diffraction_force"] = xr.zeros_like(ds["excitation_force"])
        split = False
    else:
        split = True
    dofs = [str(d) for d in ds["influenced_dof"].values]
    if all(_SEP in d for d in dofs):
        file_names = list(dict.fromkeys(d.split(_SEP)[0] for d in dofs))
    else:
        bn = str(ds["body_name"].values) if "body_name" in ds.coords else path.stem
        file_names = [bn.replace(_SEP, "_").replace("+", "_") or "body0"]
        rename = {d: f"{file_names[0]}{_SEP}{d}" for d in dofs}
        ds = ds.assign_coords(influenced_dof=[rename[d] for d in dofs],
                              radiating_dof=[rename[str(d)] for d in ds["radiating_dof"].values])
    nb = len(file_names)
    out_names = file_names if names is None else ([names] if isinstance(names, str) else list(names))
    if len(out_names) != nb:
        raise ValueError(f"names {out_names} ({len(out_names)}) do not match the {nb} bodies "
                         f"{file_names} of {path}")
    rho, g = float(ds["rho"].values), float(ds["g"].values)

    # hydrostatics: the file's, completed by export_hydrostatics' files beside it
    have_wp = "waterplane_stiffness" in ds and "displaced_volume" in ds and "center_of_buoyancy" in ds
    labels = [f"{b}{_SEP}{m}" for b in file_names for m in MODES]
    ref_src = "rotation_center of the file"
    if not have_wp:
        n = 6 * nb
        Cfile = (np.asarray(ds["hydrostatic_stiffness"].sel(influenced_dof=labels, radiating_dof=labels)
                            .transpose("influenced_dof", "radiating_dof").values, dtype=float)
                 if "hydrostatic_stiffness" in ds else None)
        Mfile = (np.asarray(ds["inertia_matrix"].sel(influenced_dof=labels, radiating_dof=labels)
                            .transpose("influenced_dof", "radiating_dof").values, dtype=float)
                 if "inertia_matrix" in ds else None)
        rc = (np.asarray(ds["rotation_center"].values, dtype=float).reshape(nb, 3)
              if "rotation_center" in ds.variables else None)
        C, W = np.zeros((n, n)), np.zeros((n, n))
        vol, cob, ref = np.zeros(nb), np.zeros((nb, 3)), np.zeros((nb, 3))
        for b in range(nb):
            kh, hs = hydrostatics_files(path.parent, b, nb, extra_dirs=[path.parent])
            if hs is None or (kh is None and Cfile is None):
                raise ValueError(
                    f"{path}: body {file_names[b]!r} has no displaced volume, centre of buoyancy or "
                    f"water-plane stiffness in the file, and no Hydrostatics_{b}.dat / KH_{b}.dat "
                    f"{'(or Hydrostatics.dat / KH.dat) ' if nb == 1 else ''}beside it (capytaine's "
                    "capytaine.io.legacy.export_hydrostatics writes them); accepted: a file of "
                    "`mfm hydro`, or one with those files beside it")
            h = read_hydrostatics(hs)
            o = 6 * b
            K = Cfile[o:o + 6, o:o + 6] if Cfile is not None and np.any(Cfile[o:o + 6, o:o + 6]) else read_kh(kh)
            if rc is not None:
                ref[b] = rc[b]
            else:
                ref[b] = h["cog"]
                ref_src = "centre of gravity XG of Hydrostatics[_b].dat (no rotation_center in the file)"
            m = Mfile[o, o] if Mfile is not None and Mfile[o, o] > 0 else rho * h["volume"]
            C[o:o + 6, o:o + 6] = K
            W[o:o + 6, o:o + 6] = waterplane_part(K, h["volume"], h["cob"], ref[b], ref[b], rho, g,
                                                  mass=m, cog=h["cog"])
            vol[b], cob[b] = h["volume"], h["cob"]
        ds = ds.drop_vars([v for v in ("hydrostatic_stiffness", "rotation_center") if v in ds.variables])
        mat = ("influenced_dof", "radiating_dof")
        ds["hydrostatic_stiffness"] = xr.DataArray(C, dims=mat, coords={d: labels for d in mat})
        ds["hydrostatic_stiffness"].attrs["includes"] = (
            "capytaine's rigid-body stiffness as given, about each rotation centre: water-plane terms "
            "and rho g V (z_B - z_c) - m g (z_G - z_c) in 44/55")
        ds["waterplane_stiffness"] = xr.DataArray(W, dims=mat, coords={d: labels for d in mat})
        ds["waterplane_stiffness"].attrs["includes"] = (
            "water-plane terms only (33, 34, 35, 44, 55, 45 about the reference point)")
        ds["displaced_volume"] = xr.DataArray(vol, dims=("body",))
        ds["center_of_buoyancy"] = xr.DataArray(cob, dims=("body", "axis"))
        ds["reference_point"] = xr.DataArray(ref, dims=("body", "axis"))
    om = np.asarray(ds["omega"].values, dtype=float)
    _check_omega(om, path)
    estimated = not np.any(np.isinf(om))
    if estimated:
        # from_capytaine takes A∞ from the ω = ∞ row: give it a provisional one (replaced below)
        inf_row = ds.isel(omega=[int(np.argmax(om))]).assign_coords(omega=[np.inf])
        ds = xr.concat([ds, inf_row], dim="omega", data_vars="minimal", coords="minimal",
                       compat="override")
    if "body" in ds.coords and ds["body"].ndim == 0:
        ds = ds.drop_vars("body")
    db = from_capytaine(ds.drop_vars([c for c in ("body_name",) if c in ds.coords]), source=path)
    if estimated:
        db["added_mass_inf"] = (("influenced_dof", "radiating_dof"), estimate_added_mass_inf(db))
        db.attrs["added_mass_inf_source"] = (
            "estimated (the file has no omega = inf): median over the radiation band of A(omega) + "
            "(1/omega) int K(t) sin(omega t) dt, hydro.radiation.estimate_added_mass_inf")
    if not split:
        db = db.drop_vars(["froude_krylov", "diffraction"])
    if not have_wp:
        db.attrs["reference_point_source"] = ref_src
    db.attrs["source"] = f"capytaine {raw.attrs.get('capytaine_version', '(version not recorded)')} file {path}"
    if out_names != file_names:
        db = _rename_bodies(db, file_names, out_names)
    return db


def _check_omega(om, path):
    fin = om[np.isfinite(om) & (om > 0)]
    if np.any(np.isnan(om)) or np.any(om < 0):
        raise ValueError(f"{path}: omega holds {om[np.isnan(om) | (om < 0)][:3].tolist()}; accepted: "
                         "frequencies > 0 rad/s (0 and inf for the limits)")
    if len(np.unique(fin)) != len(fin):
        raise ValueError(f"{path}: omega repeats values ({fin[:5].tolist()}…); accepted: distinct "
                         "frequencies")


def _rename_bodies(db, old, new):
    if len(set(new)) != len(new) or any(_SEP in n for n in new):
        raise ValueError(f"names {new}: give distinct names without '{_SEP}'")
    m = dict(zip(old, new))

    def lab(d):
        b, mode = str(d).split(_SEP)
        return f"{m[b]}{_SEP}{mode}"
    return db.assign_coords(body=new, influenced_dof=[lab(d) for d in db["influenced_dof"].values],
                            radiating_dof=[lab(d) for d in db["radiating_dof"].values])


def rename_bodies(db: xr.Dataset, names) -> xr.Dataset:
    """`db` with its bodies renamed to `names` in order (dof labels too)."""
    old = [str(b) for b in db["body"].values]
    names = [names] if isinstance(names, str) else list(names)
    if len(names) != len(old):
        raise ValueError(f"names {names} ({len(names)}) do not match the {len(old)} bodies {old}")
    return db if names == old else _rename_bodies(db, old, names)
