"""Reader of WAMIT output (.1, .3, .hst, .out, and the mean drift .8 / .9) into the internal
hydro database.

Non-dimensionalisation (WAMIT user manual, "Definitions of nondimensional quantities"), with
L = ULEN and k, m set by the modes (translations 1–3, rotations 4–6 of each body):

    A_ij = rho L^k Ā_ij,        B_ij = rho omega L^k B̄_ij,   k = 3, 4, 5 for i, j both
                                                              translations / mixed / both rotations
    X_i  = rho g a L^m X̄_i,     m = 2 (force), 3 (moment)   (a: wave amplitude, here 1 m)
    C_ij = rho g L^k C̄_ij,      k = 2, 3, 4 for 0, 1, 2 rotational modes among (i, j)
    D_i  = rho g L^k D̄_i,       k = 1 (force), 2 (moment)   (mean drift per unit amplitude²:
                                                              F_i = rho g a² L^k D̄_i)

Mean drift (WAMIT manual, numeric output files .8 "momentum" (far field: surge, sway, yaw only;
the force on all bodies together) and .9 "pressure" (near field, every mode of every body)): rows
``PER BETA1 BETA2 I Mod Pha Re Im``, the mean force of the bichromatic pair of headings β1, β2
(degrees) at one frequency. Only the rows with β1 = β2 are read (the unidirectional mean drift,
real: its Im is round-off); they become ``mean_drift`` (omega, wave_direction, influenced_dof),
N/m² and N m/m², the mean force on the body (WAMIT's sign: along the mode's axis) with the
motions WAMIT solved for (freely floating or fixed: the .out's run, recorded in the attrs as
"as in the WAMIT run"). Modes a file does not give are 0 (the attrs list the given ones).

Period conventions of the .1 file: period −1 is the zero-frequency limit (A_0, "Wave period =
infinite" in the .out), period 0 the infinite-frequency limit (A_inf, "Wave period = zero"); the
first column is the wave period in seconds (IPERIN = 1, the default; `first_column="omega"`
reads files written with radian frequencies instead).

Phase convention. WAMIT uses time dependence e^{+i omega t}: F(t) = Re[X e^{+i omega t}] for the
incident wave whose elevation at the origin is Re[a e^{+i omega t}] (crest at the origin at
t = 0). The internal convention is e^{−i omega t} with the same wave (eta at the origin
Re[a e^{−i omega t}] = a cos(omega t)), so X_internal = conj(X_WAMIT): then
Re[conj(X) e^{−i omega t}] = Re[X e^{+i omega t}], the same force history. Check on RM3: the surge
force of a long wave leads the elevation by +90° in WAMIT (fluid acceleration ∝ d/dt cos) and
lags by −90° after conjugation, as capytaine gives. A and B are real and need no conversion.

Hydrostatics. WAMIT's .hst is the "hydrostatic and gravitational restoring" matrix about the body
origin (XBODY, YBODY, ZBODY), coordinates of the .out relative to that origin (checked on RM3: the
spar's centre of buoyancy is reported at z = +5.686 m, above its origin 21.29 m below the water):

    C33 = rho g ∫n3 dS, C34 = rho g ∫y n3 dS, C35 = −rho g ∫x n3 dS, C45 = −rho g ∫xy n3 dS
    C44 = rho g ∫y² n3 dS + rho g V z_B − m g z_G,  C55 = rho g ∫x² n3 dS + rho g V z_B − m g z_G
    C46 = −rho g V x_B + m g x_G,                   C56 = −rho g V y_B + m g y_G

with m = rho V (WAMIT's default for a freely floating body). ``hydrostatic_stiffness`` keeps the
.hst as given (attrs say so). ``waterplane_stiffness`` removes rho g V (z_B − z_G) from C44 and
C55, drops C46/C56 (and any other entry) and keeps only the water-plane terms 33, 34/43, 35/53,
44, 55, 45/54. For rm3.out the centres of gravity are at the body origins (Z_G = 0), so the
m g z_G part is zero there: C44_hst(float) = 7347.0 = ∫y² dA + V z_B = 7762.7 − 725.83 · 0.5727
(ρg = 1 units), i.e. only the buoyancy term rho g V z_B is removed.

Multi-body modes are numbered i = 6 (n − 1) + mode for body n; generalised modes (NEWMDS) are not
supported. Bodies get the names `body_names` or "body0", "body1", …; RM3: ["float", "spar"].
"""
from __future__ import annotations

