"""Invalid float trees raise ConfigError naming the offending key and value."""
import copy

import numpy as np
import pytest

import mfm
from conftest import CONFIGS
from mfm.io.config import parse_config

BASE = {
    "model": {"name": "t"},
    "bodies": [
        {"name": "a", "mass": 1.0, "com": [0, 0, 0], "principal_inertia": [1, 1, 1],
         "joint": {"type": "free"}},
        {"name": "b", "parent": "a", "mass": 1.0, "com": [1, 0, 0], "principal_inertia": [1, 1, 1],
         "joint": {"type": "revolute", "axis": [0, 1, 0], "point": [0.5, 0, 0], "damping": 2.0}},
    ],
}


def modified(fn):
    d = copy.deepcopy(BASE)
    fn(d)
    return d


def test_base_config_is_valid():
    options, bodies = parse_config(BASE)
    assert [b.name for b in bodies] == ["a", "b"]
    m = mfm.compile_tree(bodies)
    assert m.coordinates == ("a.surge", "a.sway", "a.heave", "a.roll", "a.pitch", "a.yaw", "b.angle")
    assert m.bodies[1].joint.kind == "revolute" and m.bodies[1].parent == "a"
    np.testing.assert_allclose(m.damping, [0, 0, 0, 0, 0, 0, 2.0])


