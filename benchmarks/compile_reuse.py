"""Models that differ only in numbers share one compilation (issue 34's row "models differing only
in numbers"): the first call of each model in one process, and how many programs the solver's jit
caches hold after it. Prints a table; not a test.

    MFM_COMPILATION_CACHE=off MFM_FIT_CACHE=off OMP_NUM_THREADS=1 \\
        python benchmarks/compile_reuse.py [--configs wu_yuan_m1 wu_yuan_m2 wu_yuan_m3]

Each model: ``mfm.load`` (not timed), then ``mfm.frequency_response(model, [0.6, 0.8])`` (two
periods, as the issue measured). The columns: its wall time, the XLA compilations it made (jax's
compile events: every program, down to the small ones of the host's eager arithmetic), of them
the jet at rest's (``mfm.frequency.rest._static_jet``) and the joint reactions'
(``mfm.frequency.response._reaction_derivatives``), and the rollout's traces
(``TRACES["rollout"]``, 0 here: the time domain's reuse is tests/test_jax_contract.py's): the jet
and the reactions once for a structure, whatever the numbers. Turn the compilation and fit caches off (above) so
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
    import collections

    from jax._src import monitoring

    import mfm
    from mfm.timedomain.rollout import TRACES

    compiled = collections.Counter()          # XLA compilations by the program's name

    def listen(event, duration, **kw):
        if event.endswith("backend_compile_duration"):
            compiled[kw.get("fun_name", "?")] += 1

    monitoring.register_event_duration_secs_listener(listen)
    print(f"{'model':<16s} {'call':<20s} {'first call':>11s} {'compiled':>9s} {'jet':>4s} "
          f"{'reactions':>10s} {'rollout':>8s}")
    for name in args.configs:
        model = mfm.load(f"configs/{name}.toml")
        calls = [("frequency_response", lambda: mfm.frequency_response(model, [0.6, 0.8]))]
        for what, call in calls:
            compiled.clear()
            t = time.perf_counter()
            call()
            wall = time.perf_counter() - t
            print(f"{name:<16s} {what:<20s} {wall:10.1f}s {sum(compiled.values()):9d} "
                  f"{compiled['jit(_static_jet)']:4d} {compiled['jit(_reaction_derivatives)']:10d} "
                  f"{TRACES['rollout']:8d}", flush=True)


if __name__ == "__main__":
    main()