import re
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import xarray as xr

from .database import AXES, CONVENTION, dof_labels

_NUM = r"[-+]?\d*\.?\d+(?:[EeDd][-+]?\d+)?"


def _paths(stem_or_paths):
    if isinstance(stem_or_paths, dict):
        paths = {k.lstrip("."): Path(v) for k, v in stem_or_paths.items()}
    else:
        stem = Path(stem_or_paths)
        if stem.suffix in (".1", ".3", ".hst", ".out", ".8", ".9"):
            stem = stem.with_suffix("")
        paths = {ext: stem.with_name(stem.name + "." + ext)
                 for ext in ("1", "3", "hst", "out", "8", "9")}
    for ext in ("1", "out"):
        if ext not in paths or not paths[ext].is_file():
            raise FileNotFoundError(f"WAMIT file .{ext} not found ({paths.get(ext)}); read_wamit needs "
                                    "the .1 (added mass, damping) and .out (bodies, units) files.")
    return {k: v for k, v in paths.items() if v.is_file()}


def _rows(path, ncol_min, *, lines=False):
    """The numeric rows of a WAMIT numeric output file (.1, .3, .hst).

    Text lines before the first numeric row are headers. After it, every non-blank line must be
    a row of at least `ncol_min` finite numbers: a NaN/inf token, a word, or a line cut short
    (a truncated file) is an error naming the file, the line and what was expected, instead of
    a row silently dropped or a NaN that surfaces later deep inside the solver.
    With ``lines=True`` also returns the 1-based line number of each row.
    """
    fast = _rows_fast(path, ncol_min)
    if fast is not None:
        return fast if lines else fast[0]
    rows, numbers = [], []
    with open(path, errors="replace") as f:
        for n, line in enumerate(f, 1):
            parts = line.split()
            if not parts:
                continue
            try:
                vals = [float(p.replace("D", "E").replace("d", "e")) for p in parts]
            except ValueError:
                if not rows:
                    continue                               # header lines
                raise ValueError(f"{path}, line {n}: {line.strip()!r} is not a row of numbers "
                                 f"(expected at least {ncol_min} numbers per line, as on line "
                                 f"{numbers[-1]}); the file is damaged or truncated: re-export "
                                 "it from WAMIT") from None
            if not all(np.isfinite(vals)):
                raise ValueError(f"{path}, line {n}: {line.strip()!r} holds a non-finite value "
                                 "(NaN or inf); WAMIT writes finite numbers only: the file was "
                                 "edited or damaged; re-export it from WAMIT")
            if len(vals) < ncol_min:
                if not rows:
                    continue                               # a numeric header (e.g. a count)
                raise ValueError(f"{path}, line {n}: {line.strip()!r} has {len(vals)} numbers; "
                                 f"expected at least {ncol_min} (the file looks truncated or "
                                 "damaged: re-export it from WAMIT)")
            rows.append(vals)
            numbers.append(n)
    if not rows:
        raise ValueError(f"{path}: no rows of at least {ncol_min} numbers; is this a WAMIT numeric "
                         "output file (.1, .3, .hst)?")
    return (rows, numbers) if lines else rows


