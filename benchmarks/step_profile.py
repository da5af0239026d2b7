"""What one time step costs, kernel by kernel: the compiled step's kernels counted by the source
line that made them, beside the warm time per step (not a test).

    python benchmarks/step_profile.py [--config configs/m4_134.toml] [--integrator verlet]
                                      [--radiation state_space_exact] [--steps 20000] [--top 25]
                                      [--mechanics-only] [--without-welded] [--trace K]

XLA on a CPU runs each compiled step as a sequence of kernels (fusions, dots, solver calls,
copies), each with a fixed cost of a fraction of a microsecond besides its flops. For a model of
a few coordinates the step's flops are a few µs (benchmarks/RESULTS.md, "One step of the fast
path"), so the count of kernels, not the flops, sets the floor: this script shows where they come
from. It compiles the rollout of ``mfm.rollout`` (the M4 134 sea state of benchmarks/speed.py by
default), takes the body of its time loop from the optimised HLO, and attributes each kernel to
the innermost ``mfm`` source line in its metadata (jax records the Python stack of every
operation). Then it times warm rollouts: the median of ``--repeats`` calls after the compiling
one. ``--trace K`` ranks the kernels by time as well as by count: a short rollout runs under
jax's profiler, and the K kernels that take the most beyond the median kernel are listed (this is
how the library dots of a microsecond each were found among kernels of a fraction of that).

``--without-welded`` (with ``--mechanics-only``) is a cost probe, not the same physics: it profiles
the config's tree with every body on a fixed joint left out (their children hung from the
left-out body's parent at the same joint points; masses not merged), i.e. what a step would cost
if welded bodies were lumped into their parent before compiling.
"""
import argparse
import collections
import re
import time
from pathlib import Path

from speed import _timed   # the median of warm calls after the compiling one (this folder)

ROOT = Path(__file__).resolve().parents[1]
# HLO operations that are not kernels (no code runs for them)
FREE = {"get-tuple-element", "constant", "bitcast", "tuple", "parameter"}


def _section(txt, name):
    """The lines of one metadata table of an HLO module's text (FileNames, FunctionNames, …)."""
    parts = txt.split("\n" + name + "\n")
    return parts[1].split("\n\n")[0].split("\n") if len(parts) > 1 else []


def _frames(txt):
    """stack frame id -> [(file, function, line), …] innermost first, from the module's tables."""
    files = {int(x.split()[0]): x.split('"')[1] for x in _section(txt, "FileNames") if '"' in x}
    funcs = {int(x.split()[0]): x.split('"')[1] for x in _section(txt, "FunctionNames") if '"' in x}
    locs = {}
    for x in _section(txt, "FileLocations"):
        m = re.match(r"(\d+) \{file_name_id=(\d+) function_name_id=(\d+) line=(\d+)", x)
        if m:
            locs[int(m.group(1))] = (files[int(m.group(2))], funcs[int(m.group(3))], int(m.group(4)))
    frames = {}
    for x in _section(txt, "StackFrames"):
        m = re.match(r"(\d+) \{file_location_id=(\d+) parent_frame_id=(\d+)", x)
        if m:
            frames[int(m.group(1))] = (int(m.group(2)), int(m.group(3)))

    def chain(fid):
        out = []
        while fid in frames and len(out) < 64:
            loc, parent = frames[fid]
            out.append(locs.get(loc, ("?", "?", 0)))
            if parent == fid:
                break
            fid = parent
        return out
    return chain


def _computations(txt):
    comps, cur = {}, None
    for line in txt.split("\n"):
        m = re.match(r"^(ENTRY )?%(\S+) .*\{$", line)
        if m:
            cur = m.group(2)
            comps[cur] = []
            continue
        if line.startswith("}"):
            cur = None
        elif cur:
            comps[cur].append(line)
    return comps


