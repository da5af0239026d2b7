"""simulate(compile="fast") (issue 55): every program of a run compiled at XLA's lowest
optimisation level, opt-in: a cheaper first compilation, other last bits than the default's."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

import mfm
from conftest import CONFIGS, ROOT


def test_a_bad_compile_value_names_what_is_accepted():
    m = mfm.load(CONFIGS / "double_pendulum.toml")
    with pytest.raises(ValueError, match=r"compile='quick'.*'default'.*'fast'"):
        mfm.simulate(m, duration=0.1, dt=0.01, compile="quick")


@pytest.mark.parametrize("progress", [False, True])
def test_fast_compiles_every_program_of_the_run_as_one_run_once(monkeypatch, progress):
    """Each program the run asks for (the whole run; or its start and chunks) is asked for with
    ``once=True`` (the once options), the default's with ``once=False``; the result says which."""
    from mfm.runner import pipeline

    asked = []
    real = pipeline._programs.program

    def spy(fn, name, args, static=None, *, once=False):
        if name.startswith("rollout"):     # the run's, not the checks' linearisation (once)
            asked.append((name, once))
        return real(fn, name, args, static, once=once)

    monkeypatch.setattr(pipeline._programs, "program", spy)
    m = mfm.load(CONFIGS / "double_pendulum.toml")
    for mode in ("fast", "default"):
        asked.clear()
        ds = mfm.simulate(m, duration=0.5, dt=0.01, q0={"upper.angle": 0.3}, compile=mode,
                          progress={"disable": True} if progress else False)
        assert ds.attrs["compile"] == mode
        assert asked and all(once == (mode == "fast") for _, once in asked), asked


# In a process at XLA's default flags (the suite's conftest sets level 0 for every program,
# under which both modes are one program): RM3 200 RK4 steps in a regular wave both ways.
SCRIPT = textwrap.dedent("""
    import sys, warnings
    import numpy as np, hydro, mfm
    m = mfm.load(sys.argv[1])
    out = []
    for mode in ("fast", "default"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ds = mfm.simulate(m, hydro.Regular(height=2.5, period=8.0), duration=20.0, dt=0.1,
                              ramp=4.0, compile=mode, check_stability=False)
        out.append(ds)
    for v in ("q", "qd", "qdd", "pto_power"):
        a, b = out[0][v].values, out[1][v].values
        print(v, float(np.max(np.abs(a - b)) / np.max(np.abs(b))), bool(np.array_equal(a, b)))
""")


def test_fast_differs_from_the_default_at_round_off_only(tmp_path):
    """The two compilations differ in their last bits (XLA's default fuses a·b + c into one
    rounding, its lowest level does not): ~1e-16 per operation, grown over 200 steps to
    3e-9–5e-9 of each variable's largest value (measured); 1e-7 bounds it with room for other
    machines' vector widths. Identical arrays would mean the option did not reach XLA."""
    script = tmp_path / "fast.py"
    script.write_text(SCRIPT)
    env = dict(os.environ, PYTHONPATH=str(ROOT), MFM_COMPILATION_CACHE="off",
               MFM_FIT_CACHE=str(tmp_path / "fits"))
    flags = " ".join(f for f in env.get("XLA_FLAGS", "").split()
                     if "optimization_level" not in f and "expensive_passes" not in f)
    env["XLA_FLAGS"] = flags
    env.pop("MFM_FAST_COMPILE", None)
    r = subprocess.run([sys.executable, str(script), str(CONFIGS / "rm3.toml")], env=env,
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    rows = {ln.split()[0]: (float(ln.split()[1]), ln.split()[2] == "True")
            for ln in r.stdout.splitlines() if ln.split() and ln.split()[0] in
            ("q", "qd", "qdd", "pto_power")}
    assert set(rows) == {"q", "qd", "qdd", "pto_power"}, r.stdout
    assert all(rel <= 1e-7 for rel, _ in rows.values()), rows
    assert not all(same for _, same in rows.values()), rows
