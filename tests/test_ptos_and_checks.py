"""PTO laws (locked hinge, hydraulic μ/β/κ), moorings, stability warnings, natural frequencies,
joint reactions with water, and the hydro command line."""
import warnings

import numpy as np
import pytest
import xarray as xr
from conftest import CONFIGS

import hydro
import mfm
from mfm_cli import main
from mfm.io.config import parse_config

# per module, not session-wide: a database warning is expected here (the shipped BEM data)
pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


def test_locked_hinge_is_rigid():
    text = (CONFIGS / "m4_111.toml").read_text()
    data = __import__("tomllib").loads(text)
    data.pop("hydro", None)
    data["bodies"][2]["joint"] = {"type": "revolute", "axis": [0, 1, 0], "point": [1.05, 0, 0.21],
                                  "locked": True}
    options, bodies = parse_config(data)
    m = mfm.compile_tree(bodies)
    assert m.coordinates == ("float1.surge", "float1.heave", "float1.pitch")
    # the locked stern float moves rigidly with the bow: same pitch, CoM on the rotated lever
    q = np.array([0.1, -0.05, 0.2])
    x, R = mfm.body_poses(m, q)
    np.testing.assert_allclose(R[2], R[0], atol=1e-14)
    lever = np.asarray(m.com[2] - m.com[0])
    np.testing.assert_allclose(x[2], x[0] + np.asarray(R[0]) @ lever, atol=1e-14)
    with pytest.raises(mfm.ConfigError, match="locked.*coordinate"):
        data["bodies"][2]["joint"]["damping"] = 6.0
        parse_config(data)


def slider_config(extra_pto):
    body = {"name": "s", "mass": 3.0, "com": [0.0, 0.0, -1.0], "principal_inertia": [1, 1, 1],
            "joint": {"type": "prismatic", "axis": [1.0, 0.0, 0.0]}}
    data = {"model": {"gravity": 9.81}, "bodies": [body]}
    if extra_pto:
        data["ptos"] = [{"name": "piston", "body": "s", "point": [0.0, 0.0, -1.0],
                         "anchor": [-2.0, 0.0, -1.0], "mu": 2.0, "beta": 1.5, "kappa": 40.0}]
    return data


def _write(path, data):
    lines = []
    m = data.get("model", {})
    lines.append("[model]\n" + "".join(f"{k} = {v!r}\n" for k, v in m.items()))
    for b in data["bodies"]:
        lines.append("[[bodies]]\n" + "".join(f"{k} = {_toml(v)}\n" for k, v in b.items() if k != "joint"))
        lines.append("[bodies.joint]\n" + "".join(f"{k} = {_toml(v)}\n" for k, v in b["joint"].items()))
    for p in data.get("ptos", []):
        lines.append("[[ptos]]\n" + "".join(f"{k} = {_toml(v)}\n" for k, v in p.items()))
    path.write_text("\n".join(lines))
    return path


def _toml(v):
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(list(v)) if isinstance(v, (list, tuple)) else repr(v)


def test_hydraulic_pto_matches_equivalent_joint(tmp_path):
    pto = mfm.load(_write(tmp_path / "pto.toml", slider_config(True)))
    eq_data = slider_config(False)
    eq_data["bodies"][0]["mass"] = 5.0
    eq_data["bodies"][0]["joint"].update(damping=1.5, stiffness=40.0)
    eq = mfm.load(_write(tmp_path / "eq.toml", eq_data))
    a = mfm.simulate(pto, duration=4.0, dt=0.002, q0=[0.3])
    b = mfm.simulate(eq, duration=4.0, dt=0.002, q0=[0.3])
    # identical equations: agreement to round-off accumulated over 2000 RK4 steps
    np.testing.assert_allclose(a.q.values, b.q.values, atol=1e-10)
    np.testing.assert_allclose(a.pto_power.sel(pto="piston").values, b.pto_power.sel(pto="s.stroke").values,
                               atol=1e-8)
    # the piston force μẍ + βẋ + κx from the recorded accelerations
    f = 2.0 * a.qdd.values[:, 0] + 1.5 * a.qd.values[:, 0] + 40.0 * a.q.values[:, 0]
    np.testing.assert_allclose(a.pto_force.values[:, 0], f, atol=1e-9)
    # the anchor (inertial frame) end: the joint reaction along the axis carries the piston force
    np.testing.assert_allclose(a.joint_force.sel(body="s", axis="x").values, 0.0, atol=1e-9)


