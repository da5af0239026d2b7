"""BEMIO HDF5 files (WEC-Sim's and SEA-Stack/HydroChrono's hydro data): read and write.

The layout is the one WEC-Sim's ``writeBEMIOH5.m`` writes and ``readBEMIOH5.m`` reads
(WEC-Sim, ``source/functions/BEMIO``; checked at commit a23d299 and on the public ``sphere.h5`` of
NREL/HydroChrono and Project-SEA-Stack/SEA-Stack). MATLAB writes arrays column-major, so a
dataset written from a MATLAB array of size (a, b, c) appears to HDF5 (and here) as (c, b, a);
BEMIO permutes its arrays before writing so that, as read here:

====================================================  ==================  =====================
dataset                                                shape here          value
====================================================  ==================  =====================
/simulation_parameters/rho, g, scaled                  (1, 1)              kg/m³, m/s², 0
/simulation_parameters/w, T                            (N_ω, 1)            rad/s, s (T = 2π/ω)
/simulation_parameters/wave_dir                        (N_β, 1)            degrees
/simulation_parameters/water_depth                     (1, 1) or string    m, or "infinite"
/bem_data/code                                         string              the BEM solver
/body<n>/properties/name                               string              the body's name
/body<n>/properties/body_number, dof, dof_start,       (1, 1)              n, 6, 6n − 5, 6n
    dof_end
/body<n>/properties/cg, cb                             (3, 1)              m
/body<n>/properties/disp_vol                           (1, 1)              m³
/body<n>/hydro_coeffs/linear_restoring_stiffness       (6, 6)              C / (ρ g)
/body<n>/hydro_coeffs/added_mass/all                   (6, 6 N_b, N_ω)     A / ρ
/body<n>/hydro_coeffs/added_mass/inf_freq              (6, 6 N_b)          A∞ / ρ
/body<n>/hydro_coeffs/radiation_damping/all            (6, 6 N_b, N_ω)     B / (ρ ω)
/body<n>/hydro_coeffs/excitation/re, im, mag, phase    (6, N_β, N_ω)       X / (ρ g), phase rad
/body<n>/hydro_coeffs/excitation/froude-krylov/…,      (6, N_β, N_ω)       the same, each part
    scattering/… (re, im, mag, phase)
/body<n>/hydro_coeffs/radiation_damping/               (6, 6 N_b, N_t),    K(t) / ρ, s, rad/s
    impulse_response_fun/K, t, w                           (N_t, 1), (N_ω', 1)
/body<n>/hydro_coeffs/excitation/impulse_response_fun/ (6, N_β, N_t), …    K_X(t) / (ρ g)
    f, t, w
====================================================  ==================  =====================

The rows of body n's arrays are its 6 dofs (surge … yaw), the columns of A and B all 6 N_b dofs
(bodies in ``body<n>`` order): the cross-body terms are there. Rotations are about ``cg``, the
point every coefficient of the body is given about (BEMIO's readWAMIT sets it to the WAMIT body
origin, readNEMOH to NEMOH's centre of gravity; WEC-Sim applies the data about the body's centre
of gravity): it is the database's ``reference_point``.

Conventions (BEMIO's ``normalizeBEM.m`` and its readers):

- non-dimensional as WAMIT's with L = 1: A = ρ Ā, B = ρ ω B̄, X = ρ g X̄, C = ρ g C̄, A∞ = ρ Ā∞;
- time dependence e^{+iωt} (WAMIT's; BEMIO's capytaine reader negates capytaine's imaginary
  parts): X_internal = ρ g conj(re + i im), as :mod:`hydro.wamit`;
- ``linear_restoring_stiffness`` is the hydrostatic and gravity restoring about cg with m = ρV
  (WAMIT's .hst, NEMOH's KH): its 44/55 hold ρ g V (z_B − z_G) besides the water-plane terms, its
  46/56 −ρ g V (x_B − x_G), −ρ g V (y_B − y_G). ``waterplane_stiffness`` keeps the water-plane
  terms (:func:`hydro.nemoh.waterplane_part`); ``hydrostatic_stiffness`` is the file's, × ρ g.

Read and ignored: the impulse responses, the state-space fits (``radiation_damping/state_space``),
QTFs, mean drift, generalised body modes (a body with ``dof`` ≠ 6 is refused), and the legacy
``components`` groups of python-BEMIO files (copies of the ``all`` arrays). mfm makes its own
K(t) and fits from A, B and A∞.

Written (:func:`write_bemio`): every dataset ``readBEMIOH5.m`` reads, with the radiation and
excitation impulse responses that WEC-Sim's convolution and HydroChrono's irregular waves need,
computed as BEMIO's ``radiationIRF``/``excitationIRF`` define them from the same data (trapezoid on
:data:`IRF_N_OMEGA` frequencies spread evenly over the database's band, t on [0, :data:`IRF_T_END`]
and [−IRF_T_END, IRF_T_END], :data:`IRF_N_T` instants):
K(t) = (2/π) ∫ B(ω)/ρ cos ωt dω, K_X(t) = (1/π) ∫ (X̄_re cos ωt − X̄_im sin ωt) dω. No state-space
fit is written (WEC-Sim's default, ``stateSpace = 0``, uses the convolution). A database without
the Froude–Krylov/diffraction split gets NaN for both parts (BEMIO's NEMOH reader does the same).
The file is HDF5 written through netCDF4 (the base install's library): strings are variable-length
(``readBEMIOH5.m`` takes the first cell of such a name), and netCDF's dimension scales are extra
datasets in the root group (``/bemio_dim_*``), which BEMIO's readers never open.
"""
from __future__ import annotations

