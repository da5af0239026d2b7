"""The command line and the notebooks (executed in smoke mode so they never rot)."""

import os

import nbformat
import pytest
import xarray as xr
from conftest import CONFIGS, ROOT
from nbclient import NotebookClient

from mfm_cli import main


def test_cli_info(capsys):
    assert main(["info", str(CONFIGS / "m4_132.toml"), "--no-restoring"]) == 0
    out = capsys.readouterr().out
    assert "M4 132: 6 bodies, 5 coordinates" in out and "float6.angle [rad]  (damper 6 N m s/rad)" in out


def test_cli_simulate_and_plot(tmp_path, capsys):
    nc = tmp_path / "dp.nc"
    assert main(["simulate", str(CONFIGS / "double_pendulum.toml"), "--duration", "0.5", "--dt", "0.01",
                 "--initial", "upper.angle=0.3", "--integrator", "beeman", "--out", str(nc)]) == 0
    ds = xr.load_dataset(nc)
    assert ds.sizes["time"] == 51 and float(ds.q.isel(time=0, coordinate=0)) == 0.3
    assert ds.attrs["integrator"] == "beeman"
    png = tmp_path / "layout.png"
    assert main(["plot", str(CONFIGS / "m4_134.toml"), "--out", str(png)]) == 0
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


