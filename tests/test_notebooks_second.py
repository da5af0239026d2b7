"""The second half of the notebooks (design, hallak_fwwp, wu_yuan) in smoke mode (tests/test_cli_notebooks.py runs the rest; the
split lets the two pytest workers share them under --dist loadfile)."""
import pytest
from conftest import ROOT
from test_cli_notebooks import NOTEBOOKS, SECOND, run_in_smoke_mode

PATHS = [ROOT / "notebooks" / f"{name}.ipynb" for name in SECOND]


def test_the_split_covers_every_notebook_once():
    assert all(p.exists() for p in PATHS), [p for p in PATHS if not p.exists()]
    assert set(NOTEBOOKS) >= set(PATHS)


@pytest.mark.parametrize("path", PATHS, ids=[p.stem for p in PATHS])
def test_notebook_runs_in_smoke_mode(path, monkeypatch):
    run_in_smoke_mode(path, monkeypatch)
