"""Issue 54 item 14: a result file is never replaced by a worse one, and a failed write says where
the result went.

- A full disk (the writer raises OSError(ENOSPC), or netCDF's raw "NetCDF: HDF error") or a
  folder made read-only after the run started: the earlier file is unchanged, no temporary file
  is left, the result is saved in the temporary folder and the error names the target, the OS
  error and that file (or, where nothing can be written, that the dataset is all there is).
- A run that goes non-finite never replaces a complete file: it goes to ``<name>.partial.nc``.
  A partial file may be replaced by a later run, partial or complete.

Before: the command line lost the finished run behind "Permission denied" or a raw
"NetCDF: HDF error", and a non-finite run replaced a complete --out file with its 4 samples.
"""
from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from conftest import CONFIGS

from mfm import results

mfm_cli = pytest.importorskip("mfm_cli")


def _result(n, complete=True):
    t = np.arange(n) * 0.1
    return xr.Dataset({"q": (("time",), np.sin(t))}, coords={"time": t},
                      attrs={"complete": "true" if complete else "false"})


def _fail_under(monkeypatch, folder: Path, error: Exception):
    """Every NetCDF write under ``folder`` raises ``error`` (a full disk, a read-only folder);
    elsewhere (the temporary folder) writes work."""
    real = xr.Dataset.to_netcdf

    def to_netcdf(self, path=None, *a, **k):
        if path is not None and Path(path).resolve().parent == folder.resolve():
            Path(path).write_bytes(b"\x89HDF\r\n")       # what a full disk leaves: a stub
            raise error
        return real(self, path, *a, **k)

    monkeypatch.setattr(xr.Dataset, "to_netcdf", to_netcdf)


@pytest.mark.parametrize("error, said", [
    (OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)), "the disk is full"),
    (RuntimeError("NetCDF: HDF error"), "NetCDF: HDF error"),
    (PermissionError(errno.EACCES, os.strerror(errno.EACCES)), os.strerror(errno.EACCES)),
])
def test_a_failed_write_keeps_the_earlier_file_and_says_where_the_result_went(
        tmp_path, monkeypatch, error, said):
    target = tmp_path / "run.nc"
    results.save_netcdf(_result(50), target)
    before = target.read_bytes()
    _fail_under(monkeypatch, tmp_path, error)
    new = _result(80)
    with pytest.raises(results.ResultNotSaved) as caught:
        results.save_netcdf(new, target)
    e = caught.value
    message = str(e)
    assert str(target) in message and said in message, message
    assert "unchanged" in message
    assert e.saved is not None and str(e.saved) in message and e.dataset is new
    xr.testing.assert_identical(xr.load_dataset(e.saved), new)
    assert target.read_bytes() == before                      # the good file is untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]   # no temporary left


def test_a_read_only_folder(tmp_path, monkeypatch):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        if os.access(folder, os.W_OK):     # root writes anyway: the OS error it would get
            _fail_under(monkeypatch, folder, PermissionError(errno.EACCES, "Permission denied"))
        with pytest.raises(results.ResultNotSaved, match="Permission denied") as caught:
            results.save_netcdf(_result(10), folder / "run.nc")
        assert str(folder / "run.nc") in str(caught.value)
        assert caught.value.saved.exists()
    finally:
        folder.chmod(0o755)


def test_nowhere_to_write_says_the_dataset_is_all_there_is(tmp_path, monkeypatch):
    monkeypatch.setattr(xr.Dataset, "to_netcdf", lambda self, path=None, *a, **k: (_ for _ in ())
                        .throw(OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))))
    ds = _result(10)
    with pytest.raises(results.ResultNotSaved, match="only in memory") as caught:
        results.save_netcdf(ds, tmp_path / "run.nc")
    assert caught.value.saved is None and caught.value.dataset is ds
    assert str(tmp_path / "run.nc") in str(caught.value)


def test_a_partial_run_never_replaces_a_complete_file(tmp_path):
    target = tmp_path / "run.nc"
    results.save_netcdf(_result(50), target)
    before = target.read_bytes()
    said = []
    written = results.save_netcdf(_result(4, complete=False), target, announce=said.append)
    assert written == tmp_path / "run.partial.nc" and target.read_bytes() == before
    assert len(said) == 1 and str(target) in said[0] and str(written) in said[0]
    assert xr.load_dataset(written).time.size == 4
    # a partial file is no better than another partial run, nor than a complete one
    partial = tmp_path / "p.nc"
    results.save_netcdf(_result(4, complete=False), partial)
    assert results.save_netcdf(_result(6, complete=False), partial) == partial
    assert xr.load_dataset(partial).time.size == 6
    assert results.save_netcdf(_result(50), partial) == partial
    assert xr.load_dataset(partial).time.size == 50
    # a torn file (a kill during an older writer's write) is replaced too
    torn = tmp_path / "torn.nc"
    torn.write_bytes(b"\x89HDF\r\n\x1a\n")
    assert results.save_netcdf(_result(4, complete=False), torn) == torn


def _simulate(out, *extra):
    return mfm_cli.main(["simulate", str(CONFIGS / "double_pendulum.toml"), "--initial",
                         "upper.angle=3", "--no-plot", "--progress", "off", "--out", str(out),
                         *extra])


GOOD = ("--duration", "1", "--dt", "0.01")                                 # rk4: 101 samples
NON_FINITE = ("--duration", "20", "--dt", "0.5", "--integrator", "verlet")  # at t = 5 s


@pytest.mark.filterwarnings("ignore:overflow", "ignore::mfm.AccuracyWarning")
def test_the_command_line_keeps_a_complete_file_from_a_run_gone_non_finite(tmp_path, capsys):
    out = tmp_path / "run.nc"
    assert _simulate(out, *GOOD) == 0
    before = out.read_bytes()
    capsys.readouterr()
    assert _simulate(out, *NON_FINITE) == 2
    err = capsys.readouterr().err
    partial = tmp_path / "run.partial.nc"
    assert out.read_bytes() == before
    assert xr.load_dataset(partial).attrs["complete"] == "false"
    assert f"{out} holds a complete run and is kept" in err and f"are in {partial}" in err, err


def test_the_command_line_on_a_full_disk_prints_the_run_and_where_it_went(
        tmp_path, monkeypatch, capsys):
    out = tmp_path / "run.nc"
    _fail_under(monkeypatch, tmp_path, OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))
    assert _simulate(out, *GOOD) == 2
    captured = capsys.readouterr()
    assert "mean" in captured.out                      # the summary is printed all the same
    line = [ln for ln in captured.err.splitlines() if ln.startswith("mfm simulate: error:")]
    assert len(line) == 1 and str(out) in line[0] and "disk is full" in line[0], captured.err
    saved = Path(line[0].split("saved to ")[1].split(" instead")[0])
    assert xr.load_dataset(saved).time.size == 101 and saved.name == "run.nc"
    assert not out.exists() and not list(tmp_path.iterdir())
