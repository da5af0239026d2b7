"""Checks that a hydro database is the one a model means: the file can be read, and each config
body got its own hull's data (not a neighbour's, e.g. ``[hydro] names`` in the wrong order).

Nothing here imports mfm: the model builder passes plain numbers (masses, CoM positions).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: the first bytes of the NetCDF formats xarray reads: classic/64-bit ("CDF\x01", "CDF\x02",
#: "CDF\x05") and NetCDF-4 (HDF5 signature)
_MAGIC = (b"CDF\x01", b"CDF\x02", b"CDF\x05", b"\x89HDF\r\n\x1a\n")


def check_netcdf_file(path) -> Path:
    """Raise a clear error if `path` is not a readable NetCDF file (missing, empty, truncated at
    the header, or another format), naming the file and how to remake it; else return it.

    xarray's own message for these cases names neither the file nor the cause ("did not find a
    match in any of xarray's currently installed IO backends").
    """
    path = Path(path)
    remake = ("regenerate it with `mfm hydro CONFIG --force` (or restore it: `git checkout -- "
              f"{path}` for a shipped database)")
    if not path.exists():
        raise FileNotFoundError(f"hydro database {str(path)!r} not found; fix the path (relative "
                                f"to the config) or {remake}")
    if path.is_dir():
        raise IsADirectoryError(f"hydro database {str(path)!r} is a directory; give a .nc file")
    size = path.stat().st_size
    if size == 0:
        raise ValueError(f"hydro database {str(path)!r} is empty (0 bytes): an interrupted copy "
                         f"or download? {remake[0].upper() + remake[1:]}.")
    with open(path, "rb") as f:
        head = f.read(8)
    if not any(head.startswith(m) for m in _MAGIC):
        raise ValueError(f"hydro database {str(path)!r} ({size} bytes) is not a NetCDF file (it "
                         f"starts with {head!r}; NetCDF starts with b'CDF' or b'\\x89HDF'); "
                         f"{remake}. A WAMIT database is given by its .out file instead.")
    return path


# ------------------------------------------------------------------------------ body assignment
@dataclass(frozen=True)
class Finding:
    """One result of :func:`check_body_assignment`: ``kind`` is "swap" (two bodies got each
    other's data: an error) or "mismatch" (one body's data fits it poorly: a warning)."""
    kind: str
    bodies: tuple
    message: str

    def __str__(self):
        return self.message


def _cost(mass, com, volume, cob, rho, length):
    """How badly database hull data (volume, centre of buoyancy) fit a config body (mass, CoM):
    the CoM–CoB distance in units of the hull size, plus |ln(ρV/m)|. A floating body's CoB lies
    within about one hull size of its CoM and ρV is of the order of its mass (equal when it
    floats freely; a hinged or moored body carries some load, hence a log, not a tolerance)."""
    d = float(np.linalg.norm(np.asarray(com, float) - np.asarray(cob, float)))
    return d / length + abs(float(np.log(max(rho * volume, 1e-300) / mass)))


def check_body_assignment(db, bodies, *, rho: float | None = None) -> list[Finding]:
    """Check that each config body got the database data of its own hull.

    db: the hydro database (``displaced_volume`` (body), ``center_of_buoyancy`` (body, axis) in
        inertial axes at q = 0; ``rho`` attr).
    bodies: one ``(config_name, database_body, mass_kg, com_xyz_m)`` per wet body, the CoM in
        inertial axes at q = 0 (the config's ``com``); ``database_body`` may be a tuple of database
        bodies, the hulls of one rigid body (checked by their total volume and volume-weighted
        centre of buoyancy).
    rho: water density (kg/m³); default the database's ``rho`` attr, else 1000.

    Returns a list of :class:`Finding` (empty when all is well):

    - "swap": for a pair of bodies, the data fit much better exchanged (cost of the given pairing
      ≥ 3 × the exchanged one and ≥ 1 in absolute terms; cost = CoM–CoB distance / hull size +
      |ln(ρV/m)|). The message names both bodies, their masses and CoM, and the database volumes
      and CoB. This is what ``[hydro] names`` in the wrong order gives: raise it as an error.
    - "mismatch": one body whose CoB is more than 3 hull sizes from its CoM, or whose ρV is
      outside [m/4, 4 m]: a warning (a hinged or heavily moored body can be legitimately far
      from free floating, never that far).

    The hull size is V^(1/3) of the larger of the two database bodies compared (one body: its own).
    """
    if rho is None:
        rho = float(db.attrs.get("rho", 1000.0))
    names = [str(b) for b in db["body"].values]
    vol = dict(zip(names, np.asarray(db["displaced_volume"].values, dtype=float)))
    cob = dict(zip(names, np.asarray(db["center_of_buoyancy"].values, dtype=float)))
    rows = []
    for n, d, m, c in bodies:
        if isinstance(d, (tuple, list)):
            # a group of hulls on one rigid body: total volume, volume-weighted centre of buoyancy
            d = tuple(str(x) for x in d)
            if not all(x in vol for x in d):
                continue
            v = sum(vol[x] for x in d)
            vol[d] = v
            cob[d] = sum(vol[x] * cob[x] for x in d) / v
        rows.append((str(n), d if isinstance(d, tuple) else str(d), float(m), np.asarray(c, dtype=float)))
    out = []

    def desc(name, m, c):
        return f"config body {name!r}: mass {m:.6g} kg, CoM {np.round(c, 4).tolist()} m"

    def ddesc(d):
        return (f"database body {d!r}: displaced volume {vol[d]:.6g} m³ (ρV = {rho * vol[d]:.6g} "
                f"kg), centre of buoyancy {np.round(cob[d], 4).tolist()} m")

    for name, d, m, c in rows:
        if d not in vol:
            continue                       # the database's own check names missing bodies
        L = max(vol[d], 1e-12) ** (1 / 3)
        dist = float(np.linalg.norm(c - cob[d]))
        ratio = rho * vol[d] / m
        if dist > 3 * L or not 0.25 <= ratio <= 4.0:
            out.append(Finding("mismatch", (name,), (
                f"hydro: {desc(name, m, c)} got the data of {ddesc(d)}: CoM–CoB distance "
                f"{dist:.4g} m ({dist / L:.2g} hull sizes V^(1/3) = {L:.4g} m), ρV/m = {ratio:.3g}. "
                "A floating body's CoB is near its CoM and ρV near its mass; check [hydro] names "
                "(database bodies in file order) and [bodies.hydro] body.")))
    for a in range(len(rows)):
        for b in range(a + 1, len(rows)):
            (na, da, ma, ca), (nb, dbb, mb, cb) = rows[a], rows[b]
            if da == dbb or da not in vol or dbb not in vol:
                continue
            L = max(vol[da], vol[dbb]) ** (1 / 3)
            given = _cost(ma, ca, vol[da], cob[da], rho, L) + _cost(mb, cb, vol[dbb], cob[dbb], rho, L)
            swapped = _cost(ma, ca, vol[dbb], cob[dbb], rho, L) + _cost(mb, cb, vol[da], cob[da], rho, L)
            if given >= 1.0 and given >= 3.0 * swapped:
                out.append(Finding("swap", (na, nb), (
                    f"hydro: bodies {na!r} and {nb!r} look swapped: {desc(na, ma, ca)} got "
                    f"{ddesc(da)}; {desc(nb, mb, cb)} got {ddesc(dbb)}. Exchanged, the data fit "
                    f"{given / max(swapped, 1e-12):.3g}× better (CoM–CoB distance / hull size + "
                    f"|ln(ρV/m)|: {given:.3g} as given, {swapped:.3g} exchanged). Fix the order of "
                    "[hydro] names (WAMIT bodies in file order) or the [bodies.hydro] body keys.")))
    return out
