"""mfm.load from Python: a config as a dict of its tables or as TOML text (no file), relative
paths read from `base`; the same model as from the file."""
import hashlib
import tomllib
from pathlib import Path

import numpy as np
import pytest

import mfm

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def test_a_dict_and_a_toml_text_give_the_file_s_model():
    """RM3 (with its WAMIT database, a path relative to configs/) from its file, its text and its
    dict: the same coordinates, mass matrix and hydro database; the provenance names the form and
    hashes its content."""
    text = (CONFIGS / "rm3.toml").read_text()
    from_file = mfm.load(CONFIGS / "rm3.toml")
    from_text = mfm.load(text, base=CONFIGS)
    from_dict = mfm.load(tomllib.loads(text), base=CONFIGS)
    q = np.zeros(from_file.n_coordinates)
    for m in (from_text, from_dict):
        assert m.coordinates == from_file.coordinates
        np.testing.assert_array_equal(mfm.mass_matrix(m, q), mfm.mass_matrix(from_file, q))
        assert Path(m.hydro.source).resolve() == Path(from_file.hydro.source).resolve()
    assert (from_text.source, from_dict.source) == ("<toml text>", "<dict>")
    assert from_text.source_sha256 == hashlib.sha256(text.encode()).hexdigest()
    assert from_file.source_sha256 == hashlib.sha256((CONFIGS / "rm3.toml").read_bytes()).hexdigest()


def test_a_model_built_in_code_runs_as_its_file_does():
    """The double pendulum from a dict written in code: its run is the file's to the bit."""
    cfg = {"model": {"name": "double pendulum", "gravity": 9.81},
           "bodies": [{"name": "upper", "mass": 1.0, "com": [0.0, 0.0, -0.5],
                       "principal_inertia": [0.0834, 0.0834, 0.001],
                       "joint": {"type": "revolute", "axis": [0.0, 1.0, 0.0],
                                 "point": [0.0, 0.0, 0.0]}},
                      {"name": "lower", "parent": "upper", "mass": 1.0, "com": [0.0, 0.0, -1.5],
                       "principal_inertia": [0.0834, 0.0834, 0.001],
                       "joint": {"type": "revolute", "axis": [0.0, 1.0, 0.0],
                                 "point": [0.0, 0.0, -1.0], "damping": 0.05}}]}
    run = dict(duration=1.0, dt=0.01, q0={"upper.angle": 0.5})
    a = mfm.simulate(mfm.load(cfg), **run)
    b = mfm.simulate(mfm.load(CONFIGS / "double_pendulum.toml"), **run)
    np.testing.assert_array_equal(a.q.values, b.q.values)
    assert a.attrs["config_sha256"] != b.attrs["config_sha256"]


def test_relative_paths_of_a_text_config_need_base(tmp_path, monkeypatch):
    """A text config read from another folder without `base` cannot find its database: the error
    names `base`; a `base` that is not a folder is refused; a bad type says what is accepted."""
    monkeypatch.chdir(tmp_path)
    text = (CONFIGS / "rm3.toml").read_text()
    with pytest.raises(FileNotFoundError, match="base="):
        mfm.load(text)
    with pytest.raises(ValueError, match="base: .* is not a folder"):
        mfm.load(text, base=tmp_path / "nowhere")
    with pytest.raises(TypeError, match="a dict of its tables"):
        mfm.load(42)
    with pytest.raises(mfm.ConfigError, match="<toml text>: not valid TOML"):
        mfm.load("[model\nname = 1")


def test_a_missing_database_of_a_config_with_hulls_says_how_to_make_it(tmp_path):
    """Issue 54 item 7: a config that describes its hulls ([bodies.geometry]) and names a database
    that does not exist yet is told to run `mfm hydro CONFIG`."""
    text = (CONFIGS / "two_flap.toml").read_text()
    assert 'database = "../hydro/data/two_flap.nc"' in text
    cfg = tmp_path / "mine.toml"
    cfg.write_text(text.replace('database = "../hydro/data/two_flap.nc"',
                                'database = "mine.nc"'))
    with pytest.raises(FileNotFoundError, match=r"make its database with `mfm hydro .*mine\.toml`"):
        mfm.load(cfg)