def parse_out(path) -> dict:
    """Gravity, ULEN, water depth, headings and per-body XBODY, volumes, centres from a WAMIT .out.

    Returns dict with keys g, ulen, water_depth (inf for "infinite"), rho (None unless stated),
    and bodies: list of dicts (xbody (4,), volumes (3,), cob (3,), cog (3,)); centres relative to
    the body origin.
    """
    text = Path(path).read_text(errors="replace")
    out = {"rho": None}
    m = re.search(rf"Gravity:\s*({_NUM})", text)
    out["g"] = float(m.group(1)) if m else None
    m = re.search(rf"Length scale:\s*({_NUM})", text)
    out["ulen"] = float(m.group(1)) if m else 1.0
    m = re.search(rf"Water depth:\s*(infinite|{_NUM})", text)
    out["water_depth"] = float("inf") if (m is None or m.group(1) == "infinite") else float(m.group(1))
    m = re.search(rf"(?:density|RHO)\s*[:=]\s*({_NUM})", text, re.IGNORECASE)
    if m:
        out["rho"] = float(m.group(1))
    bodies = []
    for blk in re.split(r"Body number:\s*N=\s*", text)[1:]:
        blk = blk.split("Output from  WAMIT")[0]

        def vec(label, n):
            mm = re.search(label + r"[^:\n]*:?\s*" + r"\s+".join([f"({_NUM})"] * n), blk)
            if mm is None:
                raise ValueError(f"{path}: no '{label}' line in a body block of the .out")
            return np.array([float(x) for x in mm.groups()])

        xb = re.search(rf"XBODY\s*=\s*({_NUM})\s*YBODY\s*=\s*({_NUM})\s*ZBODY\s*=\s*({_NUM})"
                       rf"\s*PHIBODY\s*=\s*({_NUM})", blk)
        if xb is None:
            raise ValueError(f"{path}: no XBODY line in a body block of the .out")
        bodies.append({"xbody": np.array([float(x) for x in xb.groups()]),
                       "volumes": vec(r"Volumes \(VOLX,VOLY,VOLZ\)", 3),
                       "cob": vec(r"Center of Buoyancy \(Xb,Yb,Zb\)", 3),
                       "cog": vec(r"Center of Gravity\s+\(Xg,Yg,Zg\)", 3)})
    if not bodies:
        raise ValueError(f"{path}: no 'Body number: N=' blocks; is this a WAMIT .out file?")
    out["bodies"] = bodies
    return out


def _k_matrix(n):
    """Exponent k of L for A/B (3 + number of rotational modes among i, j), n dofs."""
    rot = (np.arange(n) % 6) >= 3
    return 3 + rot[:, None].astype(int) + rot[None, :].astype(int)


