"""Issue 34's first-answer rows: what a new user waits for, each in a fresh process (not a test).

    python benchmarks/first_call.py [--only rm3 rm3_cached m4 m4_cached wu_yuan wu_yuan_fd
                                     wu_yuan_fd_cached optimize optimize_cached yardstick
                                     rm3_fast warm] [--warm-repeats 5]

- ``rm3``: the README's first command (``mfm simulate configs/rm3.toml ...``, the run without the
  install), compilation and fit caches empty (fresh folders). Goal (issue 55) ≤ 5 CPU s.
- ``rm3_cached``: the same in a second fresh process that finds the caches the first filled.
- ``m4``: M4 134, ``mfm.simulate`` with its defaults (RK4, state space), JONSWAP H_s 0.04 m,
  T_p 1.2 s, 100 T_p at dt = T_p/200 (the sea of benchmarks/speed.py), empty caches. Goal ≤ 8 CPU s.
- ``m4_cached``: the same in a second fresh process that finds the caches the first one filled.
  Goal ≤ 1.5 CPU s (``rm3_cached`` the same).
- ``wu_yuan_fd``: ``mfm.frequency_response`` of Wu & Yuan model 1 (configs/wu_yuan_m1.toml) at
  periods 6 and 8 s (the issue's two periods), empty caches; ``wu_yuan_fd_cached``: the same in a
  second fresh process that finds the caches the first filled. Not run unless named in ``--only``.
- ``wu_yuan``: ``mfm simulate configs/wu_yuan_m1_td.toml --wave regular --height 2 --period 8
  --duration 600 --dt 0.05 --progress on --no-plot``, empty caches, with every phase line the command prints (its progress bar on stderr). Goal
  ≤ 15 CPU s, every phase shown.

- ``optimize``: ``mfm.optimize`` of Stansby & Li (configs/stansby_li.toml), its two PTO dampings
  (floatB, floatC: 0 to 4e9 N m s/rad), one sea (JONSWAP H_s 2 m, T_p 9 s, γ 3.3), empty caches;
  ``optimize_cached``: the same in a second fresh process. Goals (issue 55) ≤ 12 and ≤ 2 CPU s.
- ``rm3_fast``: the README's first command with ``--fast-compile`` (``compile="fast"``: every
  program of the run at XLA's lowest optimisation level), empty caches. Not run unless named.
- ``warm``: the issue's row "warm calls, every row" (no slower than 2 %): in one process per
  system, the call of the rows ``rm3`` (``mfm.simulate`` with the README command's arguments and
  its progress bar, drawn nowhere), ``m4``, ``optimize`` and, with ``wu_yuan`` in ``--only``, the
  Wu & Yuan run (its bar too), made once (compiled) and then ``--warm-repeats`` times: the median
  and the least of their wall and CPU seconds (the process's, every thread, over each call).
  Compare trees by running the script under each (``PYTHONPATH=<tree>``), in turn.
- ``yardstick``: a fixed piece of jax work in a fresh process (import jax, trace and compile a
  fixed program: 8 RK4 steps of a 12-state nonlinear oscillator chain, unrolled, XLA's default
  options, no cache): machines differ more than their cores say, so every row is also printed as
  its ratio to this one's CPU seconds, measured in the same run (issue 55's goals hold as such
  ratios on the machine that set them).

Each row also prints what jax did in that process (``mfm.runner.xla.counting``): programs XLA
compiled, programs read back from the compilation cache, functions traced. A counter, not a timer.

"Empty caches" are the disk caches (compiled programs, fits, mooring tables): a database that
stores its config's fit (``mfm fits``, hydro/fitstore.py: M4 134's and Wu & Yuan's do) is read as
any new machine reads it, so the ``m4`` and ``wu_yuan`` rows do not fit; set
``MFM_FIT_CACHE=off`` in the environment to time them fitting too (it turns the stored fits off,
and the ``_cached`` rows then fit again as well).

Each row's wall time is the child process's, from its start (imports and loading included), so a
row is what the user waits for. Beside it, the CPU seconds the process spent (user + system, every
thread): the work of that first answer, whatever the cores; its wall time cannot be less than that
work divided by the machine's cores. Figures depend on the machine and its load: say which when
quoting them.
"""
from __future__ import annotations

