"""A fresh process's first answer with warm caches, this tree against another, alternated (not a test).

    python benchmarks/process_ab.py --other DIR [--repeats 5] [--rows script cli]

DIR is a checkout of another commit (``git worktree add /tmp/before REV``). Each row runs the
README's RM3 case (regular wave H 2.5 m, T 8 s, 200 s at dt 0.1, ramp 40 s) in a new Python
process with ``PYTHONPATH`` set to one tree, from import to exit:

- ``script``: through the Python API (``mfm.load`` then ``mfm.simulate``), as a user's script;
- ``script_frozen``: the same script with ``gc.freeze()`` after its imports in this tree (the
  other tree's is the plain script: before issue 52, ``import mfm`` froze);
- ``cli``: through the command's entry point (``mfm_cli.main([...])``, no figure).

The two trees run in turn (this, other, this, other, …) after one warm-up of each, which also
fills the compilation and fit caches (the user's default folders: both trees share them, each
keyed by its own code). Prints per row the median CPU seconds (user + system of the child) and
wall seconds of each tree and the median of the pair-by-pair ratios this/other. Figures depend on
the machine and its load: quote ratios, and say which machine.
"""
from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

SCRIPT = """
import sys
import hydro
import mfm
m = mfm.load(sys.argv[1] + "/configs/rm3.toml")
ds = mfm.simulate(m, hydro.Regular(height=2.5, period=8.0), duration=200.0, dt=0.1, ramp=40.0)
print(float(ds["pto_power"].isel(time=slice(1000, None)).mean()))
"""
CLI = """
import sys
from mfm_cli import main
sys.exit(main(["simulate", sys.argv[1] + "/configs/rm3.toml", "--wave", "regular", "--height",
               "2.5", "--period", "8", "--duration", "200", "--dt", "0.1", "--ramp", "40",
               "--out", sys.argv[2], "--no-plot"]))
"""
# the script as README § Speed advises: the libraries' objects out of the collector's walks
SCRIPT_FROZEN = SCRIPT.replace("import mfm\n", "import mfm\nimport gc\ngc.freeze()\n", 1)
ROWS = {"script": SCRIPT, "script_frozen": SCRIPT_FROZEN, "cli": CLI}


def run(tree: Path, code: str, out: Path) -> tuple[float, float]:
    """(CPU seconds, wall seconds) of one child process."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code, str(tree), str(out)], env=env, check=True,
                   stdout=subprocess.DEVNULL, cwd=tree)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--other", type=Path, required=True, help="a checkout of the other commit")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--rows", nargs="+", choices=tuple(ROWS), default=list(ROWS))
    args = ap.parse_args(argv)
    trees = {"this": ROOT, "other": args.other.resolve()}
    out = Path(os.environ.get("TMPDIR", "/tmp")) / "process_ab.nc"
    print(f"this {trees['this']}, other {trees['other']}; {os.cpu_count()} CPUs; "
          f"{args.repeats} pairs after one warm-up each")
    for row in args.rows:
        code = ROWS[row]
        codes = {"this": code, "other": SCRIPT if row == "script_frozen" else code}
        for name, tree in trees.items():
            run(tree, codes[name], out)              # warm-up: fills the caches
        got = {name: [] for name in trees}
        for _ in range(args.repeats):
            for name, tree in trees.items():
                got[name].append(run(tree, codes[name], out))
        cpu = {n: statistics.median(c for c, _ in v) for n, v in got.items()}
        wall = {n: statistics.median(w for _, w in v) for n, v in got.items()}
        ratio = statistics.median(a[0] / b[0] for a, b in zip(got["this"], got["other"]))
        print(f"{row:7s} CPU s this {cpu['this']:.2f}, other {cpu['other']:.2f}, "
              f"ratio this/other {ratio:.3f}; wall s this {wall['this']:.2f}, "
              f"other {wall['other']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
