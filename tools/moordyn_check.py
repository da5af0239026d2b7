"""The Wu & Yuan moorings (configs/wu_yuan_m<m>.toml, seed 004 Table 2): the engine's quasi-static
catenary lines (mfm.loads.catenary, MoorPy's catenary tabulated) against MoorDyn's lumped-mass lines
(the seed's own line model, its eq. 28; Hall & Goupee 2015) in the seed's severe sea.

What it does:

1. Locks the twelve hinges (``locked = true``, as the seed does in the severe sea; their preloads and
   PTO dampers go with them) and takes the platform's motion in the regular wave H 8.1 m, T 11.4 s,
   heading 0 from the engine's frequency domain (``mfm.frequency_response`` on the ten-period
   database, the lines linearised): q(t) = q₀ + Re[(H/2) x̂ e^{−iωt}] on the platform's six
   coordinates (x̂ the coordinate RAO; ``body_rao`` of the platform is printed beside it).
2. Moves the six fairleads with that rigid-body motion (mfm's own kinematics, exact in the angles)
   and evaluates along it
   - the engine's quasi-static tensions (its catenary table, what ``mfm.simulate`` would apply),
   - MoorPy's quasi-static catenary itself at a few instants (the table's error),
   - the engine's linearised tension, T₀ + Re[(H/2) T̂ e^{−iωt}] (``fairlead_tension_rao``),
   - MoorDyn v2 (the ``moordyn`` package, MoorDyn-C): the six lines with fixed anchors and coupled
     fairlead points whose positions and velocities are prescribed each coupling step; it starts
     from its own static solution at q₀, holds still ``--settle`` s, ramps the motion in over three
     periods (½(1 − cos)), runs ``--periods`` periods in all and is read over the last four.
3. Prints per line the fairlead tension's mean, amplitude (half the range), max and min for each.

Line model in MoorDyn. From Table 2 [S]: 800 m, EA 1.243e6 kN, 0.303 t/m in water, D 0.12 m. MoorDyn
takes the mass in air and a volume-equivalent diameter: D = 0.12 m is used as that diameter and the
mass in air is 303 + ρπD²/4 = 314.59 kg/m, so the wet weight is Table 2's exactly [D]. Not stated,
assumed [A]: the line is a studless chain (0.303 t/m at D 0.12 m is a chain's weight: a 120 mm studless
chain is ≈ 0.29 t/m, a wire rope of that size ≈ 0.07 t/m); its usual hydrodynamic coefficients (DNV /
OrcaFlex and MoorPy's chain defaults, referred to the nominal diameter): normal drag Cd 2.4, axial
drag CdAx 1.15, normal added mass Ca 1.0, axial CaAx 0.5; internal damping 80 % of critical per
segment (BA = −0.8, MoorDyn's usual value: damps the segments' axial modes, no effect at the wave
period); seabed: MoorDyn's default contact stiffness 3e6 Pa/m and damping 3e5 Pa s/m, no friction
(as the engine's lines) [A]; no waves or current on the lines (the seed does not say) [A].
``--variants`` runs MoorDyn with other discretisations (default 40 segments of 20 m), drag scales
(the largest uncertainty: Cd and CdAx × the factor) and time steps.

Also, ``--equilibrium`` prints the platform's static equilibrium pose of the config as it is (hinges
free, with their preloads): the pose at which tests/test_catenary.py checks the lines' 6 × 6
stiffness.

The MoorDyn input file is written by mfm.io.moordyn. Needs the optional ``moordyn`` package
(``pip install -e .[moordyn]``), mfm installed (it does not touch sys.path) and the model's hydro
database. Usage, from the repository root::

    python tools/moordyn_check.py [--model 1] [--wave 8.1 11.4] [--variants "40,1;80,1;40,2"]
    python tools/moordyn_check.py --equilibrium
"""
from __future__ import annotations

import argparse
import contextlib
import hashlib
import math
import os
import re
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

H_WAVE, T_WAVE = 8.1, 11.4            # m, s: the seed's severe sea [S]
D_LINE = 0.12                         # m [S]
CHAIN = {"Cd": 2.4, "CdAx": 1.15, "Ca": 1.0, "CaAx": 0.5}   # studless chain [A] (mfm.io.moordyn.CHAIN)
TITLE = "Wu & Yuan (seed 004) six catenary lines, written by tools/moordyn_check.py"