def test_cli_errors_are_one_line(tmp_path, capsys):
    assert main(["simulate", str(CONFIGS / "double_pendulum.toml"), "--initial", "elbow=0.3",
                 "--out", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert "'elbow' is not a coordinate" in err
    bad = tmp_path / "bad.toml"
    bad.write_text('[[bodies]]\nname = "a"\nmass = -1\ncom = [0, 0, 0]\nprincipal_inertia = [1, 1, 1]\n'
                   '[bodies.joint]\ntype = "free"\n')
    assert main(["info", str(bad)]) == 2
    assert "bodies[0] ('a').mass" in capsys.readouterr().err


def test_cli_optimize_as_the_readme_writes_it(tmp_path, capsys):
    """README § Design by gradient's `mfm optimize` line, run as written (--out moved to tmp):
    the heave limit active and met, and the optimum's heave rms again by the numpy spectral route
    (mfm.spectral_response of the model with that damping; 1e-6 relative: SLSQP meets an active
    limit to its tolerance 1e-9 of the scaled objective, the two routes agree to round-off)."""
    import shlex

    import numpy as np

    import mfm
    from hydro.waves import Regular

    line = next(ln for ln in (ROOT / "README.md").read_text().splitlines()
                if ln.startswith("mfm optimize configs/sphere.toml"))
    argv = shlex.split(line)[1:]
    nc = tmp_path / "optimum.nc"
    argv[argv.index("--out") + 1] = str(nc)
    argv[1] = str(CONFIGS / "sphere.toml")
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "sphere.heave.damping:" in out and "rms(sphere.heave): 0.1 ≤ 0.1 (active" in out
    ds = xr.load_dataset(nc)
    assert bool(ds.constraint_active.item()) and ds.attrs["command"]
    c = float(ds.optimum.item())
    assert 0.0 < c < 20000.0
    m = mfm.load(CONFIGS / "sphere.toml")
    damped = m.replace(damping=np.where(np.array(m.coordinates) == "sphere.heave", c, m.damping))
    sp = mfm.spectral_response(damped, Regular(height=0.5, period=2.5))
    assert float(sp.q_rms.sel(coordinate="sphere.heave")) == pytest.approx(0.1, rel=1e-6)
    assert float(ds.objective) == pytest.approx(float(sp.pto_power_mean.sum()), rel=1e-9)


def test_cli_optimize_errors_are_one_line(tmp_path, capsys):
    base = ["optimize", str(CONFIGS / "sphere.toml"), "--wave", "regular", "--height", "0.5",
            "--period", "2.5", "--out", str(tmp_path / "o.nc")]
    assert main(base + ["--param", "sphere.damping=0:1"]) == 2
    err = capsys.readouterr().err
    assert "--param 'sphere.damping=0:1'" in err and "sphere.heave.damping" in err
    assert main(base + ["--param", "sphere.heave.damping=0-1"]) == 2
    assert "is not LO:HI" in capsys.readouterr().err
    assert main(base + ["--param", "sphere.heave.damping"]) == 2       # the model's value is 0
    assert "no span; give bounds" in capsys.readouterr().err
    assert main(base + ["--param", "sphere.heave.damping=0:1e4", "--constraint", "heave=0.1"]) == 2
    assert "expected QUANTITY.KIND=LIMIT" in capsys.readouterr().err
    with pytest.raises(SystemExit, match="--wave regular needs --height"):
        main(["optimize", str(CONFIGS / "sphere.toml"), "--wave", "regular",
              "--param", "sphere.heave.damping=0:1e4", "--out", str(tmp_path / "o.nc")])


NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
# the suite runs with --dist loadfile: one file's tests stay on one worker, so the notebooks are
# split over two files (these run from tests/test_notebooks_second.py) to use both workers;
# every other notebook, a new one included, runs here
SECOND = ("design", "hallak_fwwp", "wu_yuan")
# design smoke (mostly compiling: one structure per model, Hallak's κ, which moves q₀, the heaviest),
# `time nice -n 10 python -m pytest -n 0 tests/test_notebooks_second.py -k design`, 2 cores:
# with its q-factors and heading sweep, 172 s CPU / 4.8 min wall under a load of 5–8 and 187 s CPU /
# 7.6 min wall under a load of 7–9.5 (before them and before forward-mode derivatives for Stansby &
# Li and Hallak: 211 s CPU / 4.3 min at a load of 7–8); about 3 min of CPU, so ≤ 3 min wall only unloaded
FIRST = [p for p in NOTEBOOKS if p.stem not in SECOND]


@pytest.mark.parametrize("path", FIRST, ids=[p.stem for p in FIRST])
def test_notebook_runs_in_smoke_mode(path, monkeypatch):
    run_in_smoke_mode(path, monkeypatch)


def run_in_smoke_mode(path, monkeypatch):
    monkeypatch.setenv("MFM_SMOKE", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    # the kernel inherits XLA_FLAGS: conftest's cheapest optimisation (compiling is most of a
    # smoke run)
    # the kernel starts in notebooks/: put this checkout first, not whatever `pip install -e`
    # points at (another worktree's code would be tested otherwise)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    nb = nbformat.read(path, as_version=4)
    stored = stored_outputs(nb)
    NotebookClient(nb, timeout=900, kernel_name="python3",
                   resources={"metadata": {"path": str(path.parent)}}).execute()
    # issue 35: a notebook's stored numbers went stale (quickstart's natural frequencies). The
    # cells tagged "compare-output" print numbers that the smoke mode does not change: their
    # fresh stdout must be their stored stdout, as text (the numbers as printed, rounded by the
    # cell itself). A line the smoke mode changes on purpose is excluded by its cell's metadata
    # "smoke_changes" {line prefix: why}.
    fresh = stored_outputs(nb)
    for k, text in stored.items():
        assert fresh[k] == text, (f"{path.name} cell {k}: stored output {text!r}, a fresh run "
                                  f"gives {fresh[k]!r}; re-run the cell and save the notebook")


def stored_outputs(nb) -> dict[int, list[str]]:
    """The stdout lines of the cells tagged "compare-output" (by cell index), less the lines the
    cell's "smoke_changes" metadata excludes."""
    out = {}
    for k, cell in enumerate(nb.cells):
        if "compare-output" not in cell.get("metadata", {}).get("tags", []):
            continue
        skip = tuple(cell.metadata.get("smoke_changes", {}))
        text = "".join(o.get("text", "") for o in cell.get("outputs", [])
                       if o.get("output_type") == "stream" and o.get("name") == "stdout")
        out[k] = [l for l in text.splitlines() if not (skip and l.startswith(skip))]
    return out


def test_stored_outputs_are_compared():
    """The comparison above is not vacuous: the quickstart has tagged cells with stored numbers."""
    nb = nbformat.read(ROOT / "notebooks" / "quickstart.ipynb", as_version=4)
    stored = stored_outputs(nb)
    assert stored and all(any(c.isdigit() for l in v for c in l) for v in stored.values()), stored


def _stored_texts(cell):
    """Every text a cell's stored outputs show: streams, tracebacks and the text forms of rich
    outputs (not the images' base64)."""
    for o in cell.get("outputs", []):
        yield "".join(o.get("text", ""))
        yield "\n".join(o.get("traceback", []))
        for kind, value in o.get("data", {}).items():
            if not kind.startswith("image/"):
                yield value if isinstance(value, str) else "".join(value)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_stored_outputs_name_no_folder_of_a_machine(path):
    # issue 54 item 11: design.ipynb printed /work/wt-studies36/notebooks/figures/design; the
    # notebooks print paths relative to the repository, and a warning's source path is trimmed
    nb = nbformat.read(path, as_version=4)
    for k, cell in enumerate(nb.cells):
        for text in _stored_texts(cell):
            for folder in ("/work/", "/home/", "/root/", "/Users/", "/tmp/"):
                assert folder not in text, (
                    f"{path.name} cell {k}: a stored output names {folder}...: "
                    f"{text[max(0, text.index(folder) - 80):text.index(folder) + 80]!r}")
