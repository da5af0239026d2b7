"""Issue 54, item 6: what a command-line user sees names the command line's options.

``mfm simulate configs/hallak_fowt.toml --wave jonswap --hs 2 --tp 10`` stopped on a spectrum
that spills out of the database's ω grid with remedies only a Python user can take
(``omega_range``, ``components.band``); the oversized-run refusal named ``save_every=``; warnings
printed as Python warnings (a source path, the category); a usage error found by a command exited 1
where argparse's exit 2. Here: every such error names the CLI's option (``--omega-min/--omega-max``,
``--save-every``), warnings are one ``mfm: warning: ...`` line, and every usage, config or input
error exits with the one status ``mfm --help`` documents. Each case stops before any stepping
(a few seconds: a model's load, no compilation), except the one short run that shows the remedy
named works.
"""
from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest
from conftest import CONFIGS, ROOT

from mfm_cli import build_parser, main

HALLAK = str(CONFIGS / "hallak_fowt.toml")        # its database's grid: [0.16, 2.05] rad/s
PENDULUM = str(CONFIGS / "double_pendulum.toml")  # no water: a load in a moment
# the JONSWAP of the issue: its default band (0.5 to 5 × 2π/10 s = 0.314 to 3.14 rad/s) spills
# above the grid's 2.05 rad/s
SPILL = ["--wave", "jonswap", "--hs", "2", "--tp", "10"]
FAST = ["--radiation", "none", "--no-plot", "--progress", "off"]   # no radiation kernel, no bar
PYTHON_ONLY = ("omega_range", "components.band", "save_every=", "q0=", "qd0=", "t0=",
               "simulate_batch", "n_components", "math.radians", "Warning:")


def documented_exit() -> int:
    """The exit status ``mfm --help`` documents for a usage, config or input error."""
    text = " ".join(build_parser().format_help().split())
    m = re.search(r"exit status: 0 done; (\d+) a usage, config or input error", text)
    assert m, "mfm --help documents no exit status of a usage error:\n" + text[-600:]
    return int(m[1])


def run_main(argv, capsys):
    """``mfm ARGV`` in this process: (exit status as the shell sees it, stderr)."""
    try:
        code = main(argv)
    except SystemExit as e:      # argparse's, or a command's usage error
        code = e.code
    if isinstance(code, str):    # SystemExit("text"): the interpreter prints it and exits 1
        code = 1
    return (0 if code is None else code), capsys.readouterr().err


def assert_cli_words(err):
    for name in PYTHON_ONLY:
        assert name not in err, f"{name!r} is not a command-line word:\n{err}"


def test_help_documents_the_one_exit_status_of_usage_errors(capsys):
    code = documented_exit()
    assert code == 2                       # argparse's own, which every other error now shares
    import mfm_cli
    from mfm.io import cli

    assert mfm_cli.EXIT_USAGE == cli.EXIT_USAGE == code
    # a bad option value, found by argparse
    assert run_main(["simulate", PENDULUM, "--dt", "fast"], capsys)[0] == code
    # and each command's own help says it too
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    assert f"exit status: 0 done; {code} a usage" in " ".join(capsys.readouterr().out.split())


def test_spectrum_outside_the_grid_names_the_band_options(tmp_path, capsys):
    code, err = run_main(["simulate", HALLAK, *SPILL, "--duration", "1", *FAST,
                          "--out", str(tmp_path / "a.nc")], capsys)
    assert code == documented_exit()
    assert err.startswith("mfm simulate: error: ") and len(err.strip().splitlines()) == 1, err
    assert "[0.16, 2.05] rad/s" in err
    # the end of the band that spills, at the grid's end: the fix to type
    assert "--omega-max 2.05" in err and "--omega-min/--omega-max" in err, err
    assert "mfm hydro CONFIG" in err
    assert_cli_words(err)


def test_the_band_options_are_the_seas_omega_range(capsys):
    """--omega-min/--omega-max map onto hydro.Jonswap's omega_range; one end alone keeps the
    other of the default band (0.5 to 5 × ωp); neither: the sea of before."""
    import math

    from mfm.io.cli import _sea

    parse = lambda *extra: build_parser().parse_args(["simulate", HALLAK, *SPILL, *extra])  # noqa: E731
    wp = 2 * math.pi / 10
    assert _sea(parse("--omega-min", "0.2", "--omega-max", "2.05")).omega_range == (0.2, 2.05)
    assert _sea(parse("--omega-max", "2.05")).omega_range == pytest.approx((0.5 * wp, 2.05))
    assert _sea(parse("--omega-min", "0.4")).omega_range == pytest.approx((0.4, 5 * wp))
    assert _sea(parse()).omega_range is None
    # in optimize too
    args = build_parser().parse_args(["optimize", HALLAK, *SPILL, "--omega-max", "2.05",
                                      "--param", "platform.pitch.damping=0:1e6"])
    assert _sea(args, "optimize").omega_range == pytest.approx((0.5 * wp, 2.05))


def test_the_remedy_named_runs(tmp_path, capsys):
    out = tmp_path / "a.nc"
    code, err = run_main(["simulate", HALLAK, *SPILL, "--omega-max", "2.05", "--duration", "0.2",
                          "--dt", "0.05", *FAST, "--out", str(out)], capsys)
    assert code == 0, err
    assert out.exists()