def locked_config(m: int) -> str:
    """configs/wu_yuan_m<m>.toml with every hinge locked (``locked = true``: a locked joint has no
    coordinate, so its PTO damper and its [[joint_loads]] preload go) and the database path
    absolute (the text is written elsewhere)."""
    text = (ROOT / "configs" / f"wu_yuan_m{m}.toml").read_text()
    n = text.count('type = "revolute"')
    if n != 12:
        raise ValueError(f"configs/wu_yuan_m{m}.toml: {n} revolute joints, expected the 12 hinges")
    text = text.replace('type = "revolute"', 'type = "revolute"\nlocked = true')
    text = re.sub(r"^damping = .*\n", "", text, flags=re.M)
    text = re.sub(r"\[\[joint_loads\]\]\n(?:[^\[\n].*\n)*", "", text)
    return text.replace('database = "../hydro/', f'database = "{ROOT}/hydro/')


def moordyn_input(anchors, fairleads, length, EA, weight, rho, g, depth, segments, drag, dtM):
    """A MoorDyn v2 input file of the Wu & Yuan lines (mfm.io.moordyn, with Table 2's diameter
    and the studless chain's coefficients): one line type, fixed anchors, coupled fairleads."""
    from mfm.io.moordyn import moordyn_input as write

    return write(anchors, fairleads, length, EA, weight, rho, g, depth, segments, drag, dtM,
                 diameter=D_LINE, coefficients=CHAIN, title=TITLE)


@contextlib.contextmanager
def quiet_stdout():
    """MoorDyn-C writes its input echo and initialisation log to the C-level stdout: sent to
    /dev/null (errors still come back as return codes and exceptions)."""
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(null)
        os.close(saved)


def moordyn_version():
    from importlib.metadata import version

    return version("moordyn")


def stats(T):
    """(mean, amplitude = half the range, max, min) along the last axis."""
    return T.mean(-1), (T.max(-1) - T.min(-1)) / 2, T.max(-1), T.min(-1)