def read_wamit(stem_or_paths, rho: float = 1000.0, g: float = 9.81, body_names=None, *,
               first_column: str = "period", drift: str | None = "auto") -> xr.Dataset:
    """Read WAMIT .1/.3/.hst/.out files into the internal database (see module docstring).

    stem_or_paths: path stem ("…/rm3") or one of the files, or a dict {"1": path, "3": …,
    "hst": …, "out": …, "8": …, "9": …}. .3, .hst, .8 and .9 are optional (then no excitation /
    stiffness / mean drift variables).
    drift: which mean drift file becomes ``mean_drift``: "auto" (the .8 of a single body when
    present, being the far field's converged value in surge, sway and yaw; else the .9),
    "momentum" (.8), "pressure" (.9), or None (none read).
    rho (kg/m³) is used unless the .out states it; g (m/s²) is taken from the .out when given
    there (a mismatch with `g` raises). body_names: one name per body, default "body0", ….
    """
    if first_column not in ("period", "omega"):
        raise ValueError(f"first_column={first_column!r}; accepted: 'period', 'omega'.")
    if drift not in DRIFT_CHOICES:
        raise ValueError(f"drift={drift!r}; accepted: {DRIFT_CHOICES}.")
    paths = _paths(stem_or_paths)
    info = parse_out(paths["out"])
    if info["rho"] is not None:
        rho = info["rho"]
    if info["g"] is not None:
        if not np.isclose(info["g"], g, rtol=1e-4):
            raise ValueError(f"g={g} differs from the gravity {info['g']} stated in {paths['out']}: "
                             "the nondimensional data must be scaled with the run's g; pass g="
                             f"{info['g']}.")
        g = info["g"]
    L = info["ulen"]
    nb = len(info["bodies"])
    names = [f"body{k}" for k in range(nb)] if body_names is None else list(body_names)
    if len(names) != nb:
        raise ValueError(f"body_names={body_names!r} has {len(names)} names but {paths['out']} has "
                         f"{nb} bodies.")
    n = 6 * nb
    labels = dof_labels(names)
    k_ab = _k_matrix(n)

    # ---- .1: added mass and damping
    raw1, line1 = _rows(paths["1"], 4, lines=True)
    rows = np.array([r[:5] + [np.nan] * (5 - len(r[:5])) for r in raw1])
    col0, ii, jj = rows[:, 0], rows[:, 1].astype(int) - 1, rows[:, 2].astype(int) - 1
    # rows at a finite frequency carry A and B (5 numbers); only the ω = 0 / ∞ rows carry A alone
    regular = col0 > 0
    short = np.flatnonzero(regular & np.isnan(rows[:, 4]))
    if short.size:
        k = int(short[0])
        raise ValueError(f"{paths['1']}, line {line1[k]}: {raw1[k]} has {len(raw1[k])} numbers; a "
                         f"row at a finite {first_column} needs 5 ({first_column}, i, j, added "
                         "mass, damping): the file looks truncated or damaged; re-export it from "
                         "WAMIT")
    if ii.max() >= n or jj.max() >= n:
        raise ValueError(f"{paths['1']}: mode index {max(ii.max(), jj.max()) + 1} > 6 × {nb} bodies; "
                         "generalised modes are not supported.")

    def matrix_at(mask, col):
        M = np.zeros((n, n))
        M[ii[mask], jj[mask]] = rows[mask, col]
        return M

    if first_column == "period":
        special = {"zero": col0 == -1.0, "inf": col0 == 0.0}
        reg = col0 > 0
        omega_of = lambda c: 2.0 * np.pi / c                              # noqa: E731
    else:
        special = {"zero": col0 == 0.0, "inf": col0 == -1.0}
        reg = col0 > 0
        omega_of = lambda c: c                                            # noqa: E731
    keys = np.unique(col0[reg])
    _check_complete(paths["1"], col0, np.stack([ii, jj], axis=1), "(i, j) pairs", line1)
    omega = omega_of(keys)
    order = np.argsort(omega)
    keys, omega = keys[order], omega[order]
    scale_a = rho * L ** k_ab
    A = np.stack([matrix_at(col0 == c, 3) for c in keys]) * scale_a
    B = np.stack([matrix_at(col0 == c, 4) for c in keys]) * scale_a * omega[:, None, None]
    if not np.any(special["inf"]):
        raise ValueError(f"{paths['1']} has no infinite-frequency rows (period 0): rerun WAMIT with "
                         "period 0 in the period list to get A_inf (required).")

    ds = xr.Dataset(coords={"omega": omega, "body": names, "influenced_dof": labels,
                            "radiating_dof": labels, "axis": list(AXES)})
    fm = ("omega", "influenced_dof", "radiating_dof")
    ds["added_mass"] = (fm, A)
    ds["radiation_damping"] = (fm, B)
    ds["added_mass_inf"] = (fm[1:], matrix_at(special["inf"], 3) * scale_a)
    if np.any(special["zero"]):
        ds["added_mass_zero"] = (fm[1:], matrix_at(special["zero"], 3) * scale_a)

    # ---- .3: excitation (period, heading deg, i, |X|, phase deg, Re, Im)
    if "3" in paths:
        raw3, line3 = _rows(paths["3"], 7, lines=True)
        r3 = np.array([r[:7] for r in raw3])
        om3 = omega_of(r3[:, 0])
        heads = np.unique(r3[:, 1])
        # every (period, heading) must hold the same modes: a file cut at a line end still parses
        _check_complete(paths["3"], r3[:, 0] + 1j * r3[:, 1], r3[:, 2:3].astype(int), "modes", line3)
        if not np.allclose(np.unique(om3), omega, rtol=1e-6):
            raise ValueError(f"{paths['3']}: its frequencies differ from those of {paths['1']}.")
        X = np.zeros((len(omega), len(heads), n), dtype=complex)
        io = np.searchsorted(omega, om3 * (1 - 1e-9))
        ih = np.searchsorted(heads, r3[:, 1])
        im = r3[:, 2].astype(int) - 1
        rot = (im % 6) >= 3
        X[io, ih, im] = (r3[:, 5] - 1j * r3[:, 6]) * rho * g * L ** (2 + rot)     # conj: e^{+iωt} → e^{-iωt}
        ds = ds.assign_coords(wave_direction=np.deg2rad(heads))
        ds["excitation"] = (("omega", "wave_direction", "influenced_dof"), X)

    # ---- .out bodies: reference points, volumes, centres (inertial axes)
    xb = np.array([b["xbody"] for b in info["bodies"]])
    if np.any(xb[:, 3] != 0):
        raise ValueError(f"{paths['out']}: PHIBODY ≠ 0 ({xb[:, 3]}) is not supported: the modes would be "
                         "in rotated body axes, not inertial axes.")
    ref = xb[:, :3]
    vol = np.array([b["volumes"][2] for b in info["bodies"]]) * L ** 3
    cob_rel = np.array([b["cob"] for b in info["bodies"]]) * L
    cog_rel = np.array([b["cog"] for b in info["bodies"]]) * L
    ds["reference_point"] = (("body", "axis"), ref)
    ds["displaced_volume"] = (("body",), vol)
    ds["center_of_buoyancy"] = (("body", "axis"), ref + cob_rel)
    # ---- .hst: hydrostatics and the water-plane part
    if "hst" in paths:
        raw_h, line_h = _rows(paths["hst"], 3, lines=True)
        rh = np.array([r[:3] for r in raw_h])
        _check_hst(paths["hst"], rh, line_h, n, nb)
        C = np.zeros((n, n))
        C[rh[:, 0].astype(int) - 1, rh[:, 1].astype(int) - 1] = rh[:, 2]
        C = C * rho * g * L ** (k_ab - 1)
        ds["hydrostatic_stiffness"] = (fm[1:], C)
        ds["hydrostatic_stiffness"].attrs["includes"] = (
            "WAMIT .hst as given: water-plane terms, rho g V z_B in C44/C55 and -rho g V x_B, "
            "-rho g V y_B in C46/C56, and the gravity terms -m g z_G (C44/C55), +m g x_G, +m g y_G "
            "(C46/C56) with m = rho V; z_B, z_G relative to each body origin")
        W = np.zeros((n, n))
        for b in range(nb):
            o = 6 * b
            Cb = C[o:o + 6, o:o + 6]
            V = vol[b]
            zb, zg = cob_rel[b, 2], cog_rel[b, 2]
            wp = {(2, 2): Cb[2, 2],
                  (2, 3): _pair(Cb, 2, 3), (2, 4): _pair(Cb, 2, 4), (3, 4): _pair(Cb, 3, 4),
                  (3, 3): Cb[3, 3] - rho * g * V * (zb - zg),
                  (4, 4): Cb[4, 4] - rho * g * V * (zb - zg)}
            for (i, j), v in wp.items():
                W[o + i, o + j] = W[o + j, o + i] = v
        ds["waterplane_stiffness"] = (fm[1:], W)
        ds["waterplane_stiffness"].attrs["includes"] = (
            "water-plane terms only (C33, C34, C35, C44, C55, C45 about the body origin); "
            "rho g V (z_B - z_G) removed from C44/C55, C46/C56 dropped")

    # ---- .8 / .9: mean drift
    ext = _drift_file(paths, drift, nb)
    if ext is not None:
        D, given = _read_drift(paths[ext], omega_of, omega, n, nb, rho, g, L,
                               None if "3" not in paths else heads)
        if "wave_direction" not in ds.coords:
            ds = ds.assign_coords(wave_direction=np.deg2rad(D["heads"]))
        ds["mean_drift"] = (("omega", "wave_direction", "influenced_dof"), D["values"])
        ds["mean_drift"].attrs.update({
            "units": "N/m^2 (forces), N m/m^2 (moments): mean force per unit wave amplitude squared",
            "method": ("far field (WAMIT .8, momentum conservation)" if ext == "8" else
                       "near field (WAMIT .9, pressure integration)"),
            "motions": "as in the WAMIT run (see its .out: freely floating or fixed)",
            "dofs": ", ".join(labels[i] for i in given), "file": str(paths[ext])})

    ds.attrs = {
        "rho": float(rho), "g": float(g), "water_depth": float(info["water_depth"]),
        "convention": CONVENTION, "source": "hydro.wamit.read_wamit",
        "wamit_files": ", ".join(str(p) for p in paths.values()),
        "wamit_ulen": float(L), "wamit_first_column": first_column,
        "wamit_conversion": "complex amplitudes conjugated (WAMIT exp(+i omega t) -> exp(-i omega t))",
        "wamit_center_of_gravity": "; ".join(
            f"{nm}: {np.array2string(ref[b] + cog_rel[b], precision=6)}" for b, nm in enumerate(names)),
        "date_read": datetime.now(timezone.utc).isoformat(timespec="seconds"),
    }
    return ds


