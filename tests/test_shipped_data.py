"""The shipped data against the shipped configs: every database `mfm hydro` made is current with
its config (keyed on the BEM's inputs only), without capytaine and without a solve."""
import pytest

import mfm
from mfm.io import bemgen

from conftest import CONFIGS
def _shipped_bem_configs():
    import tomllib
    return [c for c in sorted(CONFIGS.glob("*.toml"))
            if "bem" in (tomllib.loads(c.read_text()).get("hydro") or {})]


@pytest.mark.parametrize("config", _shipped_bem_configs(), ids=lambda c: c.stem)
def test_every_shipped_database_is_current_with_its_config(config, capsys, monkeypatch):
    """`mfm hydro CONFIG` on a shipped config finds its database up to date, without a solve: the
    database records the key of the BEM inputs the config gives now (tools/stamp_bem_inputs.py
    verified and recorded it in files made before the key existed)."""
    from hydro import bem as hbem

    monkeypatch.setattr(hbem, "solve", lambda *a, **k: pytest.fail("a BEM solve was started"))
    bemgen.generate(config, progress=False)
    assert "is up to date" in capsys.readouterr().out
    assert bemgen.database_is_stale(config)[0] is False


def test_staleness_keys_on_the_bem_inputs_only(tmp_path):
    """Edits that do not change the BEM's answer (a mass, a comment, a PTO) keep a database
    current; one that does (the panel size, a radius) makes it stale, and the message names it."""
    config = CONFIGS / "m4_111.toml"
    db = (config.parent / "../hydro/data/m4_111.nc").resolve()
    text = config.read_text().replace('"../hydro/data/m4_111.nc"', f'"{db}"')
    edited = tmp_path / "m4_111.toml"
    edited.write_text("# a comment\n" + text.replace("damping = 6.0", "damping = 7.0"))
    assert edited.read_text() != text
    assert bemgen.database_is_stale(edited)[0] is False
    edited.write_text(text.replace("dx = 0.03", "dx = 0.04"))
    stale, why = bemgen.database_is_stale(edited)
    assert stale and "BEM input dx: 0.03 in the database, 0.04 from the config" in why


def test_hydro_on_a_config_without_bem_settings_says_so():
    with pytest.raises(mfm.ConfigError, match=r"no \[hydro.bem\] table.*not made by `mfm hydro`"):
        bemgen.generate(CONFIGS / "sphere.toml", progress=False)


def test_a_copied_config_says_its_database_path_is_relative_to_its_folder(tmp_path):
    import re
    (tmp_path / "rm3.toml").write_text((CONFIGS / "rm3.toml").read_text())
    resolved = str((tmp_path / "../hydro/data/rm3/rm3.out").resolve()).replace(str(tmp_path.parent), "")
    with pytest.raises(FileNotFoundError, match=r"'\.\./hydro/data/rm3/rm3\.out' is relative to the "
                       rf"config's folder {re.escape(repr(str(tmp_path)))}: .*{re.escape(resolved)}' not found"):
        mfm.load(tmp_path / "rm3.toml")


def test_seas_print_with_units():
    import math

    import hydro
    assert str(hydro.Regular(height=2.5, period=8.0)) == "regular wave H 2.5 m, T 8 s"
    assert (str(hydro.Jonswap(hs=2.0, tp=9.0, gamma=3.3, seed=1, heading=math.radians(30.0)))
            == "JONSWAP Hs 2 m, Tp 9 s, γ 3.3, heading 30°, seed 1")


def test_a_users_database_still_warns_once_per_process(tmp_path, monkeypatch):
    """The same RM3 WAMIT files outside hydro/data are a user's database: their three asymmetries
    warn, once per database per process (a second load of the same file is silent, another copy
    warns again); `mfm info`'s list of known issues is empty for them and names the three for
    the shipped file."""
    import shutil
    import warnings

    from hydro import database
    from hydro.database import HydroDatabaseWarning, known_data_issues, validate
    from hydro.prepare import open_any_database

    monkeypatch.setattr(database, "_WARNED", set())
    shipped = CONFIGS.parent / "hydro" / "data" / "rm3"
    copies = []
    for k in range(2):
        (tmp_path / str(k)).mkdir()
        for ext in (".out", ".1", ".3", ".hst"):
            shutil.copy(shipped / f"rm3{ext}", tmp_path / str(k) / f"rm3{ext}")
        copies.append(tmp_path / str(k) / "rm3.out")
    db = open_any_database(copies[0], names=["float", "spar"])     # as configs/rm3.toml names them
    counts = []
    for source in (copies[0], copies[0], copies[1], shipped / "rm3.out"):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            validate(db, source=source)
        counts.append(sum(issubclass(w.category, HydroDatabaseWarning) for w in caught))
    assert counts == [3, 0, 3, 0]
    assert known_data_issues(copies[0]) == []
    assert len(known_data_issues(shipped / "rm3.out")) == 3
    # a larger asymmetry than documented in the shipped file warns
    worse = db.copy(deep=True)
    i, j = (list(worse.influenced_dof.values).index(d) for d in ("float__Sway", "float__Roll"))
    worse["added_mass_inf"][i, j] = 2 * worse["added_mass_inf"][i, j]
    with pytest.warns(HydroDatabaseWarning, match=r"added_mass_inf is not symmetric.*float__Sway"):
        validate(worse, source=shipped / "rm3.out")