def print_equilibrium(m):
    import mfm

    model = mfm.load(ROOT / "configs" / f"wu_yuan_m{m}.toml", body_coupling=False)
    q0, info = mfm.equilibrium(model)
    print(f"model {m} (hinges free, preloaded) equilibrium, platform surge, sway, heave (m), roll, "
          f"pitch, yaw (rad): {', '.join(f'{v:.6g}' for v in q0[:6])}; residual {info['residual']:.2e}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", type=int, default=1, choices=range(1, 6))
    ap.add_argument("--periods", type=int, default=12, help="wave periods run (3 ramp, last 4 read)")
    ap.add_argument("--settle", type=float, default=60.0, help="s held still before the ramp")
    ap.add_argument("--dt", type=float, default=0.005, help="coupling step, s")
    ap.add_argument("--dtM", type=float, default=0.001, help="MoorDyn's own step, s")
    ap.add_argument("--variants", default="40,1",
                    help="MoorDyn runs 'segments,drag scale[,dtM];…' (the first is tabulated in full)")
    ap.add_argument("--wave", type=float, nargs=2, default=(H_WAVE, T_WAVE), metavar=("H", "T"),
                    help="regular wave height (m) and period (s); default the severe sea 8.1 m, 11.4 s")
    ap.add_argument("--equilibrium", action="store_true")
    args = ap.parse_args(argv)
    if args.equilibrium:
        print_equilibrium(args.model)
        return 0

    import jax
    import jax.numpy as jnp
    import moordyn

    import mfm
    from mfm.loads import CatenaryLines
    from mfm.loads.catenary_tables import catenary_forces

    warnings.filterwarnings("ignore", message=".*database.*")
    t_start = time.time()
    work = Path(tempfile.mkdtemp(prefix="moordyn_check_"))
    cfg = work / f"wu_yuan_m{args.model}_locked.toml"
    cfg.write_text(locked_config(args.model))
    model = mfm.load(cfg)
    ld = next(x for x in model.loads if isinstance(x, CatenaryLines))
    plat = [model.coordinate_index(f"platform.{d}") for d in ("surge", "sway", "heave", "roll", "pitch", "yaw")]
    assert model.n_coordinates == 6 and plat == list(range(6)), model.coordinates

    # -- the platform's motion from the frequency domain
    # the database's own ω (the config writes 2π/T to 6 digits; the frequency domain takes ω
    # inside the database's range only)
    w_db = np.asarray(model.hydro.database()["omega"].values)
    H_wave, T_wave = args.wave
    omega = float(w_db[np.argmin(np.abs(w_db - 2 * math.pi / T_wave))])
    if abs(2 * math.pi / omega / T_wave - 1) > 1e-5:
        raise SystemExit(f"--wave: T {T_wave} s is not one of the database's periods "
                         f"{np.round(2 * np.pi / w_db, 4).tolist()}")
    # the frequency domain costs minutes: its results are cached on the locked config, the
    # database and ω
    key = hashlib.sha256((cfg.read_text() + repr(sorted(model.hydro.provenance().items()))
                          + repr(omega)).encode()).hexdigest()[:16]
    cache = Path.home() / ".cache" / "mfm" / f"moordyn_check_{key}.npz"
    if cache.exists():
        c = np.load(cache)
        q0, x, brao, T_rao = c["q0"], c["x"], c["brao"], c["T_rao"]
    else:
        fr = mfm.frequency_response(model, [omega], heading=0.0, joint_reactions=False)
        q0, x = fr.equilibrium.values, fr.rao.values[0]
        brao = fr.body_rao.sel(body="platform").values[0]
        T_rao = fr.fairlead_tension_rao.values[0]
        assert list(fr.mooring_line.values) == list(ld.names)
        cache.parent.mkdir(parents=True, exist_ok=True)
        np.savez(cache, q0=q0, x=x, brao=brao, T_rao=T_rao)
    A = H_wave / 2
    names = list(ld.names)
    print(f"model {args.model}, hinges locked; wave H {H_wave} m, T {2 * math.pi / omega:.4f} s "
          f"(ω {omega:.6f} rad/s), heading 0; frequency domain {time.time() - t_start:.0f} s")
    print("platform equilibrium q₀ (m, rad): " + ", ".join(f"{v:.4g}" for v in q0))
    dofs = ("surge", "sway", "heave", "roll", "pitch", "yaw")
    print("platform RAO per m of wave amplitude, |x̂| (phase °) [coordinates | body_rao]:")
    for i, d in enumerate(dofs):
        print(f"  {d:6s} {abs(x[i]):.5g} ({math.degrees(np.angle(x[i])):7.2f}) | "
              f"{abs(brao[i]):.5g} ({math.degrees(np.angle(brao[i])):7.2f})")
    print(f"  coordinate RAO − body_rao: {np.abs(x - brao).max():.2e} (the platform's CoM and "
          "small rotations are its coordinates at q₀ = 0 angles)")
    print(f"  amplitudes at H/2 = {A} m: surge {A * abs(x[0]):.3f} m, heave {A * abs(x[2]):.3f} m, "
          f"pitch {math.degrees(A * abs(x[4])):.3f}°")

    # -- fairlead positions and velocities along q(t) (mfm's kinematics, jvp for the velocities)
    pos = jax.jit(jax.vmap(lambda q, qd: jax.jvp(
        lambda qq: ld.fairleads.positions(mfm.kinematics(model, qq)), (q,), (qd,))))
    period = 2 * math.pi / omega
    n_ramp = 3

    def motion(t):
        """q(t), q̇(t) (N, 6): the harmonic motion, ramped in over n_ramp periods from t = 0."""
        t = np.atleast_1d(t)
        s = np.clip(t / (n_ramp * period), 0.0, 1.0)
        r = 0.5 * (1 - np.cos(math.pi * s))
        rd = np.where((t > 0) & (t < n_ramp * period), 0.5 * math.pi * np.sin(math.pi * s) / (n_ramp * period), 0.0)
        e = np.exp(-1j * omega * t)[:, None]
        harm = A * np.real(x[None] * e)
        dharm = A * np.real(-1j * omega * x[None] * e)
        return q0[None] + r[:, None] * harm, rd[:, None] * harm + r[:, None] * dharm

    # the whole run's fairleads; the steady cycle is read over the last 4 periods
    n_run = int(round(args.periods * period / args.dt))
    t_mot = np.arange(1, n_run + 1) * args.dt
    t_end = t_mot[-1]
    q_all, qd_all = motion(t_mot)
    p_all, v_all = (np.asarray(a) for a in pos(jnp.asarray(q_all), jnp.asarray(qd_all)))
    read = slice(n_run - int(round(4 * period / args.dt)), n_run)
    t_read, q_read, p_read, v_read = t_mot[read], q_all[read], p_all[read], v_all[read]

    # -- the engine's quasi-static tensions (its table); outside it a wider table of its own
    H, V, inside = (np.asarray(a) for a in jax.vmap(ld.tensions)(jnp.asarray(p_read)))
    T_qs = np.hypot(H, V).T                                       # (line, time)
    lines_qs = ld
    if not inside.all():
        margin = min(ld.table_margin(model, q).min() for q in q_read[::20])
        print(f"NOTE: the fairleads leave the config's table (±{dict(ld.lines[0])['ext']} m; margin "
              f"{margin:.3g} m): mfm.simulate would stop here (table_extent). Quasi-static tensions "
              "below from a wider table of the same lines (table_extent [60, 40]).")
        raw = []
        for k in range(len(names)):
            ln = dict(ld.lines[k])
            raw.append({"name": names[k], "body": "platform", "fairlead": list(np.asarray(ld.fairleads.ref0[k])),
                        "anchor": list(np.asarray(ld.anchors[k])), "length": ln["length"], "EA": ln["EA"],
                        "weight": ln["weight"], "table_extent": [60.0, 40.0]})
        lines_qs = CatenaryLines.create(model, raw)
        H, V, inside = (np.asarray(a) for a in jax.vmap(lines_qs.tensions)(jnp.asarray(p_read)))
        assert inside.all()
        T_qs = np.hypot(H, V).T
    p_eq = np.asarray(ld.fairleads.positions(mfm.kinematics(model, jnp.asarray(q0))))
    T0 = np.hypot(*(np.asarray(a) for a in ld.tensions(jnp.asarray(p_eq))[:2]))
    T_lin = T0[:, None] + np.real(A * T_rao[:, None] * np.exp(-1j * omega * t_read)[None])

    x_f, z_f, _ = (np.asarray(a) for a in jax.vmap(ld.spans)(jnp.asarray(p_read)))
    print("fairlead excursions (span x, height z from the anchor; range over the cycle, m): "
          + "; ".join(f"{names[k]} x {x_f[:, k].min():.2f}..{x_f[:, k].max():.2f}, z "
                      f"{z_f[:, k].min():.2f}..{z_f[:, k].max():.2f}" for k in range(len(names)))
          + f"; largest fairlead speed {np.linalg.norm(v_read, axis=2).max():.2f} m/s")

    # MoorPy's catenary itself at 16 instants of the last period (the table's error along it)
    an = np.asarray(ld.anchors)
    idx = np.linspace(len(t_read) - int(round(period / args.dt)), len(t_read) - 1, 16).astype(int)
    worst = 0.0
    for i in idx:
        for k in range(len(names)):
            ln = dict(lines_qs.lines[k])
            d = p_read[i, k] - an[k]
            Hm, Vm = catenary_forces(math.hypot(d[0], d[1]), d[2], ln["length"], ln["EA"], ln["weight"])
            worst = max(worst, abs(T_qs[k, i] / math.hypot(Hm, Vm) - 1))
    print(f"engine's quasi-static tension against MoorPy's catenary at 16 instants × 6 lines: "
          f"largest difference {worst:.2e} of the tension")

    # -- MoorDyn, per variant (segments, drag scale)
    ln0 = dict(ld.lines[0])
    assert all(dict(ld.lines[k])["length"] == ln0["length"] and dict(ld.lines[k])["EA"] == ln0["EA"]
               and dict(ld.lines[k])["weight"] == ln0["weight"] for k in range(len(names)))
    depth, rho = float(model.hydro.water_depth), float(model.hydro.rho)
    assert depth == -float(an[:, 2].min()), (depth, an)        # the anchors lie on the seabed
    def run_moordyn(segments, drag, dtM):
        (work / "lines.txt").write_text(moordyn_input(an, p_eq, ln0["length"], ln0["EA"], ln0["weight"],
                                                      rho, float(model.gravity), depth, segments, drag, dtM))
        t_md = time.time()
        still = [0.0] * p_eq.size
        with quiet_stdout():
            md = moordyn.Create(str(work / "lines.txt"))
            err = moordyn.Init(md, p_eq.reshape(-1).tolist(), still)
        if err != 0:
            raise RuntimeError(f"MoorDyn's Init failed (error code {err}; input {work / 'lines.txt'})")
        t = 0.0
        f = moordyn.Step(md, p_eq.reshape(-1).tolist(), still, t, args.dt)
        rest = np.linalg.norm(np.asarray(f).reshape(-1, 3), axis=1)
        for _ in range(int(round(args.settle / args.dt))):     # hold still, then move
            t += args.dt
            f = moordyn.Step(md, p_eq.reshape(-1).tolist(), still, t, args.dt)
        settled = np.linalg.norm(np.asarray(f).reshape(-1, 3), axis=1)
        T = np.zeros((n_run, len(names)))
        for i in range(n_run):
            t += args.dt
            f = moordyn.Step(md, p_all[i].reshape(-1).tolist(), v_all[i].reshape(-1).tolist(), t, args.dt)
            T[i] = np.linalg.norm(np.asarray(f).reshape(-1, 3), axis=1)
        moordyn.Close(md)
        print(f"MoorDyn {moordyn_version()}: {segments} segments/line, dtM {dtM} s, coupling "
              f"{args.dt} s, drag ×{drag}: {args.settle + t_end:.0f} s simulated in "
              f"{time.time() - t_md:.0f} s; at rest (q₀) {rest.mean() / 1e3:.2f} kN after its static "
              f"solve, {settled.mean() / 1e3:.2f} kN after {args.settle:.0f} s still (engine "
              f"{T0.mean() / 1e3:.2f} kN)")
        return T[read].T

    variants = []
    for item in args.variants.split(";"):
        v = [float(a) for a in item.split(",")]
        if len(v) not in (2, 3):
            raise SystemExit(f"--variants: {item!r}; give segments,drag[,dtM]")
        variants.append((int(v[0]), v[1], v[2] if len(v) == 3 else args.dtM))
    T_mds = [run_moordyn(*v) for v in variants]
    T_md = T_mds[0]

    # -- the comparison
    print(f"\nfairlead tension over the last 4 periods, kN: mean / amplitude / max / min "
          f"(MoorDyn: {variants[0][0]} segments, drag ×{variants[0][1]}, dtM {variants[0][2]} s)")
    rows = (("MoorDyn (dynamic)", T_md), ("engine quasi-static", T_qs), ("engine linearised", T_lin))
    for k, name in enumerate(names):
        print(f"{name} (bearing {math.degrees(math.atan2(an[k, 1], an[k, 0])):6.1f}°)")
        for label, T in rows:
            mean, amp, mx, mn = (v / 1e3 for v in stats(T[k]))
            print(f"  {label:22s} {mean:8.1f} {amp:8.1f} {mx:8.1f} {mn:8.1f}")
        print(f"  MoorDyn / quasi-static: max ×{stats(T_md[k])[2] / stats(T_qs[k])[2]:.3f}, "
              f"amplitude ×{stats(T_md[k])[1] / stats(T_qs[k])[1]:.3f}")
    k = int(np.argmax(stats(T_qs)[1]))
    print(f"\n{names[k]} at 8 instants of the last period, kN: t/T, MoorPy's catenary, engine "
          "quasi-static, engine linearised, MoorDyn")
    ln = dict(lines_qs.lines[k])
    for i in np.linspace(len(t_read) - int(round(period / args.dt)), len(t_read) - 1, 9).astype(int)[:8]:
        d = p_read[i, k] - an[k]
        Tm = math.hypot(*catenary_forces(math.hypot(d[0], d[1]), d[2], ln["length"], ln["EA"], ln["weight"]))
        print(f"  {(t_read[i] % period) / period:5.3f} {Tm / 1e3:9.1f} {T_qs[k, i] / 1e3:9.1f} "
              f"{T_lin[k, i] / 1e3:9.1f} {T_md[k, i] / 1e3:9.1f}")
    if len(variants) > 1:
        print(f"\nMoorDyn variants, {names[k]}: segments, drag scale, dtM: mean / amplitude / max / "
              "min, kN")
        for (n, d, dtM), T in zip(variants, T_mds):
            mean, amp, mx, mn = (v / 1e3 for v in stats(T[k]))
            print(f"  {n:4d} ×{d:<4g} {dtM:<7g} {mean:8.1f} {amp:8.1f} {mx:8.1f} {mn:8.1f}")
    print(f"\ntotal {time.time() - t_start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
