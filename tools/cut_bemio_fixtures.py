"""Cut the small BEM fixtures of tests/data/bemio from WEC-Sim's BEMIO examples (data only).

    python tools/cut_bemio_fixtures.py <WEC-Sim checkout or `git archive` extract> [--out tests/data/bemio]

Reads examples/BEMIO/{NEMOH,CAPYTAINE} of a WEC-Sim tree (https://github.com/WEC-Sim/WEC-Sim) and
writes a subset of their frequencies, the files otherwise byte for byte as the solvers wrote them:

- NEMOH result files (.tec): the header and each zone's rows kept verbatim, every STEP-th row of
  the first N_KEEP rows; the zone header's ``I=`` and the Nemoh.cal frequency line (count, min,
  max) rewritten to the kept rows, their spacing and comments untouched. Mesh/KH*.dat and
  Hydrostatics*.dat copied unchanged; meshes are not copied (not read).
- capytaine NetCDF: the same subset along ``omega`` (xarray isel), written back with the
  file's own variables, dims (the leading ``complex`` dim), coordinates and attributes; the
  hydrostatics files (KH_*.dat, Hydrostatics_*.dat) beside it copied unchanged.
- a BEMIO HDF5 file (``--bemio-h5 FILE``: the public sphere.h5 of NREL/HydroChrono, the same bytes
  as SEA-Stack's iea_sphere one): :func:`cut_bemio_h5`, every STEP-th frequency, each dataset's
  values verbatim at its path with its description/units; the python-BEMIO ``components`` copies,
  the impulse responses and the state-space fit left out (derived data the reader ignores). The
  full file's dataset paths and shapes go to ``sphere_layout.json`` beside it (the layout the
  writer is checked against). HDF5 is written through netCDF4 (hydro.bemio's writer of datasets).
"""
from __future__ import annotations

import argparse
import re
import shutil
from pathlib import Path

import numpy as np

# (source folder under examples/BEMIO, destination under --out, STEP, N_KEEP rows of the source)
NEMOH = [("NEMOH/NEMOH_v2.3/RM3", "nemoh_v2/rm3", 3, 130),        # 0.02 … 2.60 rad/s, 44 rows
         ("NEMOH/NEMOH_v3.0.2/Sphere", "nemoh_v3/sphere", 10, 420)]  # 0.02 … 8.22 rad/s, 42 rows
CAPYTAINE = [("CAPYTAINE/rm3/outputs/rm3_hydrodynamics.nc", "capytaine_2.3.1/rm3", 3, 130)]
RESULTS = ("RadiationCoefficients.tec", "ExcitationForce.tec", "FKForce.tec", "DiffractionForce.tec")


def _cut_tec(src: Path, dst: Path, step: int, n_keep: int) -> int:
    out, rows, kept = [], None, 0
    for line in src.read_text().splitlines(keepends=True):
        s = line.strip()
        if s.lower().startswith("zone"):
            rows = 0
            kept = len(range(0, n_keep, step))
            line = re.sub(r"(I\s*=\s*)(\d+)", lambda m: m.group(1) + f"{kept:>{len(m.group(2))}d}", line)
            out.append(line)
            continue
        if rows is None or not s or s.startswith('"'):
            out.append(line)
            continue
        if rows < n_keep and rows % step == 0:
            out.append(line)
        rows += 1
    dst.write_text("".join(out))
    return kept


def _cut_cal(src: Path, dst: Path, step: int, n_keep: int):
    text = src.read_text().splitlines(keepends=True)
    for k, line in enumerate(text):
        if "Number of wave frequencies" in line:
            head, _, comment = line.partition("!")
            toks = re.split(r"(\s+)", head)
            nums = [i for i, t in enumerate(toks) if t and not t.isspace()]
            v3 = len(nums) == 4
            i_n, i_lo, i_hi = (nums[1], nums[2], nums[3]) if v3 else (nums[0], nums[1], nums[2])
            n0, lo, hi = int(toks[i_n]), float(toks[i_lo]), float(toks[i_hi])
            grid = np.linspace(lo, hi, n0)[:n_keep:step]
            toks[i_n], toks[i_hi] = str(len(grid)), f"{grid[-1]:.2f}"
            text[k] = "".join(toks) + ("!" + comment if comment else "")
    dst.write_text("".join(text))