import os
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import xarray as xr

from .database import AXES, CONVENTION, _SEP, dof_labels

#: the impulse responses written with a file (BEMIO's radiationIRF/excitationIRF defaults)
IRF_T_END = 100.0
IRF_N_T = 1001
IRF_N_OMEGA = 1001

_MAGIC = b"\x89HDF\r\n\x1a\n"


class _File:
    """An HDF5 file read whole from memory (the project never gives HDF5 a second handle on a path
    a process may hold open: hydro.database's note), its datasets looked up by path with errors
    that name the file, the dataset and what is expected."""

    def __init__(self, path):
        import netCDF4

        self.path = Path(path)
        if not self.path.exists():
            raise FileNotFoundError(f"hydro.database: {str(self.path)!r} not found; fix the path "
                                    "(relative to the config)")
        data = self.path.read_bytes()
        if not data.startswith(_MAGIC):
            raise ValueError(f"{str(self.path)!r} ({len(data)} bytes) is not an HDF5 file (it starts "
                             f"with {data[:8]!r}); accepted: a BEMIO .h5 file (WEC-Sim's "
                             "writeBEMIOH5, `mfm hydro --format bemio`)")
        try:
            self.nc = netCDF4.Dataset("inmemory.h5", mode="r", memory=data)
        except OSError as e:
            raise ValueError(f"{str(self.path)!r} is not a readable HDF5 file ({e})") from None
        self.nc.set_auto_mask(False)

    def close(self):
        self.nc.close()

    def _node(self, key):
        parts = [p for p in key.split("/") if p]
        g = self.nc
        for p in parts[:-1]:
            if p not in g.groups:
                return None
            g = g.groups[p]
        return g.variables.get(parts[-1])

    def has(self, key) -> bool:
        return self._node(key) is not None

    def groups(self, key="/"):
        g = self.nc
        for p in [p for p in key.split("/") if p]:
            g = g.groups[p]
        return list(g.groups)

    def array(self, key, shape=None, what=""):
        v = self._node(key)
        if v is None:
            raise ValueError(f"{str(self.path)!r}: no dataset {key} ({what or 'required'}); "
                             "accepted: a BEMIO file as WEC-Sim's writeBEMIOH5 writes it (hydro/"
                             "bemio.py lists the datasets)")
        a = np.asarray(v[...])
        if a.dtype.kind not in "fiu":
            raise ValueError(f"{str(self.path)!r}: dataset {key} holds {a.dtype} {a!r:.60}; expected "
                             f"numbers ({what})")
        a = a.astype(float)
        if shape is not None and a.shape != tuple(shape):
            raise ValueError(f"{str(self.path)!r}: dataset {key} has shape {a.shape}; expected "
                             f"{tuple(shape)} ({what}; BEMIO writes MATLAB arrays, which HDF5 "
                             "shows with their dimensions reversed)")
        return a

    def scalar(self, key, what=""):
        a = self.array(key, what=what)
        if a.size != 1:
            raise ValueError(f"{str(self.path)!r}: dataset {key} has shape {a.shape}; expected one "
                             f"value ({what})")
        return float(a.ravel()[0])

    def vector(self, key, what=""):
        a = self.array(key, what=what)
        if a.ndim > 2 or (a.ndim == 2 and 1 not in a.shape):
            raise ValueError(f"{str(self.path)!r}: dataset {key} has shape {a.shape}; expected a "
                             f"vector, (n, 1) ({what})")
        return a.ravel()

    def text(self, key):
        v = self._node(key)
        if v is None:
            return None
        a = v[...]
        if isinstance(a, bytes):
            return a.decode(errors="replace")
        if isinstance(a, str):
            return a
        a = np.asarray(a)
        if a.dtype.kind in "SU":
            return "".join(x.decode() if isinstance(x, bytes) else str(x) for x in a.ravel())
        if a.dtype == object and a.size == 1:
            x = a.ravel()[0]
            return x.decode() if isinstance(x, bytes) else str(x)
        return None