DRIFT_CHOICES = ("auto", "momentum", "pressure", None)


def _drift_file(paths, drift, nb):
    """The extension ("8", "9") of the mean drift file to read, or None."""
    if drift is None:
        return None
    if drift == "momentum" or (drift == "auto" and "8" in paths and nb == 1):
        if "8" not in paths:
            raise FileNotFoundError(f"drift='momentum' needs the WAMIT .8 file beside the .1 "
                                    f"({paths['1'].with_suffix('.8')}): not found")
        if nb != 1:
            raise ValueError(f"drift='momentum': {paths['8']} holds the far-field drift of all "
                             f"{nb} bodies together, which cannot be split among them; use "
                             "drift='pressure' (the .9, per body)")
        return "8"
    if drift == "pressure" and "9" not in paths:
        raise FileNotFoundError(f"drift='pressure' needs the WAMIT .9 file beside the .1 "
                                f"({paths['1'].with_suffix('.9')}): not found")
    return "9" if "9" in paths else None


def _read_drift(path, omega_of, omega, n, nb, rho, g, L, heads):
    """``mean_drift`` values (n_ω, n_β, n) and the dof modes given, from a WAMIT .8 or .9 file
    (rows PER BETA1 BETA2 I Mod Pha Re Im; D_i = rho g L^k Re, k = 1 force, 2 moment)."""
    raw, lines = _rows(path, 8, lines=True)
    r = np.array([x[:8] for x in raw])
    same = np.isclose(r[:, 1], r[:, 2], atol=1e-9)
    if not same.any():
        raise ValueError(f"{path}: no rows with BETA1 = BETA2 (the unidirectional mean drift); "
                         "rerun WAMIT with the mean drift of each heading with itself")
    r, lines = r[same], [ln for ln, s_ in zip(lines, same) if s_]
    om = omega_of(r[:, 0])
    uo = np.unique(om)
    if uo.shape != omega.shape or not np.allclose(uo, omega, rtol=1e-6):
        raise ValueError(f"{path}: its {uo.size} frequencies ({uo.min():.6g}…{uo.max():.6g} rad/s) "
                         f"differ from the {omega.size} of the .1 file ({omega.min():.6g}…"
                         f"{omega.max():.6g} rad/s): re-export both from one run")
    h = np.unique(r[:, 1])
    if heads is not None and not (h.shape == heads.shape and np.allclose(h, heads, atol=1e-6)):
        raise ValueError(f"{path}: its headings {h.tolist()} degrees differ from those of the .3 "
                         f"file ({np.asarray(heads).tolist()}): re-export both from one run")
    im = r[:, 3].astype(int) - 1
    if im.min() < 0 or im.max() >= n:
        bad = int(np.argmax((im < 0) | (im >= n)))
        raise ValueError(f"{path}, line {lines[bad]}: mode {im[bad] + 1} is outside 1…{n} "
                         f"(6 modes × {nb} bodies); generalised modes are not supported")
    _check_complete(path, r[:, 0] + 1j * r[:, 1], im[:, None], "modes", lines)
    scale = max(1.0, float(np.max(np.abs(r[:, 6]))))
    if np.any(np.abs(r[:, 7]) > 1e-3 * scale):
        k = int(np.argmax(np.abs(r[:, 7])))
        raise ValueError(f"{path}, line {lines[k]}: Im = {r[k, 7]!r} at BETA1 = BETA2 (the mean "
                         f"drift is real; the largest Re is {scale:g}): the file is damaged")
    D = np.zeros((len(omega), len(h), n))
    io = np.searchsorted(omega, om * (1 - 1e-9))
    ih = np.searchsorted(h, r[:, 1])
    rot = (im % 6) >= 3
    D[io, ih, im] = r[:, 6] * rho * g * L ** (1 + rot.astype(int))
    return {"values": D, "heads": h}, sorted(set(int(i) for i in im))


