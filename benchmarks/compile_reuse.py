"""Models that differ only in numbers share one compilation (issue 34's row "models differing only
in numbers"): the first call of each model in one process, and how many programs the solver's jit
caches hold after it. Prints a table; not a test.

    MFM_COMPILATION_CACHE=off MFM_FIT_CACHE=off OMP_NUM_THREADS=1 \\
        python benchmarks/compile_reuse.py [--configs wu_yuan_m1 wu_yuan_m2 wu_yuan_m3]

Each model: ``mfm.load`` (not timed), then ``mfm.frequency_response(model, [0.6, 0.8])`` (two
periods, as the issue measured). The columns: its wall time, and the number of
compiled programs of the jet at rest (``mfm.frequency.rest._static_jet``), of the joint reactions
(``mfm.frequency.response._reaction_derivatives``) and of the rollout (``TRACES["rollout"]``,
0 here: the time domain's reuse is tests/test_jax_contract.py's): one each for a structure,
whatever the numbers. Turn the compilation and fit caches off (above) so
that a first call is a first call. What a later model still pays is host work in numpy (its
water's preparation: the consistent A∞, the radiation fit), not compilation.
"""
from __future__ import annotations

import argparse
import time
import warnings


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", nargs="+", default=["wu_yuan_m1", "wu_yuan_m2", "wu_yuan_m3"],
                    help="config stems in configs/ (models of one structure)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    import mfm
    from mfm.frequency import response, rest
    from mfm.timedomain.rollout import TRACES

    print(f"{'model':<16s} {'call':<20s} {'first call':>11s} {'jet':>4s} {'reactions':>10s} "
          f"{'rollout':>8s}")
    for name in args.configs:
        model = mfm.load(f"configs/{name}.toml")
        calls = [("frequency_response", lambda: mfm.frequency_response(model, [0.6, 0.8]))]
        for what, call in calls:
            t = time.perf_counter()
            call()
            wall = time.perf_counter() - t
            print(f"{name:<16s} {what:<20s} {wall:10.1f}s {rest._static_jet._cache_size():4d} "
                  f"{response._reaction_derivatives._cache_size():10d} {TRACES['rollout']:8d}",
                  flush=True)


if __name__ == "__main__":
    main()
