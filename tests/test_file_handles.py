"""Files a user holds open while mfm reads or writes them (issue 16): each case runs in its own
Python process, because the failure it guards against is a segmentation fault (exit 139 / −11),
which would kill the test runner itself.

The netCDF-C 4.10 / HDF5 2.2 libraries of the netCDF4 wheel crash when a file the process holds
open is opened a second time, read, closed and opened a third time (hydro/database.py, the note
above read_netcdf); and HDF5 truncates a file it opens for writing, so an in-place write over a
result a reader holds open destroys it and then fails.
"""
import os
import subprocess
import sys
import textwrap

import pytest
from conftest import ROOT

SPHERE_NC = ROOT / "hydro" / "data" / "sphere.nc"
SPHERE_TOML = ROOT / "configs" / "sphere.toml"


def run_python(code: str, cwd=ROOT, timeout=300):
    """Run `code` in a fresh interpreter that imports this checkout's mfm/hydro."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), JAX_PLATFORMS="cpu")
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)


def check(r, marker="DONE"):
    assert r.returncode == 0 and marker in r.stdout, (
        f"exit {r.returncode} (139 / -11: segmentation fault)\nstdout: {r.stdout[-2000:]}\n"
        f"stderr: {r.stderr[-3000:]}")


def test_database_held_open_then_model_loaded():
    # the two notebook steps: look at the shipped database, then load the model using it
    r = run_python(f"""
        import xarray as xr, mfm
        ds = xr.open_dataset({str(SPHERE_NC)!r})          # still open
        model = mfm.load({str(SPHERE_TOML)!r})
        assert model.hydro is not None
        assert float(ds.omega[0]) > 0                     # the user's handle still reads
        ds.close()
        print("DONE")
    """)
    check(r)


def test_hydro_readers_with_the_database_held_open():
    # every hydro reader of a NetCDF database, each several times, while the file is held open
    r = run_python(f"""
        import xarray as xr
        from hydro import bem, database, prepare
        ds = xr.open_dataset({str(SPHERE_NC)!r})
        for _ in range(3):
            a = prepare.open_any_database({str(SPHERE_NC)!r})
            b = bem.load({str(SPHERE_NC)!r})
            c = database.read_netcdf({str(SPHERE_NC)!r})
        assert a.sizes["omega"] == ds.sizes["omega"] - 1  # ω = ∞ moved into added_mass_inf
        ds.load(); ds.close()
        print("DONE")
    """)
    check(r)


def test_two_models_load_one_database():
    r = run_python(f"""
        import mfm
        m1 = mfm.load({str(SPHERE_TOML)!r})
        m2 = mfm.load({str(SPHERE_TOML)!r})
        assert m1.hydro is not m2.hydro
        print("DONE")
    """)
    check(r)


def test_two_models_load_one_database_held_open():
    r = run_python(f"""
        import xarray as xr, mfm
        ds = xr.open_dataset({str(SPHERE_NC)!r})
        m1 = mfm.load({str(SPHERE_TOML)!r})
        m2 = mfm.load({str(SPHERE_TOML)!r})
        ds.close()
        print("DONE")
    """)
    check(r)


def test_database_held_open_while_mfm_hydro_rewrites_it(tmp_path):
    # `mfm hydro --force` over a database a notebook holds open. The BEM solve is replaced by the
    # shipped result (no capytaine run): the write path under test is generate's own (probe of the
    # old file, temporary file, check by loading, rename over the old one).
    db = tmp_path / "sphere.nc"
    db.write_bytes(SPHERE_NC.read_bytes())
    cfg = tmp_path / "sphere.toml"
    cfg.write_text(SPHERE_TOML.read_text().replace('"../hydro/data/sphere.nc"', '"sphere.nc"')
                   + '[bodies.geometry]\nshape = "sphere"\nradius = 1.0\n')
    r = run_python(f"""
        import xarray as xr, mfm
        from hydro import bem
        from mfm.io import bemgen
        shipped = bem.load({str(SPHERE_NC)!r})
        bem.solve = lambda *a, **k: shipped.copy()
        ds = xr.open_dataset({str(db)!r})                  # held open
        old_attrs = dict(ds.attrs)
        bemgen.generate({str(cfg)!r}, force=True, progress=False,
                        overrides={{"omega_min": 0.1, "omega_max": 6.0, "n_omega": 60, "dx": 0.05}})
        model = mfm.load({str(cfg)!r})                     # the rewritten file loads
        new = xr.open_dataset({str(db)!r})
        assert "mfm_bem_inputs_sha256" in new.attrs and "mfm_bem_inputs_sha256" not in old_attrs
        assert float(ds.added_mass.sum()) == float(shipped.added_mass.sum())   # old handle intact
        ds.close(); new.close()
        print("DONE")
    """, cwd=tmp_path)
    check(r)


def test_result_held_open_while_the_cli_writes_it(tmp_path):
    out = tmp_path / "run.nc"
    cli = [sys.executable, "-m", "mfm", "simulate", str(ROOT / "configs" / "double_pendulum.toml"),
           "--duration", "0.2", "--dt", "0.01", "--initial", "upper.angle=0.3", "--out", str(out)]
    r = run_python(f"""
        import os, subprocess, numpy as np, xarray as xr
        xr.Dataset({{"q": (("time",), np.arange(5.0))}}).to_netcdf({str(out)!r})   # a first result
        ds = xr.open_dataset({str(out)!r})                # held open
        rc = subprocess.run({cli!r}, env=dict(os.environ)).returncode
        assert rc == 0, f"CLI run over the held result: exit {{rc}}"
        assert ds.sizes["time"] == 5 and float(ds.q[-1]) == 4.0      # the reader keeps its file
        with xr.open_dataset({str(out)!r}) as new:
            assert new.sizes["time"] == 21                 # and the path holds the new result
        print("DONE")
    """, cwd=tmp_path)
    check(r)
