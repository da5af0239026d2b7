"""Judge each config's default state-space fit on its own modes (mfm.frequency.fitcheck), and the
convolution the same way: the verdict, the worst mode and the seconds of each step (RESULTS.md,
issue 51). Usage: python benchmarks/judge_fits.py configs/rm3.toml configs/m4_134.toml …"""
import sys, time, warnings
warnings.simplefilter("ignore")
import numpy as np, mfm
from mfm.frequency.rest import linear_system
from mfm.frequency.fitcheck import judge_fit
for c in sys.argv[1:]:
    m = mfm.load(c)
    if m.hydro is None: continue
    t0 = time.perf_counter(); s = linear_system(m); t1 = time.perf_counter()
    m.hydro.state_space(); t2 = time.perf_counter()
    j = judge_fit(m, s); t3 = time.perf_counter()
    jc = judge_fit(m, s, radiation="convolution"); t4 = time.perf_counter()
    print(f"{c}: n_q {m.n_coordinates} modes {len(j.modes)} ok {j.ok} err {j.mode_error:.3g} conv err {jc.mode_error:.3g}  lin {t1-t0:.2f}s fit {t2-t1:.2f}s judge {t3-t2:.2f}s conv {t4-t3:.2f}s")
    for md in j.modes[:3]: print("   ", md)