def _rows_fast(path, ncol_min):
    """:func:`_rows` of a sound file in numpy (RM3's .1 and .3: 0.6 s of Python float() calls →
    0.06 s): (rows, line numbers), or None for anything :func:`_rows` must look at line by line
    (a word, a non-finite value or a short row after the first row: its error names the line)."""
    with open(path, errors="replace") as f:
        text = f.read().splitlines()
    first = None
    for n, line in enumerate(text):
        parts = line.split()
        if not parts:
            continue
        try:
            if len([float(p.replace("D", "E").replace("d", "e")) for p in parts]) >= ncol_min:
                first = n
                break
        except ValueError:
            continue
    if first is None:
        return None
    split = [ln.split() for ln in text[first:]]
    numbers = [first + 1 + k for k, parts in enumerate(split) if parts]
    split = [parts for parts in split if parts]
    counts = np.fromiter(map(len, split), int, len(split))
    if counts.min() < ncol_min:
        return None
    body = " ".join(" ".join(parts) for parts in split).replace("D", "E").replace("d", "e")
    try:
        values = np.array(body.split(), dtype=float)
    except ValueError:
        return None
    if not np.isfinite(values).all():
        return None
    ends = np.cumsum(counts).tolist()
    flat = values.tolist()
    rows = [flat[e - c:e] for e, c in zip(ends, counts.tolist())]
    return rows, numbers