CASES = {
    "unknown parent": (lambda d: d["bodies"][1].update(parent="zz"), ["parent", "'zz'"]),
    "cycle": (lambda d: (d["bodies"].append({**copy.deepcopy(d["bodies"][1]), "name": "c", "parent": "d"}),
                         d["bodies"].append({**copy.deepcopy(d["bodies"][1]), "name": "d", "parent": "c"})),
              ["parent", "cycle"]),
    "no root": (lambda d: d["bodies"][0].update(parent="b"), ["root"]),
    "massless hinged body": (lambda d: d["bodies"][1].update(mass=0.0), ["bodies[1]", "mass", "fixed"]),
    "massless root": (lambda d: d["bodies"][0].update(mass=0.0), ["bodies[0]", "mass", "parent"]),
    "asymmetric inertia": (lambda d: (d["bodies"][0].pop("principal_inertia"),
                                      d["bodies"][0].update(inertia=[[1, 0.1, 0], [0, 1, 0], [0, 0, 1]])),
                           ["bodies[0]", "inertia", "symmetric"]),
    "not positive-definite": (lambda d: d["bodies"][0].update(principal_inertia=[1, 1, -1]),
                              ["principal_inertia", "positive"]),
    "triangle inequality": (lambda d: d["bodies"][0].update(principal_inertia=[1, 1, 3]),
                            ["principal_inertia", "triangle"]),
    "zero axis": (lambda d: d["bodies"][1]["joint"].update(axis=[0, 0, 0]), ["joint.axis", "zero"]),
    "non-positive mass": (lambda d: d["bodies"][1].update(mass=0.0), ["mass", "0.0"]),
    "negative mass": (lambda d: d["bodies"][1].update(mass=-2), ["mass", "-2"]),
    "unknown body key": (lambda d: d["bodies"][1].update(colour="red"), ["bodies[1]", "colour"]),
    "unknown joint key": (lambda d: d["bodies"][1]["joint"].update(axes=[0, 1, 0]), ["joint", "axes"]),
    "unknown top key": (lambda d: d.update(extra={}), ["extra"]),
    "unknown joint type": (lambda d: d["bodies"][1]["joint"].update(type="hinge"),
                           ["joint.type", "'hinge'", "revolute"]),
    "duplicate name": (lambda d: d["bodies"][1].update(name="a"), ["name", "'a'"]),
    "free below root": (lambda d: d["bodies"][1].update(joint={"type": "free"}), ["joint.type", "root"]),
    "negative damping": (lambda d: d["bodies"][1]["joint"].update(damping=-1.0), ["damping"]),
    "bad dof": (lambda d: d["bodies"][0]["joint"].update(dofs=["heave", "bob"]), ["dofs", "'bob'"]),
    "missing point": (lambda d: d["bodies"][1]["joint"].pop("point"), ["joint.point"]),
    "bad com": (lambda d: d["bodies"][1].update(com=[1, 2]), ["com"]),
    "two inertias": (lambda d: d["bodies"][1].update(radii_of_gyration=[1, 1, 1]), ["inertia"]),
    "reserved name": (lambda d: d["bodies"][1].update(name="b__x"), ["name", "__"]),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_invalid_config_names_the_key(case):
    fn, words = CASES[case]
    with pytest.raises(mfm.ConfigError) as info:
        parse_config(modified(fn))
    for w in words:
        assert w in str(info.value), f"{case}: {w!r} missing from: {info.value}"


def test_load_reports_file_and_toml_errors(tmp_path):
    with pytest.raises(mfm.ConfigError, match="not found"):
        mfm.load(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[[bodies]\nname=")
    with pytest.raises(mfm.ConfigError, match="not valid TOML"):
        mfm.load(bad)


def test_two_roots_each_hang_from_the_inertial_frame():
    """Two roots, a floating body and a pendulum hinged to the earth (parent = "earth", said so
    beside a floating root: without it the hinge would hang from the earth by a missing parent,
    refused): each moves as it would alone (no coupling through the tree), the second one's
    coordinates after the first's; a free joint below a root stays an error."""
    d = modified(lambda d: (d["bodies"][1].pop("parent"),
                            d["bodies"][1].update(joint={"type": "revolute", "axis": [0, 1, 0],
                                                         "point": [0.5, 0, 0]})))
    with pytest.raises(mfm.ConfigError, match=r"no parent, so its revolute joint hangs"):
        parse_config(d)
    d["bodies"][1]["parent"] = "earth"
    _, bodies = parse_config(d)
    both = mfm.compile_tree(bodies)
    assert both.coordinates[-1] == "b.angle" and both.bodies[1].parent is None
    alone_a = mfm.compile_tree(parse_config({**d, "bodies": [d["bodies"][0]]})[1])
    alone_b = mfm.compile_tree(parse_config({**d, "bodies": [d["bodies"][1]]})[1])
    q = np.array([0.1, -0.2, 0.3, 0.05, -0.1, 0.2, 0.4])
    qd = np.array([0.3, 0.1, -0.2, 0.4, 0.2, -0.1, 0.5])
    qdd = np.asarray(mfm.forward_dynamics(both, q, qd))
    np.testing.assert_allclose(qdd[:6], mfm.forward_dynamics(alone_a, q[:6], qd[:6]), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(qdd[6:], mfm.forward_dynamics(alone_b, q[6:], qd[6:]), rtol=1e-12, atol=1e-12)
    # the pendulum b about y through (0.5, 0, 0), CoM 0.5 m along +x: gravity’s moment about +y
    # is r × F = +m g r cos θ, so θ̈ = m g r cos θ / (I + m r²)
    th = q[6]
    assert qdd[6] == pytest.approx(9.81 * 0.5 * np.cos(th) / (1.0 + 0.25), rel=1e-12)
    d["bodies"][1]["parent"] = "a"
    d["bodies"][1]["joint"] = {"type": "free"}
    with pytest.raises(mfm.ConfigError, match="only allowed for a root"):
        parse_config(d)


def test_massless_welded_hull_adds_nothing():
    """A hull welded to its parent with mass 0 (its parent carries the mass): the model's
    dynamics are those without it."""
    hull = {"name": "h", "parent": "a", "mass": 0.0, "com": [3, 0, -1], "joint": {"type": "fixed"}}
    with_hull = mfm.compile_tree(parse_config({**BASE, "bodies": BASE["bodies"] + [hull]})[1])
    without = mfm.compile_tree(parse_config(BASE)[1])
    q = np.array([0.1, -0.2, 0.3, 0.05, -0.1, 0.2, 0.4])
    qd = np.array([0.3, 0.1, -0.2, 0.4, 0.2, -0.1, 0.5])
    np.testing.assert_allclose(mfm.forward_dynamics(with_hull, q, qd),
                               mfm.forward_dynamics(without, q, qd), rtol=1e-12)


def test_inertia_forms_agree():
    d1 = modified(lambda d: d["bodies"][1].update(principal_inertia=[2.0, 3.0, 4.0]))
    d2 = modified(lambda d: (d["bodies"][1].pop("principal_inertia"),
                             d["bodies"][1].update(radii_of_gyration=[2 ** .5, 3 ** .5, 2.0])))
    d3 = modified(lambda d: (d["bodies"][1].pop("principal_inertia"),
                             d["bodies"][1].update(inertia=[[2, 0, 0], [0, 3, 0], [0, 0, 4]])))
    J = [parse_config(d)[1][1].inertia for d in (d1, d2, d3)]
    np.testing.assert_allclose(J[0], J[1], rtol=1e-12)
    np.testing.assert_allclose(J[0], J[2], rtol=1e-12)


@pytest.mark.parametrize("layout,n_bodies,n_q", [("111", 3, 4), ("132", 6, 5), ("134", 8, 7)])
def test_m4_configs_load(layout, n_bodies, n_q):
    m = mfm.load(CONFIGS / f"m4_{layout}.toml", hydro=False)
    assert m.n_bodies == n_bodies and m.n_coordinates == n_q
    assert m.coordinates[:3] == ("float1.surge", "float1.heave", "float1.pitch")
    # Table 1 of seed 001
    masses = {b.name: b.mass for b in m.bodies}
    assert masses["float1"] == 2.345 and masses["float2"] == 5.312 and masses["float3"] == 17.52
    np.testing.assert_allclose(m.damping[3:], 6.0)
