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


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("wecsim", type=Path)
    ap.add_argument("--out", type=Path, default=Path("tests/data/bemio"))
    a = ap.parse_args()
    cut_nemoh(a.wecsim, a.out)
    cut_capytaine(a.wecsim, a.out)


if __name__ == "__main__":
    main()