def _check_hst(path, rh, lines, n, nb):
    """Raise unless the .hst lists every (i, j) of the n = 6 × n_bodies modes exactly once, as
    WAMIT writes it (the full matrix, zeros included): a file cut short at a line end still
    parses, and its missing entries (read as zeros) would take away the stiffness of the modes
    it lost without a word."""
    ij = rh[:, :2].astype(int)
    bad = (ij < 1) | (ij > n)
    if bad.any():
        k = int(np.argmax(bad.any(axis=1)))
        raise ValueError(f"{path}, line {lines[k]}: mode pair ({ij[k, 0]}, {ij[k, 1]}); accepted: "
                         f"modes 1 … {n} (6 per body, {nb} bodies in the .out)")
    seen = {}
    for (i, j), ln in zip(map(tuple, ij), lines):
        if (i, j) in seen:
            raise ValueError(f"{path}, line {ln}: entry ({i}, {j}) repeated (first on line "
                             f"{seen[(i, j)]}); the file is damaged: re-export it from WAMIT")
        seen[(i, j)] = ln
    if len(seen) != n * n:
        missing = [(i, j) for i in range(1, n + 1) for j in range(1, n + 1) if (i, j) not in seen]
        raise ValueError(
            f"{path}: {len(seen)} of the {n * n} entries (i, j = 1 … {n}: 6 modes × {nb} bodies) "
            f"after line {lines[-1]}; missing {missing[:4]}"
            f"{f' and {len(missing) - 4} more' if len(missing) > 4 else ''}. "
            "WAMIT writes the full matrix, zeros included: the file is cut short or damaged "
            "(its missing entries would be read as zero stiffness); re-export it from WAMIT")