def is_bemio(path) -> bool:
    """Whether `path` names a BEMIO HDF5 file by its suffix (``.h5``, ``.hdf5``)."""
    return Path(path).suffix.lower() in (".h5", ".hdf5")


def read_bemio(path, body_names=None, *, rho=None, g=None) -> xr.Dataset:
    """A BEMIO HDF5 file (module docstring) as the internal database (unchecked: through
    :func:`hydro.prepare.open_any_database` it gets the one database check).

    body_names: the bodies in ``body1 … bodyN`` order (default: each ``properties/name``).
    rho: the density the non-dimensional data are scaled with (default: the file's
    ``simulation_parameters/rho``; WEC-Sim scales them with its simulation's). g: must equal the
    file's (the coefficients depend on it through the wave number); default the file's.
    """
    from .formats import _rename_bodies
    from .nemoh import waterplane_part

    f = _File(path)
    try:
        return _read(f, body_names, rho, g, waterplane_part, _rename_bodies)
    finally:
        f.close()


def _read(f, body_names, rho, g, waterplane_part, rename):
    where = str(f.path)
    sp = "/simulation_parameters"
    rho_file = f.scalar(f"{sp}/rho", "water density, kg/m³")
    g_file = f.scalar(f"{sp}/g", "gravity, m/s²")
    if f.has(f"{sp}/scaled"):
        scaled = f.scalar(f"{sp}/scaled", "0: data at full scale")
        if scaled != 0:
            raise ValueError(f"{where!r}: {sp}/scaled = {scaled:g}; accepted: 0 (data at full scale; "
                             "a Froude-scaled file is not supported: write it again from BEMIO with "
                             "scaled = 0)")
    rho = rho_file if rho is None else float(rho)
    if g is not None and not np.isclose(float(g), g_file, rtol=1e-4):
        raise ValueError(f"hydro.g = {g} differs from the {sp}/g = {g_file} of {where!r}: the "
                         "non-dimensional coefficients were computed with the file's g (through the "
                         f"wave number); drop hydro.g or set it to {g_file}")
    g = g_file
    omega = f.vector(f"{sp}/w", "wave frequencies, rad/s")
    beta_deg = f.vector(f"{sp}/wave_dir", "wave headings, degrees")
    depth_text = f.text(f"{sp}/water_depth")
    if depth_text is not None:
        if depth_text.strip().lower() not in ("infinite", "inf"):
            raise ValueError(f"{where!r}: {sp}/water_depth = {depth_text!r}; accepted: a number "
                             "(m) or 'infinite'")
        depth = np.inf
    elif f.has(f"{sp}/water_depth"):
        depth = f.scalar(f"{sp}/water_depth", "water depth, m")
        depth = np.inf if depth == 0 else depth      # python-BEMIO wrote 0 for deep water
    else:
        raise ValueError(f"{where!r}: no dataset {sp}/water_depth; accepted: a number (m) or the "
                         "string 'infinite'")

    bodies = sorted((int(b[4:]), b) for b in f.groups() if b.startswith("body") and b[4:].isdigit())
    if not bodies:
        raise ValueError(f"{where!r}: no group /body1; accepted: a BEMIO file with groups /body1 … "
                         "/bodyN")
    numbers = [n for n, _ in bodies]
    if numbers != list(range(1, len(bodies) + 1)):
        raise ValueError(f"{where!r}: body groups {[b for _, b in bodies]}; expected /body1 … "
                         f"/body{len(bodies)} without gaps")
    nb, nw, nh = len(bodies), len(omega), len(beta_deg)
    n = 6 * nb
    file_names = []
    A = np.zeros((nw, n, n))
    B = np.zeros((nw, n, n))
    Ainf = np.zeros((n, n))
    X = np.zeros((nw, nh, n), dtype=complex)
    parts = {"froude-krylov": np.zeros((nw, nh, n), dtype=complex),
             "scattering": np.zeros((nw, nh, n), dtype=complex)}
    have_parts = True
    C = np.zeros((n, n))
    W = np.zeros((n, n))
    vol, cob, ref = np.zeros(nb), np.zeros((nb, 3)), np.zeros((nb, 3))
    for k, (num, grp) in enumerate(bodies):
        b = f"/{grp}"
        name = f.text(f"{b}/properties/name")
        file_names.append((name or grp).strip().replace(_SEP, "_") or grp)
        if f.has(f"{b}/properties/dof"):
            dof = f.scalar(f"{b}/properties/dof", "degrees of freedom")
            if dof != 6:
                raise ValueError(f"{where!r}: {b}/properties/dof = {dof:g}; accepted: 6 (rigid-body "
                                 "modes; generalised body modes are not supported)")
        if f.has(f"{b}/properties/dof_start"):
            start = f.scalar(f"{b}/properties/dof_start", "first dof")
            if start != 6 * k + 1:
                raise ValueError(f"{where!r}: {b}/properties/dof_start = {start:g}; expected "
                                 f"{6 * k + 1} (6 rigid-body dofs per body, bodies in order)")
        o = 6 * k
        hc = f"{b}/hydro_coeffs"
        a = f.array(f"{hc}/added_mass/all", (6, n, nw), "A/ρ: (6 dofs, 6 × bodies, frequencies)")
        A[:, o:o + 6, :] = rho * np.moveaxis(a, 2, 0)
        bb = f.array(f"{hc}/radiation_damping/all", (6, n, nw),
                     "B/(ρω): (6 dofs, 6 × bodies, frequencies)")
        B[:, o:o + 6, :] = rho * omega[:, None, None] * np.moveaxis(bb, 2, 0)
        Ainf[o:o + 6, :] = rho * f.array(f"{hc}/added_mass/inf_freq", (6, n), "A∞/ρ: (6 dofs, 6 × bodies)")

        def complex_part(grp_path, what):
            re = f.array(f"{grp_path}/re", (6, nh, nw), f"{what}: (6 dofs, headings, frequencies)")
            im = f.array(f"{grp_path}/im", (6, nh, nw), f"{what}: (6 dofs, headings, frequencies)")
            # e^{+iωt} → e^{−iωt}: conjugate; (dof, heading, ω) → (ω, heading, dof)
            return rho * g * np.transpose(re - 1j * im, (2, 1, 0))

        X[:, :, o:o + 6] = complex_part(f"{hc}/excitation", "X/(ρg)")
        for p in parts:
            key = f"{hc}/excitation/{p}"
            if have_parts and f.has(f"{key}/re") and f.has(f"{key}/im"):
                val = complex_part(key, f"{p} force/(ρg)")
                if np.all(np.isfinite(val)):
                    parts[p][:, :, o:o + 6] = val
                    continue
            have_parts = False
        Kn = f.array(f"{hc}/linear_restoring_stiffness", (6, 6), "C/(ρg) about cg")
        Cb = rho * g * Kn
        C[o:o + 6, o:o + 6] = Cb
        vol[k] = f.scalar(f"{b}/properties/disp_vol", "displaced volume, m³")
        cob[k] = _point(f, f"{b}/properties/cb", "centre of buoyancy, m")
        ref[k] = _point(f, f"{b}/properties/cg", "centre of gravity: the point the coefficients "
                        "are about, m")
        W[o:o + 6, o:o + 6] = waterplane_part(Cb, vol[k], cob[k], ref[k], ref[k], rho, g)

    labels = dof_labels(file_names)
    if len(set(file_names)) != nb:
        raise ValueError(f"{where!r}: body names {file_names} repeat; give distinct names with "
                         "[hydro] names = [...] or fix /bodyN/properties/name")
    mat = ("influenced_dof", "radiating_dof")
    fm = ("omega",) + mat
    ex = ("omega", "wave_direction", "influenced_dof")
    db = xr.Dataset(coords={"omega": omega, "wave_direction": np.deg2rad(beta_deg),
                            "body": file_names, "influenced_dof": labels, "radiating_dof": labels,
                            "axis": list(AXES)})
    db["added_mass"] = (fm, A)
    db["radiation_damping"] = (fm, B)
    db["added_mass_inf"] = (mat, Ainf)
    db["excitation"] = (ex, X)
    if have_parts:
        db["froude_krylov"] = (ex, parts["froude-krylov"])
        db["diffraction"] = (ex, parts["scattering"])
    db["hydrostatic_stiffness"] = (mat, C)
    db["hydrostatic_stiffness"].attrs["includes"] = (
        "BEMIO's linear_restoring_stiffness x rho g, about each body's cg: water-plane terms, "
        "rho g V (z_B - z_G) in 44/55, -rho g V (x_B - x_G), -rho g V (y_B - y_G) in 46/56")
    db["waterplane_stiffness"] = (mat, W)
    db["waterplane_stiffness"].attrs["includes"] = (
        "water-plane terms only (33, 34, 35, 44, 55, 45 about the reference point, the cg)")
    db["displaced_volume"] = (("body",), vol)
    db["center_of_buoyancy"] = (("body", "axis"), cob)
    db["reference_point"] = (("body", "axis"), ref)
    code = f.text("/bem_data/code")
    db.attrs = {
        "rho": float(rho), "g": float(g), "water_depth": float(depth), "convention": CONVENTION,
        "source": f"BEMIO HDF5 file {where} (BEM code: {code or 'not recorded'})",
        "bemio_file": where, "bemio_rho": float(rho_file),
        "bemio_conversion": ("A = rho A/rho, B = rho w B/(rho w), X = rho g conj(re + i im) "
                             "(exp(+i omega t) -> exp(-i omega t)), C = rho g C/(rho g); headings "
                             "deg -> rad"),
        "reference_point_source": "cg of each body (/bodyN/properties/cg): BEMIO's coefficients "
                                  "are about it",
        "added_mass_inf_source": "the file's added_mass/inf_freq",
        "date_read": datetime.now(timezone.utc).isoformat(timespec="seconds"),
    }
    if body_names is not None:
        names = [body_names] if isinstance(body_names, str) else list(body_names)
        if len(names) != nb:
            raise ValueError(f"names {names} ({len(names)}) do not match the {nb} bodies "
                             f"{file_names} of {where!r}")
        if names != file_names:
            db = rename(db, file_names, names)
    return db


