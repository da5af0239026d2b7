"""The default radiation state-space fit against the database and the convolution on the two-flap
test device (configs/two_flap.toml, issue 51). Not a test: it prints numbers.

    OMP_NUM_THREADS=2 .venv/bin/python benchmarks/two_flap_fit.py [CONFIG] [--no-decay]

With the public API only:
1. ``mfm.natural_frequencies(model, radiation=r)`` for r = "database", "state_space",
   "convolution": each mode's period, damping ratio (the PTO's, ζ_lin, and radiation's, ζ_rad)
   and shape, and the minima of the damped |det Λ(ω)| (the impedance's resonances: two modes
   "merged" when one minimum is left for two); then the flap modes' total damping ζ_lin + ζ_rad,
   state space and convolution against the database, for the config's PTO and a range of PTOs.
2. ``mfm.frequency_response(model, ω, radiation=r)`` over a window about the flap modes: the hinge
   RAOs' largest difference from the database's, relative to the database's peak, and the peaks.
3. ``mfm.runner.choices.choose_radiation`` (what ``radiation="auto"`` takes, and why) for a
   3-hour sea state at dt 0.1 s and for the decay run below.
4. A free decay from ``fore.angle`` = 0.1 rad in still water, ``mfm.simulate`` with the defaults
   (radiation="auto"), radiation="convolution" and radiation="state_space": the hinge angles'
   largest difference from the convolution's, relative to the convolution's largest angle. The
   decay's length and step are chosen so that "auto" takes the state space (the convolution's
   work above AUTO_CONVOLUTION_LIMIT), as a long sea state does.

The fit cache is off (``MFM_FIT_CACHE=off``): each run fits afresh (≈ 1 s).
"""
import argparse
import math
import os
import re
import tempfile
import time
import warnings
from pathlib import Path

os.environ.setdefault("MFM_FIT_CACHE", "off")
import numpy as np

import hydro
import mfm
from mfm.runner.choices import choose_radiation

warnings.simplefilter("ignore", hydro.database.HydroDatabaseWarning)
ROOT = Path(__file__).resolve().parents[1]
STRATEGIES = ("database", "state_space", "convolution")
FLAPS = ("fore", "aft")


def natural(model, strategies=STRATEGIES, quiet=False):
    """{strategy: natural_frequencies Dataset, or the error's text}."""
    out = {}
    for r in strategies:
        t0 = time.perf_counter()
        try:
            nat = mfm.natural_frequencies(model, radiation=r)
        except Exception as e:            # "convolution" may raise LinAlgError: reported, not fixed
            out[r] = f"{type(e).__name__}: {e}"
            if not quiet:
                print(f"natural_frequencies(radiation={r!r}) raised {out[r][:200]}")
            continue
        out[r] = nat
        if quiet:
            continue
        coords = [str(c) for c in nat["coordinate"].values]
        print(f"natural_frequencies(radiation={r!r}): {time.perf_counter() - t0:.1f} s")
        print(f"  {'mode':>4} {'ω rad/s':>8} {'T s':>7} {'ζ_lin':>7} {'ζ_rad':>7} {'ζ total':>7}  shape "
              f"({', '.join(coords)}; largest = 1)")
        for k in range(nat.sizes["mode"]):
            phi = nat["modes"].values[:, k]
            zl, zr = float(nat["damping_ratio"][k]), float(nat["radiation_damping_ratio"][k])
            print(f"  {k:4d} {float(nat['eigen'][k]):8.4f} {float(nat['period'][k]):7.3f} {zl:7.4f} "
                  f"{zr:7.4f} {zl + zr:7.4f}  " + " ".join(f"{v:+.2f}" for v in phi / np.abs(phi).max())
                  + f"  {label(nat, k)}")
        dd = nat["min_det_damped"].values
        print(f"  min |det Λ| damped: ω {np.round(dd, 4)} rad/s, T {np.round(2 * np.pi / dd, 3)} s")
    return out


def label(nat, k):
    """'flaps in phase' / 'flaps anti-phase' where the hinges lead the mode, else 'hub'."""
    coords = [str(c) for c in nat["coordinate"].values]
    phi = nat["modes"].values[:, k]
    f = np.array([phi[coords.index(f"{b}.angle")] for b in FLAPS])
    if np.abs(f).max() < 0.3 * np.abs(phi).max():
        return "hub"
    return "flaps in phase" if f[0] * f[1] > 0 else "flaps anti-phase"


def flap_modes(nat):
    """{label: (period s, ζ_lin, ζ_rad)} of the flap modes."""
    out = {}
    for k in range(nat.sizes["mode"]):
        lab = label(nat, k)
        if lab != "hub":
            out[lab] = (float(nat["period"][k]), float(nat["damping_ratio"][k]),
                        float(nat["radiation_damping_ratio"][k]))
    return out


def damping_table(nats, title):
    ref = flap_modes(nats["database"])
    print(title)
    print(f"  {'mode':<17} {'strategy':<12} {'T s':>7} {'ζ_lin':>7} {'ζ_rad':>7} {'ζ total':>7} "
          f"{'ζ_rad/db':>8} {'ζ total/db':>10}")
    for lab, (T0, zl0, zr0) in ref.items():
        for r in STRATEGIES:
            if not isinstance(nats.get(r), type(nats["database"])):
                print(f"  {lab:<17} {r:<12} {nats.get(r, '')!s:.60}")
                continue
            T, zl, zr = flap_modes(nats[r]).get(lab, (math.nan,) * 3)
            print(f"  {lab:<17} {r:<12} {T:7.3f} {zl:7.4f} {zr:7.4f} {zl + zr:7.4f} "
                  f"{zr / zr0:8.2f} {(zl + zr) / (zl0 + zr0):10.2f}")


