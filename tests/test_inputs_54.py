"""Issue 54's input checks that live in mfm: a bad ω grid for natural_frequencies, a heading in
degrees given to frequency_response, a database body no config body names."""
import warnings
from pathlib import Path

import numpy as np
import pytest

import mfm
from hydro.database import HydroDatabaseWarning
from hydro.waves import SeaStateWarning

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


@pytest.fixture(scope="module")
def rm3():
    return mfm.load(CONFIGS / "rm3.toml")


@pytest.mark.parametrize("grid", [np.linspace(-1.0, 2.0, 50), [0.5, np.nan, 1.0], [1.0, 0.5, 2.0],
                                  [0.5, 1.0]])
def test_natural_frequencies_refuses_a_bad_grid(rm3, grid):
    with pytest.raises(ValueError, match="omega_grid: give at least 3 positive, finite, ascending"):
        mfm.natural_frequencies(rm3, omega_grid=grid)


def test_frequency_response_warns_of_a_heading_in_degrees(rm3):
    """RM3's database has the one heading 0: 10π rad (1800°, the same direction) runs, warned."""
    with pytest.warns(SeaStateWarning, match=r"math\.radians\(31\.4"):
        mfm.frequency_response(rm3, [0.5], heading=10 * np.pi, joint_reactions=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SeaStateWarning)
        mfm.frequency_response(rm3, [0.5], heading=0.0, joint_reactions=False)


def test_a_database_body_no_config_body_names_warns(tmp_path):
    """Two-flap's database with the aft flap dropped from the config: it is held fixed, said."""
    text = (CONFIGS / "two_flap.toml").read_text().replace(
        'database = "../hydro/data/two_flap.nc"',
        f'database = "{(CONFIGS.parent / "hydro/data/two_flap.nc").as_posix()}"')
    import tomllib
    cfg = tomllib.loads(text)
    cfg["bodies"] = [b for b in cfg["bodies"] if b["name"] != "aft"]
    for table in ("ptos", "joint_dampers"):
        cfg.pop(table, None)
    with pytest.warns(HydroDatabaseWarning, match=r"\['aft'\].*named by no config body"):
        mfm.load(cfg)