def test_stability_warning_names_dt_and_limit():
    model = mfm.compile_tree(parse_config({"bodies": [
        {"name": "s", "mass": 1.0, "com": [0, 0, 0], "principal_inertia": [1, 1, 1],
         "joint": {"type": "prismatic", "axis": [1, 0, 0], "stiffness": 1e4, "damping": 50.0}}]})[1])
    with pytest.warns(mfm.StabilityWarning, match=r"dt = 0.03 s is beyond the stability limit of rk4"):
        mfm.simulate(model, duration=0.3, dt=0.03, q0=[0.1])
    with warnings.catch_warnings():
        warnings.simplefilter("error", mfm.StabilityWarning)
        mfm.simulate(model, duration=0.3, dt=0.003, q0=[0.1])
        mfm.simulate(model, duration=0.3, dt=0.03, q0=[0.1], integrator="newmark")


def test_natural_frequencies_two_ways_agree():
    # the iterated generalised eigenproblem and the minima of |det Λ(ω)| (seed 000 §2.10) find
    # the same undamped natural frequencies (grid of 2000 points, parabolic refinement: 0.5 %)
    m = mfm.load(CONFIGS / "rm3.toml")
    nat = mfm.natural_frequencies(m)
    assert len(nat["eigen"]) == 3   # spar heave, pitch and float stroke; surge has no stiffness
    for w in nat["eigen"]:
        assert np.min(np.abs(nat["min_det"] - w)) / w < 5e-3


def test_reactions_with_water_are_consistent():
    # the planar root of the spar transmits nothing along its free directions (surge x, heave z,
    # pitch about y) although water, added mass and the PTO load the bodies: the reactions hold
    # every load, acceleration-proportional ones included
    m = mfm.load(CONFIGS / "rm3.toml")
    ds = mfm.simulate(m, hydro.Regular(height=2.0, period=8.0), duration=40.0, dt=0.1, ramp=10.0,
                      save_every=10)
    f = ds.joint_force.sel(body="spar")
    mom = ds.joint_moment.sel(body="spar")
    scale = float(np.abs(ds.hydro_force.sel(component="excitation")).max())
    assert np.abs(f.sel(axis="x")).max() < 1e-6 * scale
    assert np.abs(f.sel(axis="z")).max() < 1e-6 * scale
    assert np.abs(mom.sel(axis="y")).max() < 1e-6 * scale * 20
    # the prismatic float joint transmits the PTO force along its axis (which pitches with the
    # spar): −c ż
    th = ds.body_rotation.sel(body="spar", angle="pitch").values
    f_float = ds.joint_force.sel(body="float")
    along = np.sin(th) * f_float.sel(axis="x").values + np.cos(th) * f_float.sel(axis="z").values
    np.testing.assert_allclose(along, -1.2e6 * ds.qd.sel(coordinate="float.stroke").values,
                               atol=1e-6 * scale)


def test_mooring_spring_restores_surge():
    # a horizontal linear spring at the spar CoM: surge oscillates at √(k/(m + A11)) in still water
    text = (CONFIGS / "rm3.toml").read_text().replace("../hydro", str(CONFIGS.parent / "hydro"))
    text += '\n[[moorings]]\nbody = "spar"\npoint = [0.0, 0.0, -21.29]\nstiffness = [1e5, 1e5, 0.0]\n'
    import tempfile, pathlib
    with tempfile.TemporaryDirectory() as d:
        p = pathlib.Path(d) / "rm3_moored.toml"
        p.write_text(text)
        m = mfm.load(p)
    q0, info = mfm.equilibrium(m)
    assert info["free"] == []
    nat = mfm.natural_frequencies(m)
    assert len(nat["eigen"]) == 4
    K = mfm.frequency.linearise(m)[2]
    assert K[0, 0] == pytest.approx(1e5, rel=1e-9)


def test_cli_wave_simulation_and_rao(tmp_path, capsys):
    nc = tmp_path / "rm3.nc"
    assert main(["simulate", str(CONFIGS / "rm3.toml"), "--wave", "regular", "--height", "1.0",
                 "--period", "8", "--duration", "16", "--dt", "0.1", "--ramp", "8",
                 "--radiation", "state_space", "--out", str(nc)]) == 0
    ds = xr.open_dataset(nc)
    assert ds.attrs["radiation"] == "state_space" and "eta" in ds and "pto_power" in ds
    assert abs(float(ds.eta.max()) - 0.5) < 0.01
    out = tmp_path / "rao.nc"
    assert main(["rao", str(CONFIGS / "rm3.toml"), "--omega-min", "0.3", "--omega-max", "1.5", "--n", "7",
                 "--out", str(out)]) == 0
    r = xr.open_dataset(out)
    assert r.sizes["omega"] == 7 and "natural_frequency" in r
    text = capsys.readouterr().out
    assert "natural frequencies (eigen)" in text
    with pytest.raises(SystemExit, match="--tp"):
        main(["simulate", str(CONFIGS / "rm3.toml"), "--wave", "jonswap", "--hs", "1"])