def step_kernels(hlo_text, n_steps):
    """The kernels of the time loop's body (the while loop of ``n_steps`` trips): a Counter of
    "file:function:line" (the innermost frame in mfm/ or hydro/) -> kernels, and one of op kinds."""
    comps = _computations(hlo_text)
    chain = _frames(hlo_text)
    body = None
    for lines in comps.values():
        for line in lines:
            if " while(" in line and f'"known_trip_count":{{"n":"{n_steps}"}}' in line:
                body = re.search(r"body=%([^,\s]+)", line).group(1)
    if body is None:
        raise RuntimeError(f"no while loop of {n_steps} trips in the compiled rollout")
    where, kinds, named = collections.Counter(), collections.Counter(), {}
    for line in comps[body]:
        op = re.search(r"%(\S+) = (\S+) ([a-z][\w-]*)\(", line)
        if not op or op.group(3) in FREE:
            continue
        kinds[op.group(3)] += 1
        sf = re.search(r"stack_frame_id=(\d+)", line)
        ours = [f for f in (chain(int(sf.group(1))) if sf else [])
                if "/mfm/" in f[0] or "/hydro/" in f[0]]
        key = (f"{Path(ours[0][0]).parent.name}/{Path(ours[0][0]).name}:{ours[0][1]}:{ours[0][2]}"
               if ours else f"(no mfm frame) {op.group(3)}")
        where[key] += 1
        named[op.group(1)] = (op.group(3), op.group(2).split("{")[0], key)
    return where, kinds, named


def traced_kernels(run, n_steps):
    """Each kernel's traced time per step, from one ``run()`` under ``jax.profiler.trace``: a dict
    kernel name -> µs per step. The trace adds a fixed overhead to every kernel, so these rank
    the kernels (and show which cost more than their share); their sum is not the step's time.
    Kernels running concurrently on XLA's two threads are each counted whole."""
    import glob
    import tempfile

    import jax
    from jax.profiler import ProfileData

    with tempfile.TemporaryDirectory() as d:
        with jax.profiler.trace(d):
            run()
        pd = ProfileData.from_file(glob.glob(d + "/**/*.xplane.pb", recursive=True)[0])
        total = collections.Counter()
        for plane in pd.planes:
            for line in plane.lines:
                if "XLAEigen" not in line.name:      # the threads that run the kernels
                    continue
                for ev in line.events:
                    if not ev.name.startswith("ThunkExecutor"):
                        total[ev.name] += ev.duration_ns
    return {k: v / 1e3 / n_steps for k, v in total.items()}


