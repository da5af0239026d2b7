"""The timings the README quotes, measured: the first command of "On a new machine" (the run,
without the install) and each Python block of the Quickstart (wall time and peak memory), each in
a fresh process, as a new user runs them.

    python benchmarks/readme_timings.py               # every block as written (several minutes)
    python benchmarks/readme_timings.py --smoke       # MFM_SMOKE=1: the shortened blocks
    python benchmarks/readme_timings.py --blocks 1 2  # some blocks only (1-based); --no-command

Wall times include the imports, the loading of the data and every compilation (a first run);
peak memory is the process's maximum resident set (ru_maxrss). Runs in a temporary folder with
configs/ and hydro/ linked, so nothing is written into the repository. The figures depend on the
machine and its load: say which machine and load when quoting them.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# runs one block in this process, then prints its wall time and peak resident memory
RUNNER = r"""
import json, resource, sys, time
t0 = time.perf_counter()
exec(compile(open(sys.argv[1]).read(), "<README block>", "exec"), {"__name__": "__main__"})
wall = time.perf_counter() - t0
kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss          # KiB on Linux
print("TIMING " + json.dumps({"wall_s": wall, "peak_gib": kib / 2**20}), flush=True)
"""


def python_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def first_command(text: str) -> list[str]:
    """The README's first `mfm simulate` command of "On a new machine", without the install."""
    line = next(l for l in text.splitlines() if "mfm simulate configs/rm3.toml" in l)
    cmd = line.split("&&")[-1].strip()
    argv = shlex.split(cmd)
    return [sys.executable, str(ROOT / "mfm_cli.py"), *argv[1:]]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smoke", action="store_true", help="MFM_SMOKE=1 (the shortened blocks)")
    ap.add_argument("--blocks", type=int, nargs="*", help="1-based block numbers (default: all)")
    ap.add_argument("--no-command", action="store_true", help="skip the first command")
    args = ap.parse_args()
    text = (ROOT / "README.md").read_text()
    blocks = python_blocks(text)
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT))
    if args.smoke:
        env["MFM_SMOKE"] = "1"
    else:
        env.pop("MFM_SMOKE", None)
    load = os.getloadavg()[0]
    print(f"{os.cpu_count()} cores, load average {load:.1f} at the start, "
          f"{'smoke' if args.smoke else 'full'} mode")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name in ("configs", "hydro"):
            (tmp / name).symlink_to(ROOT / name)
        (tmp / "runner.py").write_text(RUNNER)
        if not args.no_command:
            cmd = first_command(text)
            t0 = time.perf_counter()
            r = subprocess.run(cmd, cwd=tmp, env=env, capture_output=True, text=True)
            wall = time.perf_counter() - t0
            if r.returncode:
                sys.exit(f"the first command failed:\n{r.stderr[-3000:]}")
            print(f"first command (the run, without the install): {wall:.1f} s  "
                  f"[{' '.join(shlex.quote(c) for c in cmd[2:])}]")
        for i in args.blocks or range(1, len(blocks) + 1):
            (tmp / f"block{i}.py").write_text(blocks[i - 1])
            r = subprocess.run([sys.executable, "runner.py", f"block{i}.py"], cwd=tmp, env=env,
                               capture_output=True, text=True)
            found = [l for l in r.stdout.splitlines() if l.startswith("TIMING ")]
            if r.returncode or not found:
                sys.exit(f"Python block {i} failed:\n{r.stderr[-3000:]}")
            t = json.loads(found[-1][7:])
            first = blocks[i - 1].strip().splitlines()
            what = next((l for l in first if "mfm.load" in l or "simulate" in l), first[0])
            print(f"Python block {i}: {t['wall_s']:.1f} s, peak memory {t['peak_gib']:.2f} GiB  "
                  f"[{what.strip()[:70]}]")
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
