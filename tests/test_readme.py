"""README.md as a document: every ```python block runs as written (smoke sizes: MFM_SMOKE=1), each
in its own namespace (so none leans on names of another), all in one subprocess (imports and
compilations shared); the sensitivity example's derivative matches a central difference; every
file the README links to is in the repository.
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import pytest
from conftest import ROOT

README = ROOT / "README.md"

# appended to the sensitivity block, in its namespace: the same compiled `sweep` (same shape, no
# recompilation) at c ± h gives the central difference
SENSITIVITY_CHECK = """
_c, _h = 1.2e6, 1e3
_P, _D = sweep(jnp.array([_c - _h, _c, _c + _h, _c, _c, _c]))
_fd = (_P[2] - _P[0]) / (2 * _h)
assert abs(_D[1] - _fd) <= 1e-4 * abs(_fd), (float(_D[1]), float(_fd))
assert abs(_D[1]) * _c > 0.05 * _P[1], "trivial sensitivity"     # not the 6e-15 of a dry model
print("SENSITIVITY", float(_D[1]), float(_fd), float(_P[1]))
"""

RUNNER = """
import json, sys, time, traceback
blocks = json.load(open(sys.argv[1]))
for i, code in enumerate(blocks):
    t0 = time.perf_counter()
    ns = {"__name__": "__readme__"}
    try:
        exec(compile(code, f"README block {i + 1}", "exec"), ns)
    except Exception:
        print(f"BLOCK {i + 1} FAILED", flush=True)
        traceback.print_exc()
        sys.exit(1)
    print(f"BLOCK {i + 1} OK {time.perf_counter() - t0:.1f} s", flush=True)
"""


def python_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


@pytest.mark.slow            # about 6 minutes: four compilations of RM3 and M4 134 with water
def test_readme_python_blocks_run(tmp_path):
    blocks = python_blocks(README.read_text())
    assert len(blocks) >= 4
    sens = [i for i, b in enumerate(blocks) if "def mean_power" in b]
    assert len(sens) == 1, "the sensitivity example is missing"
    blocks[sens[0]] += SENSITIVITY_CHECK
    # run where the README's relative paths hold (configs/, hydro/data via ../hydro from configs/)
    # without writing into the repository
    for name in ("configs", "hydro"):
        (tmp_path / name).symlink_to(ROOT / name)
    (tmp_path / "blocks.json").write_text(json.dumps(blocks))
    (tmp_path / "runner.py").write_text(RUNNER)
    # os.environ carries conftest's XLA_FLAGS (the cheapest optimisation: compiling is most of
    # these short runs)
    env = dict(os.environ, MFM_SMOKE="1", MPLBACKEND="Agg", PYTHONPATH=str(ROOT),
               OPENBLAS_NUM_THREADS="1")
    r = subprocess.run([sys.executable, "runner.py", "blocks.json"], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=900)
    print(r.stdout[-3000:])
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-4000:]
    assert r.stdout.count(" OK ") == len(blocks)
    assert "SENSITIVITY" in r.stdout


def test_readme_links_stay_inside_the_repository():
    text = README.read_text()
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        if target.startswith(("http://", "https://")):
            continue
        assert (ROOT / target).exists(), f"README links to {target}, which is not in the repository"
    for path in re.findall(r"`((?:docs|notebooks|hydro/data|configs|benchmarks)/[\w./-]+\.\w+)`", text):
        assert (ROOT / path).exists(), f"README names {path}, which is not in the repository"
    assert "GEOMETRY.md" not in text or (ROOT / "docs" / "GEOMETRY.md").exists()
    assert "TIMING_PLACEHOLDER" not in text


def test_papers_cited_in_full_and_documents_in_the_repository():
    """"seed 001" and GEOMETRY.md are named in the README and configs: the papers are cited by
    authors and title (docs/references.md), GEOMETRY.md is in docs/, no path leaves the repo."""
    text = README.read_text()
    assert "[`docs/references.md`](docs/references.md)" in text
    assert "Lande-Sudall" in text and "Moving Frame Method*" in text
    refs = (ROOT / "docs" / "references.md").read_text()
    for who in ("Hallak", "Lande-Sudall", "Stansby", "Wu, Z. Yuan"):
        assert who in refs
    assert (ROOT / "docs" / "GEOMETRY.md").exists()
    for cfg in sorted((ROOT / "configs").rglob("*.toml")):
        body = cfg.read_text()
        assert "shared/" not in body, f"{cfg.name} points outside the repository"
        for rel in re.findall(r"(\.\./[\w./]*GEOMETRY\.md)", body):
            assert (cfg.parent / rel).resolve().exists(), (cfg.name, rel)


def test_readme_lists_every_shipped_config_and_notebook():
    """Issue 54 item 11: a user finds every config and notebook from the README (6 of 20 configs
    were named there)."""
    text = (ROOT / "README.md").read_text()
    configs = sorted(p.relative_to(ROOT / "configs").as_posix()
                     for p in (ROOT / "configs").rglob("*.toml"))
    missing = [c for c in configs if f"`{c}`" not in text]
    assert not missing, f"configs not named in the README: {missing}"
    notebooks = sorted(p.name for p in (ROOT / "notebooks").glob("*.ipynb"))
    missing = [n for n in notebooks if f"`{n}`" not in text]
    assert not missing, f"notebooks not named in the README: {missing}"
    assert '".[notebooks]"' in text and "jupyter lab" in text