def _without_welded(config):
    """The config's tree (no hydro, no loads) without its bodies on fixed joints: each one's
    children hang from its parent at their own joint points (a cost probe, masses not merged)."""
    import tempfile
    import tomllib

    import mfm

    with open(config, "rb") as f:
        cfg = tomllib.load(f)
    bodies = {b["name"]: b for b in cfg["bodies"]}
    welded = {n for n, b in bodies.items() if b.get("joint", {}).get("type") == "fixed"}

    def keeper(name):
        while name in welded:
            name = bodies[name].get("parent")
        return name

    def value(v):
        return "[" + ", ".join(map(value, v)) + "]" if isinstance(v, list) else (
            f'"{v}"' if isinstance(v, str) else repr(v).lower() if isinstance(v, bool) else repr(v))

    lines = [f'[model]\nname = "{cfg["model"]["name"]} without welded bodies"\n'
             f'gravity = {cfg["model"].get("gravity", 9.81)}\n']
    for name, b in bodies.items():
        if name in welded:
            continue
        keep = {k: v for k, v in b.items() if k not in ("joint", "geometry", "hydro", "notes")}
        if keep.get("parent") is not None:
            keep["parent"] = keeper(keep["parent"])
        lines.append("[[bodies]]")
        lines += [f"{k} = {value(v)}" for k, v in keep.items() if v is not None]
        lines += ["[bodies.joint]"] + [f"{k} = {value(v)}" for k, v in b.get("joint", {}).items()]
        lines.append("")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "without_welded.toml"
        path.write_text("\n".join(lines))
        return mfm.load(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--config", default=str(ROOT / "configs" / "m4_134.toml"))
    ap.add_argument("--integrator", default="verlet")
    ap.add_argument("--radiation", default="state_space_exact")
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--mechanics-only", action="store_true",
                    help="the tree alone: no water, no other loads of the config")
    ap.add_argument("--trace", type=int, default=0, metavar="K",
                    help="also trace a rollout of 1,000 steps with jax's profiler and list the K "
                         "kernels that take the most time beyond the median kernel's")
    ap.add_argument("--without-welded", action="store_true",
                    help="with --mechanics-only: the tree without its fixed-joint bodies (a cost "
                         "probe of lumping them, not the same physics)")
    a = ap.parse_args()

    import jax.numpy as jnp

    import hydro
    import mfm
    from mfm import integrators
    from mfm.timedomain.rollout import rollout_jit
    from mfm.timedomain.setup import model_loads

    tp = 1.2
    dt = tp / 200
    if a.without_welded and not a.mechanics_only:
        ap.error("--without-welded needs --mechanics-only (the hydro data belong to every body)")
    m = _without_welded(a.config) if a.without_welded else mfm.load(a.config)
    sea = hydro.Jonswap(hs=0.04, tp=tp, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
    loads = () if a.mechanics_only else model_loads(
        m, sea, dt=dt, duration=a.steps * dt, ramp=5 * tp, radiation=a.radiation,
        integrator=a.integrator)
    q0 = jnp.zeros(m.n_coordinates)
    z0 = jnp.concatenate([ld.initial_state(m) for ld in loads]) if loads else jnp.zeros(0)
    t0 = time.perf_counter()
    compiled = rollout_jit.lower(m, loads, q0, q0, z0, jnp.asarray(0.0), jnp.asarray(dt),
                                  n_steps=a.steps, integrator=integrators.get(a.integrator),
                                  save_every=a.steps, record=False).compile()
    t_compile = time.perf_counter() - t0
    where, kinds, _ = step_kernels(compiled.as_text(), a.steps)

    def run():
        return mfm.rollout(m, q0, q0, dt=dt, n_steps=a.steps, integrator=a.integrator, loads=loads,
                           save_every=a.steps)[1].block_until_ready()
    _, _, warm = _timed(run, a.repeats)
    n = sum(kinds.values())
    what = "mechanics only" if a.mechanics_only else a.radiation
    what += ", welded bodies left out" if a.without_welded else ""
    print(f"{Path(a.config).name}, {a.integrator} / {what}, {a.steps} steps: compile "
          f"{t_compile:.1f} s, warm {warm:.3f} s = {warm / a.steps * 1e6:.1f} µs/step; "
          f"{n} kernels per step ({warm / a.steps * 1e6 / n:.2f} µs per kernel on average)")
    whole = "xla_cpu_small_call" in compiled.as_text()
    print("time loop compiled " + ("whole: one native function, the kernels above are its parts "
                                   "(mfm.runner.xla)" if whole else "kernel by kernel: each kernel "
                                   "dispatched on its own (mfm.runner.xla says when and why)"))
    print("kinds: " + ", ".join(f"{k} {v}" for k, v in kinds.most_common()))
    by_file = collections.Counter()
    for k, v in where.items():
        by_file[k.split(":")[0]] += v
    print("by file: " + ", ".join(f"{k} {v}" for k, v in by_file.most_common()))
    print("\n| kernels | source line (innermost mfm frame) |\n|---|---|")
    for k, v in where.most_common(a.top):
        print(f"| {v} | {k} |")
    if a.trace:
        n_tr = 1000
        text = rollout_jit.lower(m, loads, q0, q0, z0, jnp.asarray(0.0), jnp.asarray(dt),
                                  n_steps=n_tr, integrator=integrators.get(a.integrator),
                                  save_every=n_tr, record=False).compile().as_text()
        _, _, named = step_kernels(text, n_tr)

        def run_short():
            return mfm.rollout(m, q0, q0, dt=dt, n_steps=n_tr, integrator=a.integrator,
                               loads=loads, save_every=n_tr)[1].block_until_ready()
        run_short()
        per = {k: v for k, v in traced_kernels(run_short, n_tr).items() if k in named}
        if not per:
            # a loop compiled whole is one native call to the profiler: its parts are not timed
            print("\ntraced: no kernel of the step seen by the profiler (the time loop is compiled "
                  "whole, one native call); to rank them kernel by kernel, run again with "
                  "XLA_FLAGS=--xla_backend_extra_options=xla_cpu_small_while_loop_byte_threshold"
                  "=1024 (XLA's default: the loop dispatched kernel by kernel, slower)")
            return
        base = sorted(per.values())[len(per) // 2]
        print(f"\ntraced ({n_tr} steps; every kernel carries the trace's overhead, the median "
              f"kernel {base:.2f} µs/step): the kernels that take the most beyond the median\n"
              "| µs/step beyond the median | kernel | kind, shape | source line |\n|---|---|---|---|")
        for k in sorted(per, key=per.get, reverse=True)[:a.trace]:
            kind, shape, key = named[k]
            print(f"| {per[k] - base:.2f} | {k} | {kind} {shape} | {key} |")


if __name__ == "__main__":
    main()
