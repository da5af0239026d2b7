"""Issue 53 item 3: mean wave drift: the database variable, its WAMIT .8/.9 reader, the load.

The WAMIT reader is checked against capytaine's own .8 writer (capytaine.io.wamit, written from the
WAMIT manual's non-dimensionalisation F/(rho g A^2 L^k), k = 1 forces, 2 moments: another
implementation of the same format), with ULEN = 2 so that the length scaling is exercised.
"""
import shutil
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hydro.database import validate
from hydro.wamit import read_wamit

RM3 = Path(__file__).resolve().parents[1] / "hydro" / "data" / "rm3"


def _rm3_copy(tmp_path, ulen=None):
    for ext in ("1", "3", "hst", "out"):
        shutil.copy(RM3 / f"rm3.{ext}", tmp_path / f"rm3.{ext}")
    if ulen is not None:
        out = tmp_path / "rm3.out"
        text = out.read_text()
        assert "Length scale:        1.00000" in text
        out.write_text(text.replace("Length scale:        1.00000", f"Length scale:        {ulen:.5f}"))
    return tmp_path / "rm3"


def _capytaine_drift_file(path, omega, heads, values, *, rho, g, L):
    """Write `values` (n_ω, n_β, 3: surge, sway, yaw; N/m², N m/m²) with capytaine's WAMIT writer."""
    wamit = pytest.importorskip("capytaine.io.wamit")
    da = xr.DataArray(values.astype(complex)[:, :, :, None] * np.eye(len(heads))[None, :, None, :],
                      dims=("omega", "wave_direction_k", "influenced_dof", "wave_direction_l"),
                      coords={"omega": omega, "wave_direction_k": heads, "wave_direction_l": heads,
                              "influenced_dof": ["Surge", "Sway", "Yaw"], "rho": rho, "g": g,
                              "period": ("omega", 2 * np.pi / omega)})
    da = da.transpose("influenced_dof", "omega", "wave_direction_k", "wave_direction_l")
    wamit._export_wamit_mean_drift(da, str(path), length_scale=L)


def test_wamit_drift_file_read_as_capytaine_writes_it(tmp_path):
    stem = _rm3_copy(tmp_path, ulen=2.0)
    base = read_wamit(stem, body_names=["float", "spar"])
    assert "mean_drift" not in base                   # no .8/.9: a database without drift is valid
    om, beta = base["omega"].values, base["wave_direction"].values
    rng = np.random.default_rng(53)
    vals = rng.normal(size=(len(om), len(beta), 3)) * np.array([1e3, 1e3, 1e4])
    rho, g = float(base.attrs["rho"]), float(base.attrs["g"])
    # WAMIT's .9 (pressure) has the layout of the .8; capytaine writes modes 1, 2, 6 of body 1
    _capytaine_drift_file(tmp_path / "rm3.9", om, beta, vals, rho=rho, g=g, L=2.0)
    db = read_wamit(stem, body_names=["float", "spar"])
    validate(db, warn=False)
    D = db["mean_drift"]
    assert D.dims == ("omega", "wave_direction", "influenced_dof")
    got = D.sel(influenced_dof=["float__Surge", "float__Sway", "float__Yaw"]).values
    # the file holds 6 significant digits (%12.6e)
    np.testing.assert_allclose(got, vals, rtol=2e-6, atol=0)
    others = D.drop_sel(influenced_dof=["float__Surge", "float__Sway", "float__Yaw"]).values
    assert np.all(others == 0.0)
    assert D.attrs["dofs"] == "float__Surge, float__Sway, float__Yaw"
    assert "near field" in D.attrs["method"]
    # a multi-body .8 (all bodies together) cannot be split: refused when asked for, skipped by auto
    shutil.copy(tmp_path / "rm3.9", tmp_path / "rm3.8")
    with pytest.raises(ValueError, match="cannot be split"):
        read_wamit(stem, body_names=["float", "spar"], drift="momentum")
    assert "near field" in read_wamit(stem, body_names=["float", "spar"])["mean_drift"].attrs["method"]
    assert "mean_drift" not in read_wamit(stem, body_names=["float", "spar"], drift=None)
    with pytest.raises(ValueError, match="drift='far'"):
        read_wamit(stem, drift="far")


def test_wamit_drift_file_damaged(tmp_path):
    stem = _rm3_copy(tmp_path)
    base = read_wamit(stem, body_names=["float", "spar"])
    om, beta = base["omega"].values, base["wave_direction"].values
    _capytaine_drift_file(tmp_path / "rm3.9", om, beta, np.ones((len(om), len(beta), 3)),
                          rho=1000.0, g=9.81, L=1.0)
    lines = (tmp_path / "rm3.9").read_text().splitlines()
    (tmp_path / "rm3.9").write_text("\n".join(lines[:-1]) + "\n")        # one mode cut off
    with pytest.raises(ValueError, match="truncated or damaged"):
        read_wamit(stem)
    (tmp_path / "rm3.9").write_text("\n".join(lines[3:]) + "\n")          # first frequency short
    with pytest.raises(ValueError, match="rm3.9"):
        read_wamit(stem)


def test_database_mean_drift_must_be_real_and_finite(tmp_path):
    db = read_wamit(_rm3_copy(tmp_path), body_names=["float", "spar"])
    D = np.zeros(db["excitation"].shape)
    bad = db.assign(mean_drift=(db["excitation"].dims, D + 1j))
    with pytest.raises(ValueError, match="'mean_drift' must be real"):
        validate(bad, warn=False)
    D[1, 0, 0] = np.nan
    with pytest.raises(ValueError, match="'mean_drift' has 1 non-finite"):
        validate(db.assign(mean_drift=(db["excitation"].dims, D)), warn=False)
    with pytest.raises(ValueError, match="mean_drift"):
        validate(db.assign(mean_drift=(("omega", "influenced_dof", "wave_direction"),
                                       np.zeros(D.shape).transpose(0, 2, 1))), warn=False)