def cut_nemoh(root: Path, out: Path):
    for rel, dest, step, n_keep in NEMOH:
        src, dst = root / "examples" / "BEMIO" / rel, out / dest
        (dst / "Results").mkdir(parents=True, exist_ok=True)
        (dst / "Mesh").mkdir(exist_ok=True)
        _cut_cal(src / "Nemoh.cal", dst / "Nemoh.cal", step, n_keep)
        res = next(d for d in src.iterdir() if d.is_dir() and d.name.lower() == "results")
        for name in RESULTS:
            _cut_tec(res / name, dst / "Results" / name, step, n_keep)
        mesh = next(d for d in src.iterdir() if d.is_dir() and d.name.lower() == "mesh")
        for f in mesh.iterdir():
            if re.fullmatch(r"(kh|hydrostatics)(_\d+)?\.dat", f.name, re.IGNORECASE):
                shutil.copyfile(f, dst / "Mesh" / f.name)


def cut_capytaine(root: Path, out: Path):
    import xarray as xr

    for rel, dest, step, n_keep in CAPYTAINE:
        src = root / "examples" / "BEMIO" / rel
        dst = out / dest
        dst.mkdir(parents=True, exist_ok=True)
        with xr.open_dataset(src) as ds:
            ds.load().isel(omega=slice(0, n_keep, step)).to_netcdf(dst / src.name)
        for f in src.parent.iterdir():
            if re.fullmatch(r"(kh|hydrostatics)(_\d+)?\.dat", f.name, re.IGNORECASE):
                shutil.copyfile(f, dst / f.name)


BEMIO_STEP = 10                                     # 240 frequencies 0.05 … 12 → 24, 0.05 … 11.55
BEMIO_SKIP = ("components", "impulse_response_fun", "state_space")


def _h5_walk(g, prefix=""):
    """(path, netCDF4 variable) of every dataset under the group `g`, groups in file order."""
    for name, v in g.variables.items():
        yield f"{prefix}/{name}", v
    for name, sub in g.groups.items():
        yield from _h5_walk(sub, f"{prefix}/{name}")


def cut_bemio_h5(src: Path, dst: Path, step: int):
    """Every `step`-th frequency of the BEMIO file `src` into `dst` (module docstring), and the
    layout of `src` (every dataset's path and shape) into ``<dst stem>_layout.json``."""
    import json

    import netCDF4

    from hydro.bemio import _Writer

    dst.parent.mkdir(parents=True, exist_ok=True)
    with netCDF4.Dataset("src.h5", mode="r", memory=Path(src).read_bytes()) as nc:
        nc.set_auto_mask(False)
        layout = {p: list(v.shape) for p, v in _h5_walk(nc)}
        nw = nc["simulation_parameters/w"].shape[0]
        with netCDF4.Dataset(dst, "w", format="NETCDF4") as out:
            w = _Writer(out)
            for p, v in _h5_walk(nc):
                if any(part in BEMIO_SKIP for part in p.split("/")):
                    continue
                a = v[...]
                if isinstance(a, str) or (isinstance(a, np.ndarray) and a.dtype.kind in "OSU"):
                    w.text(p, a if isinstance(a, str) else str(np.asarray(a).ravel()[0]))
                    continue
                a = np.asarray(a)
                if p in ("/simulation_parameters/w", "/simulation_parameters/T"):
                    a = a[::step]                    # (N_ω, 1)
                elif a.ndim == 3 and a.shape[-1] == nw:
                    a = a[..., ::step]               # (dof, dof or heading, N_ω)
                attrs = {k: v.getncattr(k) for k in v.ncattrs()}
                w.array(p, a, attrs.get("description", ""), attrs.get("units", ""))
    lines = [f"{json.dumps(p)}: {json.dumps(shape)}" for p, shape in layout.items()]
    dst.with_name(dst.stem + "_layout.json").write_text("{\n" + ",\n".join(lines) + "\n}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("wecsim", type=Path)
    ap.add_argument("--out", type=Path, default=Path("tests/data/bemio"))
    ap.add_argument("--bemio-h5", type=Path, help="a public BEMIO .h5 (HydroChrono's sphere.h5)")
    a = ap.parse_args()
    cut_nemoh(a.wecsim, a.out)
    cut_capytaine(a.wecsim, a.out)
    if a.bemio_h5 is not None:
        cut_bemio_h5(a.bemio_h5, a.out / "bemio_h5" / "sphere.h5", BEMIO_STEP)


if __name__ == "__main__":
    main()