import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# each row's call, ``call()`` (made by the row's script and, again and again, by the row warm)
M4_CALL = """
m = mfm.load("configs/m4_134.toml")
sea = hydro.Jonswap(hs=0.04, tp=1.2, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
call = lambda: mfm.simulate(m, sea, duration=120.0, dt=0.006)
"""
OPTIMIZE_CALL = """
m = mfm.load("configs/stansby_li.toml")
sea = hydro.Jonswap(hs=2.0, tp=9.0, gamma=3.3, seed=1, omega_range=(0.3, 2.0))
call = lambda: mfm.optimize(m, sea, {"floatB.angle.damping": (0.0, 4e9),
                                     "floatC.angle.damping": (0.0, 4e9)})
"""
# the warm rows of the README's RM3 command (mfm.simulate with its arguments and its bar, drawn
# nowhere) and of Wu & Yuan's run
RM3_CALL = """
m = mfm.load("configs/rm3.toml")
call = lambda: mfm.simulate(m, hydro.Regular(height=2.5, period=8.0), duration=200.0, dt=0.1,
                            ramp=40.0, progress={"file": open(os.devnull, "w")})
"""
WU_YUAN_CALL = """
m = mfm.load("configs/wu_yuan_m1_td.toml")
call = lambda: mfm.simulate(m, hydro.Regular(height=2.0, period=8.0), duration=600.0, dt=0.05,
                            progress={"file": open(os.devnull, "w")})
"""

# a row's script: its call once, timed from the process's start
ROW = """
import os, time, warnings
t0 = time.perf_counter()
import hydro, mfm
warnings.simplefilter("ignore")
{call}
out = call()
print("PHASES", round(time.perf_counter() - t0, 2))
"""
M4 = ROW.format(call=M4_CALL)

FD = """
import time, warnings
t0 = time.perf_counter()
import numpy as np, mfm
m = mfm.load("configs/wu_yuan_m1.toml")
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    r = mfm.frequency_response(m, 2 * np.pi / np.array([6.0, 8.0]))
print("PHASES", round(time.perf_counter() - t0, 2), float(np.abs(r.rao).max()))
"""


OPTIMIZE = ROW.format(call=OPTIMIZE_CALL)

# a warm row's script: its call made once, then timed ``repeats`` (argv[1]) times in the same
# process
WARM = """
import os, resource, statistics, sys, time, warnings
import hydro, mfm
warnings.simplefilter("ignore")

def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime

{call}
call()
walls, cpus = [], []
for _ in range(int(sys.argv[1])):
    t, c = time.perf_counter(), cpu()
    call()
    walls.append(time.perf_counter() - t)
    cpus.append(cpu() - c)
print("WARM", statistics.median(walls), min(walls), statistics.median(cpus), min(cpus))
"""

YARDSTICK = """
import jax, jax.numpy as jnp
jax.config.update("jax_enable_x64", True)
def f(y):
    # a chain of 6 nonlinear oscillators: 12 states
    x, v = y[:6], y[6:]
    left = jnp.concatenate([x[:1] * 0, x[:-1]])
    right = jnp.concatenate([x[1:], x[:1] * 0])
    a = -jnp.sin(x) - 0.1 * v + 0.5 * (left - 2 * x + right) - 0.05 * x ** 3
    return jnp.concatenate([v, a])
def run(y):
    dt = 0.01
    for _ in range(8):
        k1 = f(y); k2 = f(y + dt / 2 * k1); k3 = f(y + dt / 2 * k2); k4 = f(y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return y
print(float(jax.jit(run)(jnp.linspace(0.1, 0.6, 12)).sum()))
"""

# wraps a row's script or the mfm command: counts what jax did (mfm.runner.xla.counting) and
# prints it on stderr at the end
COUNTED = """
import atexit, runpy, sys
try:
    from mfm.runner.xla import counting
except ImportError:          # a tree before the counter (this script run on an older one)
    counting = None
if counting is not None:
    block = counting()
    c = block.__enter__()
    atexit.register(lambda: print(f"COUNTS compiled={c.compiled} loaded={c.loaded} "
                                  f"traced={c.traced}", file=sys.stderr))
target, sys.argv = sys.argv[1], sys.argv[1:]
runpy.run_path(target, run_name="__main__")
"""