def test_frequency_domain_grid_errors_name_the_options(tmp_path, capsys):
    """rao's own frequencies outside the grid: its --omega-min/--omega-max, with the grid's ends."""
    code, err = run_main(["rao", HALLAK, "--omega-min", "0.1", "--omega-max", "3",
                          "--out", str(tmp_path / "r.nc")], capsys)
    assert code == documented_exit()
    assert "--omega-min 0.16 --omega-max 2.05" in err and len(err.strip().splitlines()) == 1, err
    assert "omega:" not in err and "choose frequencies inside it" not in err
    assert_cli_words(err)


def test_oversized_run_names_save_every_and_duration(tmp_path, capsys):
    code, err = run_main(["simulate", PENDULUM, "--duration", "1e15", "--no-plot", "--progress",
                          "off", "--out", str(tmp_path / "b.nc")], capsys)
    assert code == documented_exit()
    assert err.startswith("mfm simulate: error: --duration 1e+15 s") and len(err.strip().splitlines()) == 1, err
    assert "--save-every" in err and "--dt" in err, err
    assert_cli_words(err)
    assert not (tmp_path / "b.nc").exists()


@pytest.mark.parametrize("argv, says", [
    (["simulate", PENDULUM, "--initial", "upper.angle"], "--initial 'upper.angle': expected NAME=VALUE"),
    (["simulate", PENDULUM, "--initial-velocity", "upper.angle=fast"], "'fast' is not a number"),
    (["simulate", PENDULUM, "--hs", "2"], "--hs needs --wave regular or --wave jonswap"),
    (["simulate", PENDULUM, "--wave", "jonswap", "--hs", "2"], "--wave jonswap needs --hs (m) and --tp (s)"),
    (["simulate", PENDULUM, "--wave", "regular", "--height", "1", "--period", "8", "--omega-max", "2"],
     "--omega-max sets the band of --wave jonswap"),
    (["simulate", PENDULUM, *SPILL, "--omega-min", "1", "--omega-max", "0.5"],
     "give --omega-min < --omega-max"),
    (["simulate", PENDULUM, "--omega-min", "0"], "--omega-min: '0' is out of range"),
])
def test_bad_option_values_exit_with_the_documented_status(argv, says, tmp_path, capsys):
    code, err = run_main([*argv, "--out", str(tmp_path / "x.nc")], capsys)
    assert code == documented_exit(), err
    assert says in err, err
    assert err.strip().splitlines()[-1].startswith("mfm simulate: error: "), err
    assert_cli_words(err)


def _mfm(*argv, timeout=300):
    # Python's default warning filters, as a user's shell has them (PYTHONWARNINGS=default would
    # add the ResourceWarnings of mfm.runner.checks.usable_memory's unclosed /proc files)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
    return subprocess.run([sys.executable, "-m", "mfm", *argv], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=timeout)


def test_bad_config_path_exits_with_the_documented_status(tmp_path):
    r = _mfm("info", str(tmp_path / "no" / "such.toml"))
    assert r.returncode == documented_exit(), r.stderr
    assert r.stderr.strip() == f"mfm info: error: config file {str(tmp_path / 'no' / 'such.toml')!r} not found"


def test_warnings_are_one_line_without_a_source_path(tmp_path):
    """A band that keeps little of the spectrum (hydro's SeaStateWarning) and a heading beyond a
    turn: each one `mfm: warning: ...` line in the CLI's words; then the error of a band wholly
    above the grid, naming both ends to give."""
    r = _mfm("simulate", HALLAK, *SPILL, "--omega-min", "3", "--heading", "400", "--duration", "1",
             *FAST, "--out", str(tmp_path / "w.nc"))
    assert r.returncode == documented_exit(), r.stderr
    lines = r.stderr.strip().splitlines()
    warns = [ln for ln in lines if "warning" in ln.lower()]
    assert len(warns) == 2 and all(ln.startswith("mfm: warning: ") for ln in warns), r.stderr
    assert not re.search(r"\.py:\d+|<string>:\d+|SeaStateWarning|UserWarning", r.stderr), r.stderr
    band, = (ln for ln in warns if "spectrum's variance" in ln)
    assert "--omega-min 3 --omega-max 3.142" in band and "Widen --omega-min/--omega-max" in band
    heading, = (ln for ln in warns if "--heading" in ln)
    assert "--heading 400° is beyond ±360°: taken as 40°" in heading
    assert lines[-1].startswith("mfm simulate: error: ") and "--omega-min 0.16 --omega-max 2.05" in lines[-1]
    assert len(lines) == 3, r.stderr
    assert_cli_words(r.stderr)


def test_a_heading_beyond_a_turn_warns_in_degrees_in_one_line(tmp_path):
    """--heading 400 (degrees): hydro's warning was a Python one (``<string>:14: SeaStateWarning``)
    in radians naming ``heading=math.radians(...)``; a regular wave outside the grid names the
    --period that fits it."""
    r = _mfm("simulate", HALLAK, "--wave", "regular", "--height", "1", "--period", "50",
             "--heading", "400", "--duration", "1", *FAST, "--out", str(tmp_path / "h.nc"))
    assert r.returncode == documented_exit(), r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 2, r.stderr
    assert lines[0] == ("mfm: warning: --heading 400° is beyond ±360°: taken as 40° (the same "
                        "direction; --heading is in degrees, 0 = waves travelling towards +x)")
    assert lines[1].startswith("mfm simulate: error: ") and "give a --period" in lines[1], lines[1]
    assert "T from 3.065 to 39.27 s" in lines[1]
    assert_cli_words(r.stderr)