def _point(f, key, what):
    a = f.array(key, what=what)
    if a.size != 3:
        raise ValueError(f"{str(f.path)!r}: dataset {key} has shape {a.shape}; expected 3 "
                         f"coordinates, (3, 1) ({what})")
    return a.ravel()


# ------------------------------------------------------------------------------------ writing
def solver_code(db: xr.Dataset) -> str:
    """The BEM solver of `db` as BEMIO's ``bem_data/code`` names it ("WAMIT", "NEMOH",
    "CAPYTAINE"), from its ``source`` attribute; "mfm" where none is recognised."""
    src = str(db.attrs.get("source", "")).lower() + " " + str(db.attrs.get("generated_by", "")).lower()
    for key, code in (("wamit", "WAMIT"), ("nemoh", "NEMOH"), ("capytaine", "CAPYTAINE"),
                      ("mfm hydro", "CAPYTAINE"), ("bemio", "BEMIO")):
        if key in src:
            return code
    return "mfm"


def restoring_about_reference(db: xr.Dataset) -> np.ndarray:
    """BEMIO's restoring matrix (N m per unit dof, 6 n × 6 n block diagonal) about each body's
    reference point P, with its centre of gravity taken there and m = ρV (WAMIT's .hst with
    G = P): the water-plane stiffness plus ρ g V (z_B − z_P) in 44 and 55, −ρ g V (x_B − x_P) in 46
    and −ρ g V (y_B − y_P) in 56 (the inverse of the reader's :func:`hydro.nemoh.waterplane_part`)."""
    rg = float(db.attrs["rho"]) * float(db.attrs["g"])
    C = np.array(db["waterplane_stiffness"].values, dtype=float)
    vol = np.asarray(db["displaced_volume"].values, dtype=float)
    d = (np.asarray(db["center_of_buoyancy"].values, dtype=float)
         - np.asarray(db["reference_point"].values, dtype=float))
    for k in range(len(vol)):
        o = 6 * k
        C[o + 3, o + 3] += rg * vol[k] * d[k, 2]
        C[o + 4, o + 4] += rg * vol[k] * d[k, 2]
        C[o + 3, o + 5] += -rg * vol[k] * d[k, 0]
        C[o + 4, o + 5] += -rg * vol[k] * d[k, 1]
    return C