def _counts(stderr: str) -> str:
    m = re.findall(r"COUNTS compiled=(\d+) loaded=(\d+) traced=(\d+)", stderr)
    if not m:
        return ""
    compiled, loaded, traced = m[-1]
    return f" [jax: {compiled} compiled, {loaded} from the cache, {traced} traced]"


def _cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _run(argv, env, cwd):
    """(wall seconds, the finished process, its CPU seconds: user + system, all its threads)."""
    t0, c0 = time.perf_counter(), _cpu_seconds()
    r = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    cpu = _cpu_seconds() - c0
    if r.returncode:
        sys.exit(f"{argv} failed:\n{r.stderr[-3000:]}")
    return wall, r, cpu


def _cores() -> int:
    """The cores this process may run on (its CPU affinity where the system says)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:
        return max(1, os.cpu_count() or 1)


def _work(cpu: float) -> str:
    """A row's CPU seconds and what they bound: its wall time on the cores the row's process
    could use cannot be less than CPU / cores, however its work is scheduled."""
    cores = _cores()
    return f"[CPU {cpu:.1f} s: ≥ {cpu / cores:.1f} s of wall on {cores} cores]"


def _phases(stderr: str) -> list[str]:
    """The distinct phases a tqdm bar's lines said (carriage returns split them): the text after
    its rate in the bracket ("[00:05<?, ?step/s, compiling]"), the steps' own counts left out."""
    seen = []
    for part in re.split(r"[\r\n]", stderr):
        m = re.search(r"\|\s*\d+/\d+ \[[^,\]]*, [^,\]]*/s, ([^\]]+)\]", part)
        if m and m.group(1).strip() not in seen:
            seen.append(m.group(1).strip())
    return _counted(seen)