def _check_complete(path, key, items, what, lines):
    """Raise unless every value of `key` (a period, or period + heading) lists the same `items`
    (rows of ints) once each: a WAMIT file cut short at a line end, or edited, still parses but
    leaves entries missing (read as zeros) — named here with its line instead."""
    if _complete_fast(key, items):
        return
    items = [tuple(int(v) for v in r) for r in np.asarray(items)]
    groups = {}
    for k, it, ln in zip(key, items, lines):
        groups.setdefault(k, []).append((it, ln))
    ref_key = max(groups, key=lambda k: len(groups[k]))
    ref = sorted(it for it, _ in groups[ref_key])
    for k, rows in groups.items():
        got = sorted(it for it, _ in rows)
        if got == ref:
            continue
        if len(got) != len(set(got)):
            dup = next(it for it in got if got.count(it) > 1)
            ln = next(n for it, n in rows if it == dup)
            raise ValueError(f"{path}, line {ln}: {what} {dup} repeated for the same period"
                             f"{'/heading' if np.iscomplexobj(key) else ''} ({k}); the file is damaged")
        if np.iscomplexobj(key) or any(np.iscomplexobj(x) for x in [k]):
            label = f"period {np.real(k):g} s, heading {np.imag(k):g} deg"
        else:
            label = f"period {k:g}"
        missing = sorted(set(ref) - set(got))
        # the (i, j) of the zero/infinite-frequency rows may legitimately differ: compare regular only
        if not np.iscomplexobj(key) and k <= 0:
            continue
        raise ValueError(f"{path}: {label} has {len(got)} {what}, other periods {len(ref)} (missing "
                         f"{missing[:4]}{'…' if len(missing) > 4 else ''}, last line {rows[-1][1]}): the "
                         "file is truncated or damaged; re-export it from WAMIT")


def _complete_fast(key, items) -> bool:
    """True when every value of ``key`` lists the same ``items`` once each (numpy: RM3's .1
    0.3 s → 0.01 s); False sends :func:`_check_complete` down its line-by-line path, which
    names what is missing or repeated (or allows what may differ)."""
    items = np.asarray(items).astype(int).reshape(len(key), -1)
    _, group, counts = np.unique(np.asarray(key), return_inverse=True, return_counts=True)
    if counts.min() != counts.max():
        return False
    order = np.lexsort(tuple(items.T[::-1]) + (group,))
    table = items[order].reshape(len(counts), counts[0], items.shape[1])
    if not (table == table[:1]).all():
        return False
    return counts[0] < 2 or bool(np.any(table[0, 1:] != table[0, :-1], axis=1).all())


def _pair(C, i, j):
    """A symmetric water-plane entry from the .hst (WAMIT may list only one of C_ij, C_ji)."""
    return C[i, j] if C[i, j] != 0.0 else C[j, i]