def _irf_grid(omega):
    w = np.linspace(omega[0], omega[-1], IRF_N_OMEGA)
    wt = np.full(IRF_N_OMEGA, w[1] - w[0])          # trapezoid weights on the even grid
    wt[[0, -1]] *= 0.5
    return w, wt


def radiation_irf(db: xr.Dataset):
    """BEMIO's radiation impulse response: (t, w, K) with K(i, j, t) = (2/π) ∫ B_ij(ω)/ρ cos ωt dω,
    the trapezoid on :data:`IRF_N_OMEGA` even frequencies over the database's band (B linearly
    interpolated), t = 0 … :data:`IRF_T_END` s in :data:`IRF_N_T` instants."""
    om = np.asarray(db["omega"].values, dtype=float)
    B = np.asarray(db["radiation_damping"].values, dtype=float) / float(db.attrs["rho"])
    t = np.linspace(0.0, IRF_T_END, IRF_N_T)
    w, wt = _irf_grid(om)
    n = B.shape[1]
    Bw = np.stack([np.interp(w, om, B[:, i, j]) for i in range(n) for j in range(n)])
    K = (2.0 / np.pi) * (Bw * wt) @ np.cos(np.outer(w, t))
    return t, w, K.reshape(n, n, len(t))


def excitation_irf(db: xr.Dataset):
    """BEMIO's excitation impulse response: (t, w, K) with K(i, β, t) = (1/π) ∫ (X̄_re cos ωt −
    X̄_im sin ωt) dω, X̄ = conj(X)/(ρ g) (BEMIO's e^{+iωt} amplitudes), t = −IRF_T_END … IRF_T_END."""
    om = np.asarray(db["omega"].values, dtype=float)
    Xb = np.conj(np.asarray(db["excitation"].values)) / (float(db.attrs["rho"]) * float(db.attrs["g"]))
    t = np.linspace(-IRF_T_END, IRF_T_END, IRF_N_T)
    w, wt = _irf_grid(om)
    nh, n = Xb.shape[1], Xb.shape[2]
    re = np.stack([np.interp(w, om, Xb[:, h, i].real) for i in range(n) for h in range(nh)])
    im = np.stack([np.interp(w, om, Xb[:, h, i].imag) for i in range(n) for h in range(nh)])
    K = (1.0 / np.pi) * ((re * wt) @ np.cos(np.outer(w, t)) - (im * wt) @ np.sin(np.outer(w, t)))
    return t, w, K.reshape(n, nh, len(t))