def _counted(phases: list[str]) -> list[str]:
    """Runs of one phase that counts ("passivity, iteration 3 of at most 40", "order 16 (3 of at
    most 9)") as one entry from its first count to its last."""
    out, last = [], None
    for p in phases:
        key = re.sub(r"\d+", "#", p)
        if key == last and "#" in key:
            out[-1] = (out[-1].split(" … ")[0]) + " … " + p
        else:
            out.append(p)
        last = key
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*",
                    default=["yardstick", "rm3", "rm3_cached", "m4", "m4_cached", "wu_yuan",
                             "optimize", "optimize_cached", "warm"])
    ap.add_argument("--warm-repeats", type=int, default=5,
                    help="the warm calls timed per system (row 'warm'), after one that compiles")
    a = ap.parse_args(argv)
    if a.warm_repeats < 1:
        ap.error(f"--warm-repeats {a.warm_repeats}: give 1 or more")
    print(f"{_cores()} cores, load average {os.getloadavg()[0]:.1f} at the start"
          + ("; PYTHONDONTWRITEBYTECODE set: each process compiles mfm's Python sources"
             if os.environ.get("PYTHONDONTWRITEBYTECODE") else ""))
    yard = None
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name in ("configs", "hydro"):
            (tmp / name).symlink_to(ROOT / name)
        (tmp / "counted.py").write_text(COUNTED)

        def env(tag):
            path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
            return dict(os.environ, PYTHONPATH=path, MPLBACKEND="Agg",
                        MFM_COMPILATION_CACHE=str(tmp / f"jax-{tag}"),
                        # off as asked (every fit made, none read), else a fresh folder
                        MFM_FIT_CACHE="off" if os.environ.get("MFM_FIT_CACHE") == "off"
                        else str(tmp / f"fit-{tag}"))

        def row(label, target, args, tag, goal=None):
            """Run ``target`` (a script or the command) counted, in a fresh process; print its
            line; return (wall, the finished process, CPU)."""
            wall, r, cpu = _run([sys.executable, "counted.py", str(target), *args], env(tag), tmp)
            ratio = f", {cpu / yard:.2f}× the yardstick" if yard else ""
            print(f"{label}: {wall:.1f} s{'' if goal is None else f' (goal ≤ {goal})'} "
                  f"{_work(cpu)}{ratio}{_counts(r.stderr)}")
            return wall, r, cpu

        if "yardstick" in a.only:
            (tmp / "yardstick.py").write_text(YARDSTICK)
            wall, _, cpu = _run([sys.executable, "yardstick.py"],
                                dict(env("yard"), MFM_COMPILATION_CACHE="off"), tmp)
            yard = cpu
            print(f"yardstick (import jax, compile 8 unrolled RK4 steps of 12 states): "
                  f"{wall:.1f} s [CPU {cpu:.2f} s]")
        if "rm3" in a.only:
            line = next(ln for ln in (ROOT / "README.md").read_text().splitlines()
                        if "mfm simulate configs/rm3.toml" in ln)
            cmd = line.split("&&")[-1].strip().split()
            cli = ROOT / "mfm_cli.py"
            row("RM3, the README's first command, empty caches", cli, cmd[1:], "rm3", "5 CPU s")
            if "rm3_cached" in a.only:
                row("RM3, the same in a process after one that filled the caches", cli, cmd[1:],
                    "rm3", "1.5 CPU s")
        if "rm3_fast" in a.only:
            line = next(ln for ln in (ROOT / "README.md").read_text().splitlines()
                        if "mfm simulate configs/rm3.toml" in ln)
            cmd = line.split("&&")[-1].strip().split()
            row("RM3, the README's first command with --fast-compile, empty caches",
                ROOT / "mfm_cli.py", [*cmd[1:], "--fast-compile"], "rm3fast")
        if "m4" in a.only or "m4_cached" in a.only:
            (tmp / "m4.py").write_text(M4)
            row("M4 134 simulate with defaults (120 s at dt 0.006 s), empty caches", "m4.py", [],
                "m4", "8 CPU s")
            if "m4_cached" in a.only:
                row("M4 134, the same in a process after one that filled the caches", "m4.py", [],
                    "m4", "1.5 CPU s")
        if "wu_yuan_fd" in a.only or "wu_yuan_fd_cached" in a.only:
            (tmp / "fd.py").write_text(FD)
            row("Wu & Yuan m1 frequency_response at two periods, empty caches", "fd.py", [], "fd")
            if "wu_yuan_fd_cached" in a.only:
                row("Wu & Yuan m1 frequency_response, the same in a process after one that "
                    "filled the caches", "fd.py", [], "fd")
        if "optimize" in a.only or "optimize_cached" in a.only:
            (tmp / "optimize.py").write_text(OPTIMIZE)
            row("optimize Stansby & Li, two dampings, one sea, empty caches", "optimize.py", [],
                "opt", "12 CPU s")
            if "optimize_cached" in a.only:
                row("optimize Stansby & Li, the same in a process after one that filled the "
                    "caches", "optimize.py", [], "opt", "2 CPU s")
        if "wu_yuan" in a.only:
            out = tmp / "wy.nc"
            _, r, _ = row("Wu & Yuan m1 time domain, 600 s, empty caches", ROOT / "mfm_cli.py",
                          ["simulate", "configs/wu_yuan_m1_td.toml", "--wave", "regular",
                           "--height", "2", "--period", "8", "--duration", "600", "--dt", "0.05",
                           "--progress", "on", "--no-plot", "--out", str(out)], "wy",
                          "15 CPU s")
            print(f"    phases shown: {_phases(r.stderr) or 'none'}")
        if "warm" in a.only:
            systems = {"rm3": ("RM3, the README command's simulate", RM3_CALL),
                       "m4": ("M4 134 simulate defaults", M4_CALL),
                       "optimize": ("optimize Stansby & Li", OPTIMIZE_CALL),
                       "wu_yuan": ("Wu & Yuan m1 time domain, 600 s", WU_YUAN_CALL)}
            for system, (label, call) in systems.items():
                if system == "wu_yuan" and "wu_yuan" not in a.only:
                    continue
                (tmp / f"warm_{system}.py").write_text(WARM.format(call=call))
                _, r, _ = _run([sys.executable, f"warm_{system}.py", str(a.warm_repeats)],
                               env(f"warm-{system}"), tmp)
                w_med, w_min, c_med, c_min = (float(v) for v in r.stdout.split("WARM")[-1].split())
                print(f"{label}, warm (the same call again in its process, {a.warm_repeats} "
                      f"times): median {w_med:.3f} s (least {w_min:.3f}) [CPU median {c_med:.3f} s, "
                      f"least {c_min:.3f}]")
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
