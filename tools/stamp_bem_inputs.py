"""Record the BEM-inputs key (``mfm_bem_inputs_sha256``, ``mfm_bem_inputs``) in shipped databases
made by ``mfm hydro`` before the key existed, without solving anything again.

A file is stamped only where its inputs are verified to be the config's: the hulls and
``[hydro.bem]`` table ``mfm hydro`` recorded in it equal the config's now
(:func:`mfm.io.bemgen.database_is_stale`), and the arrays and attributes of the solve itself agree
with what the config resolves to (the finite frequencies, the headings, depth, ρ, g, panel size,
lid, symmetry, A∞, deep_water_kh). Only attributes are written (netCDF4, in place); the data
variables are compared before and after, to the bit. A file that does not verify is named with
the reason and left alone.

    python tools/stamp_bem_inputs.py [--dry-run] [configs/*.toml]
"""
import argparse
import json
import math
import sys
from pathlib import Path

import netCDF4
import numpy as np
import xarray as xr

from mfm.io import bemgen


def verify(config):
    """(database path, key, record) or raise ValueError with the reason."""
    specs, kw, out = bemgen.config_bem_inputs(config)
    if out is None or out.suffix != ".nc" or not out.exists():
        raise ValueError(f"no NetCDF database at {out}")
    stale, why = bemgen.database_is_stale(config, out)
    if stale:
        raise ValueError(why)
    with xr.open_dataset(out) as ds:
        a = ds.attrs
        omega = ds["omega"].values
        heads = ds["wave_direction"].values
        checks = {
            "omega": np.array_equal(omega[np.isfinite(omega)], np.asarray(kw["omega"], float)),
            "infinite_frequency": bool(np.isinf(omega).any()) == kw["infinite_frequency"],
            "wave_directions": np.allclose(heads, kw["wave_directions"], rtol=0, atol=1e-12),
            "water_depth": float(a["water_depth"]) == kw["water_depth"],
            "rho": float(a["rho"]) == kw["rho"],
            "g": float(a["g"]) == kw["g"],
            "dx": float(a["dx"]) == kw["dx"],
            "lid": str(a["lid"]) == str(kw["lid"]),
            "symmetry": str(a["symmetry"]) == kw["symmetry"],
            "deep_water_kh": (kw["deep_water_kh"] is None and "deep_water_kh" not in a)
            or (kw["deep_water_kh"] is not None and float(a.get("deep_water_kh", math.nan))
                == kw["deep_water_kh"]),
            "no overrides": json.loads(a.get("mfm_overrides", "{}")) == {},
        }
    bad = [k for k, ok in checks.items() if not ok]
    if bad:
        raise ValueError(f"{out}: the stored solve differs from the config in {bad}")
    record = json.dumps(bemgen.bem_inputs(specs, kw), sort_keys=True, default=float)
    return out, bemgen.bem_inputs_key(specs, kw), record


def data_bits(path):
    with xr.open_dataset(path) as ds:
        ds.load()
        return {k: ds[k].values.copy() for k in ds.variables}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("configs", nargs="*")
    p.add_argument("--dry-run", action="store_true")
    args = p.parse_args(argv)
    configs = args.configs or sorted(str(c) for c in Path("configs").glob("*.toml"))
    failed = 0
    for config in configs:
        import tomllib
        hydro = tomllib.loads(Path(config).read_text()).get("hydro") or {}
        if "bem" not in hydro:
            continue
        try:
            out, key, record = verify(config)
        except ValueError as e:
            print(f"{config}: NOT stamped: {e}")
            failed += 1
            continue
        if args.dry_run:
            print(f"{config}: {out} verified, key {key[:12]}")
            continue
        before = data_bits(out)
        with netCDF4.Dataset(out, "a") as nc:
            nc.setncattr("mfm_bem_inputs_sha256", key)
            nc.setncattr("mfm_bem_inputs", record)
        after = data_bits(out)
        same = before.keys() == after.keys() and all(
            np.array_equal(before[k], after[k], equal_nan=before[k].dtype.kind in "fc")
            for k in before)
        print(f"{config}: {out} stamped, key {key[:12]}, data unchanged: {same}")
        failed += not same
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