class _Writer:
    """Datasets of a BEMIO file written through netCDF4: each array with its own dimensions in the
    root group (netCDF needs names for them), a 'description' and 'units' attribute as BEMIO's."""

    def __init__(self, nc):
        self.nc = nc
        self.dims = {}

    def _dim(self, size):
        name = f"bemio_dim_{size}"
        if name not in self.dims:
            self.nc.createDimension(name, size)
            self.dims[name] = size
        return name

    def _group(self, key):
        parts = [p for p in key.split("/") if p]
        g = self.nc
        for p in parts[:-1]:
            g = g.groups[p] if p in g.groups else g.createGroup(p)
        return g, parts[-1]

    def array(self, key, values, description, units):
        a = np.asarray(values, dtype=float)
        a = a.reshape(1, 1) if a.ndim == 0 else a
        g, name = self._group(key)
        # repeated sizes share a dimension (a dataset of shape (6, 6) uses one twice: allowed)
        v = g.createVariable(name, "f8", tuple(self._dim(s) for s in a.shape))
        v[...] = a
        v.setncattr("description", description)
        v.setncattr("units", units)

    def text(self, key, value):
        g, name = self._group(key)
        v = g.createVariable(name, str, ())
        v[...] = np.array(value, dtype=object)


def write_bemio(db: xr.Dataset, path, *, code: str = "mfm") -> Path:
    """Write the database `db` as a BEMIO HDF5 file at `path` (module docstring: WEC-Sim's
    readBEMIOH5 reads it, SEA-Stack/HydroChrono too), atomically (a temporary file beside `path`
    renamed over it). `db` passes the one database check first (:func:`hydro.database.validate`).
    What BEMIO has no place for is not written: ``added_mass_zero``, the provenance attributes.
    `code`: the ``/bem_data/code`` string. Returns `path`."""
    import netCDF4

    from .database import validate

    validate(db, warn=False)
    path = Path(path)
    if path.suffix.lower() not in (".h5", ".hdf5"):
        raise ValueError(f"out: {str(path)!r}: a BEMIO file is HDF5; give a path ending in .h5")
    rho, g = float(db.attrs["rho"]), float(db.attrs["g"])
    rg = rho * g
    om = np.asarray(db["omega"].values, dtype=float)
    beta = np.rad2deg(np.atleast_1d(np.asarray(db["wave_direction"].values, dtype=float)))
    names = [str(b) for b in db["body"].values]
    nb, nw, nh = len(names), len(om), len(beta)
    n = 6 * nb
    A = np.asarray(db["added_mass"].values, dtype=float) / rho
    B = np.asarray(db["radiation_damping"].values, dtype=float) / (rho * om[:, None, None])
    Ainf = np.asarray(db["added_mass_inf"].values, dtype=float) / rho
    Xb = {"excitation": np.conj(np.asarray(db["excitation"].values)) / rg}
    split = "froude_krylov" in db and "diffraction" in db
    for key, var in (("froude-krylov", "froude_krylov"), ("scattering", "diffraction")):
        Xb[key] = (np.conj(np.asarray(db[var].values)) / rg if split
                   else np.full((nw, nh, n), np.nan + 1j * np.nan))
    C = restoring_about_reference(db) / rg
    vol = np.asarray(db["displaced_volume"].values, dtype=float)
    cob = np.asarray(db["center_of_buoyancy"].values, dtype=float)
    ref = np.asarray(db["reference_point"].values, dtype=float)
    depth = float(db.attrs["water_depth"])
    rt, rw, rK = radiation_irf(db)
    et, ew, eK = excitation_irf(db)

    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        with netCDF4.Dataset(tmp, "w", format="NETCDF4") as nc:
            w = _Writer(nc)
            w.text("/bem_data/code", code)
            for k, name in enumerate(names):
                w.text(f"/body{k + 1}/properties/name", name)
            sp = "/simulation_parameters"
            if np.isinf(depth):
                w.text(f"{sp}/water_depth", "infinite")
            w.array(f"{sp}/scaled", 0.0, "", "")
            w.array(f"{sp}/g", g, "Gravitational acceleration", "m/s^2")
            w.array(f"{sp}/rho", rho, "Water density", "kg/m^3")
            w.array(f"{sp}/T", (2 * np.pi / om)[:, None], "Wave periods", "s")
            w.array(f"{sp}/w", om[:, None], "Wave frequencies", "rad/s")
            if not np.isinf(depth):
                w.array(f"{sp}/water_depth", depth, "Water depth", "m")
            w.array(f"{sp}/wave_dir", beta[:, None], "Wave direction", "deg")
            for k in range(nb):
                b, o = f"/body{k + 1}", 6 * k
                rows = slice(o, o + 6)
                w.array(f"{b}/properties/body_number", k + 1, "Number of rigid body from the BEM "
                        "simulation", "")
                w.array(f"{b}/properties/cb", cob[k][:, None], "Center of buoyancy", "m")
                w.array(f"{b}/properties/cg", ref[k][:, None], "Center of gravity (the point the "
                        "coefficients are about: the database's reference point)", "m")
                w.array(f"{b}/properties/disp_vol", vol[k], "Displaced volume", "m^3")
                w.array(f"{b}/properties/dof", 6, "Degrees of freedom", "")
                w.array(f"{b}/properties/dof_start", o + 1, "Degrees of freedom", "")
                w.array(f"{b}/properties/dof_end", o + 6, "Degrees of freedom", "")
                hc = f"{b}/hydro_coeffs"
                w.array(f"{hc}/linear_restoring_stiffness", C[rows, rows],
                        "Hydrostatic stiffness matrix (normalized by rho*g)", "N/m")
                w.array(f"{hc}/added_mass/inf_freq", Ainf[rows, :],
                        "Infinite frequency added mass (normalized by rho)", "kg")
                # (ω, i, j) → (i of this body, j, ω): the order MATLAB's permute(A, [3 2 1]) shows
                w.array(f"{hc}/added_mass/all", np.transpose(A[:, rows, :], (1, 2, 0)),
                        "Added mass (normalized by rho)", "kg")
                for key, grp, label in (("excitation", "excitation", "excitation"),
                                        ("froude-krylov", "excitation/froude-krylov", "Froude-Krylov"),
                                        ("scattering", "excitation/scattering", "scattering")):
                    x = np.transpose(Xb[key][:, :, rows], (2, 1, 0))      # (dof, heading, ω)
                    norm = " (normalized by rho*g)"
                    w.array(f"{hc}/{grp}/im", x.imag, f"Imaginary component of {label} force{norm}", "N")
                    w.array(f"{hc}/{grp}/mag", np.abs(x), f"Magnitude of {label} force{norm}", "N")
                    w.array(f"{hc}/{grp}/phase", np.angle(x), f"Phase angle of {label} force", "rad")
                    w.array(f"{hc}/{grp}/re", x.real, f"Real component of {label} force{norm}", "N")
                ir = f"{hc}/excitation/impulse_response_fun"
                w.array(f"{ir}/f", eK[rows], "Impulse response function", "")
                w.array(f"{ir}/t", et[:, None], "Time vector for the impulse resonse function", "s")
                w.array(f"{ir}/w", ew[:, None], "Interpolated frequencies used to compute the "
                        "impulse response function", "rad/s")
                w.array(f"{hc}/radiation_damping/all", np.transpose(B[:, rows, :], (1, 2, 0)),
                        "Radiation damping (normalized by rho*w)", "N-s/m")
                ir = f"{hc}/radiation_damping/impulse_response_fun"
                w.array(f"{ir}/K", rK[rows], "Impulse response function", "")
                w.array(f"{ir}/t", rt[:, None], "Time vector for the impulse resonse function", "s")
                w.array(f"{ir}/w", rw[:, None], "Interpolated frequencies used to compute the "
                        "impulse response function", "rad/s")
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


__all__ = ["read_bemio", "write_bemio", "is_bemio", "solver_code", "radiation_irf", "excitation_irf",
           "restoring_about_reference", "IRF_T_END", "IRF_N_T", "IRF_N_OMEGA"]