def with_pto(config, damping):
    """A copy of the config (in a temporary folder, the database path made absolute) with every
    joint damper set to ``damping``."""
    text = Path(config).read_text()
    db = re.search(r'^database\s*=\s*"([^"]+)"', text, re.M).group(1)
    text = text.replace(f'"{db}"', f'"{(Path(config).parent / db).resolve()}"', 1)
    text = re.sub(r"^damping\s*=\s*[0-9.eE+-]+", f"damping = {damping:.6g}", text, flags=re.M)
    path = Path(tempfile.mkdtemp()) / Path(config).name
    path.write_text(text)
    return path


def responses(model, omega):
    fr = {}
    for r in STRATEGIES:
        try:
            fr[r] = mfm.frequency_response(model, omega, radiation=r)
        except Exception as e:
            print(f"frequency_response(radiation={r!r}) raised {type(e).__name__}: {e}"[:300])
    print(f"frequency_response over {omega[0]:.3f}–{omega[-1]:.3f} rad/s ({len(omega)} ω), heading 0:")
    print(f"  {'hinge':<11} {'strategy':<12} {'peak |RAO| rad/m':>16} {'at ω':>7} {'peak/db':>7} "
          f"{'max|ΔRAO|/db peak':>17} {'at ω':>7}")
    for b in FLAPS:
        c = f"{b}.angle"
        a0 = fr["database"]["rao"].sel(coordinate=c).values
        for r, ds in fr.items():
            a = ds["rao"].sel(coordinate=c).values
            rel = np.abs(a - a0) / np.abs(a0).max()
            j, i = int(np.argmax(np.abs(a))), int(np.argmax(rel))
            print(f"  {c:<11} {r:<12} {np.abs(a[j]):16.4g} {omega[j]:7.4f} "
                  f"{np.abs(a).max() / np.abs(a0).max():7.3f} {rel.max():17.3f} {omega[i]:7.4f}")


def decay(model, duration, dt, angle=0.1):
    n = int(round(duration / dt))
    name, why = choose_radiation(model, dt=dt, n_steps=n, integrator="rk4")
    print(f"decay from fore.angle = {angle} rad, {duration:g} s at dt {dt:g} s (rk4): "
          f"radiation='auto' takes {name!r}\n  reason: {why}")
    runs = {}
    for r in ("auto", "convolution", "state_space"):
        t0 = time.perf_counter()
        kw = {} if r == "auto" else {"radiation": r}
        runs[r] = mfm.simulate(model, None, duration=duration, dt=dt, q0={"fore.angle": angle}, **kw)
        print(f"  simulate(radiation={r!r}): {time.perf_counter() - t0:.1f} s")
    ref = runs["convolution"]
    print(f"  {'run':<12} {'hinge':<11} {'max|Δθ|/max|θ_conv|':>20} {'at t s':>7}  "
          f"{'|θ| at t = 600 s, 1200 s (conv: …)':>30}")
    t = ref["time"].values
    for r in ("auto", "state_space"):
        for b in FLAPS:
            c = f"{b}.angle"
            a, q = runs[r]["q"].sel(coordinate=c).values, ref["q"].sel(coordinate=c).values
            d = np.abs(a - q)
            i = int(np.argmax(d))
            env = [(np.abs(a[(t >= s - 15) & (t <= s + 15)]).max(), np.abs(q[(t >= s - 15) & (t <= s + 15)]).max())
                   for s in (600.0, 1200.0) if s + 15 <= t[-1]]
            print(f"  {r:<12} {c:<11} {d.max() / np.abs(q).max():20.3f} {t[i]:7.1f}  "
                  + ", ".join(f"{x:.4f} (conv {y:.4f})" for x, y in env))
    return runs


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("config", nargs="?", default=str(ROOT / "configs" / "two_flap.toml"))
    ap.add_argument("--duration", type=float, default=6000.0,
                    help="decay length, s (default 6000: long enough for 'auto' to take the state space at dt 0.05)")
    ap.add_argument("--dt", type=float, default=0.05)
    ap.add_argument("--no-decay", action="store_true")
    ap.add_argument("--ptos", default="3e4,1e5,1e6,1e7", help="PTO dampings (N m s/rad) for the damping table")
    args = ap.parse_args()

    model = mfm.load(args.config)
    spec = model.hydro
    ss = spec.state_space()
    rep = ss.report
    print(f"{args.config}\nwave band (fit band) {tuple(round(x, 4) for x in spec.wave_band())} rad/s; "
          f"memory T_K {spec.memory():.3g} s; fit: {rep['n_states']} states, pole sharing "
          f"{rep['pole_sharing']}, band error {rep['overall_error']:.4f}, passive {rep['passive']}")

    nats = natural(model)
    damping_table(nats, "flap modes, the config's PTO:")
    for c in [float(x) for x in args.ptos.split(",") if x]:
        m = mfm.load(with_pto(args.config, c))
        damping_table(natural(m, quiet=True), f"flap modes, PTO {c:.3g} N m s/rad on each hinge:")

    w = [float(nats["database"]["eigen"][k]) for k in range(nats["database"].sizes["mode"])
         if label(nats["database"], k) != "hub"]
    omega = np.linspace(0.85 * min(w), 1.15 * max(w), 401)
    responses(model, omega)

    for dur, dt in ((3 * 3600.0, 0.1),):
        name, why = choose_radiation(model, dt=dt, n_steps=int(round(dur / dt)), integrator="rk4")
        print(f"choose_radiation for a {dur / 3600:g} h sea state at dt {dt} s: {name!r}\n  reason: {why}")
    if not args.no_decay:
        decay(model, args.duration, args.dt)


if __name__ == "__main__":
    main()
