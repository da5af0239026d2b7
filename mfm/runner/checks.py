"""The checks of a run, before it (a request whose memory cannot fit; dt against the stability
limit at the shortest natural period of the model at rest, against the periods the sea excites;
Verlet on coordinates nothing pulls back) and after it (where and why the state went
non-finite)."""
from __future__ import annotations

import math
import os
import warnings

import numpy as np

from ..errors import AccuracyWarning, StabilityWarning
from ..frequency.rest import shortest_natural_period
from ..timedomain import integrators as _integrators


def machine_memory() -> int:
    """Bytes of memory this machine has (0 where the system does not say)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return 0


# where the kernel says how much this process may use (cgroup v2, then v1), under a root a test
# can move
CGROUP_FILES = (("sys/fs/cgroup/memory.max", "sys/fs/cgroup/memory.current"),
                ("sys/fs/cgroup/memory/memory.limit_in_bytes",
                 "sys/fs/cgroup/memory/memory.usage_in_bytes"))


def _read_int(path) -> int | None:
    try:
        with open(path) as f:
            text = f.read().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None        # "max": no limit


def usable_memory(root: str = "/") -> tuple[int, str]:
    """(bytes, what): the memory this process may still take, the least of
    - the machine's physical memory (:func:`machine_memory`),
    - its control group's limit less what the group uses now (cgroup v2 ``memory.max`` −
      ``memory.current``, or v1's ``memory.limit_in_bytes`` − ``memory.usage_in_bytes``: a
      container's limit, which kills the process without a word when passed),
    - the address-space and data limits of the process (``ulimit -v``, ``-d``),
    - the memory the kernel says is available (``MemAvailable`` of /proc/meminfo) plus what this
      process holds already (its resident set),
    and what that least one is. (0, "") where nothing is known."""
    import resource

    found = []
    phys = machine_memory()
    if phys:
        found.append((phys, "this machine's memory"))
    for limit_file, usage_file in CGROUP_FILES:
        limit = _read_int(os.path.join(root, limit_file))
        if limit is not None and limit < 2**60:
            used = _read_int(os.path.join(root, usage_file)) or 0
            found.append((max(limit - used, 0), f"its control group's limit ({limit / 1e9:.3g} GB "
                                                f"in /{limit_file}, {used / 1e9:.3g} GB in use)"))
            break
    for which, name in ((resource.RLIMIT_AS, "ulimit -v"), (resource.RLIMIT_DATA, "ulimit -d")):
        try:
            soft = resource.getrlimit(which)[0]
        except (ValueError, OSError):
            continue
        if soft not in (resource.RLIM_INFINITY, -1) and soft > 0:
            found.append((int(soft), f"the process's limit ({name})"))
    try:
        with open(os.path.join(root, "proc/meminfo")) as f:
            info = dict(line.split(":", 1) for line in f)
        avail = int(info["MemAvailable"].split()[0]) * 1024
        rss = 0
        try:
            with open(os.path.join(root, "proc/self/statm")) as f:
                rss = int(f.read().split()[1]) * int(os.sysconf("SC_PAGE_SIZE"))
        except (OSError, ValueError, IndexError):
            pass
        found.append((avail + rss, "the memory available now (MemAvailable of /proc/meminfo)"))
    except (OSError, KeyError, ValueError):
        pass
    return min(found) if found else (0, "")


def check_sea_read(model, loads, seas) -> None:
    """Refuse a sea (``seas``: the run's sea states, None for still water) that no load of the run
    reads: the model's water, or a load of ``model.loads`` or ``loads`` with ``reads_sea``
    (:meth:`mfm.loads.base.Load.for_run`). Without one the sea would change nothing."""
    if all(s is None for s in seas) or model.hydro is not None:
        return
    if any(ld.reads_sea for ld in tuple(model.loads) + tuple(loads)):
        return
    raise ValueError("sea: this model has no hydrodynamics (no [hydro] table in its config, or "
                     "mfm.load(..., hydro=False)) and none of its loads reads a sea (a load's "
                     "reads_sea); pass sea=None")


def run_bytes(model, loads, n_steps: int, save_every: int, *, cases: int = 1,
              every_output: bool = True, names=()) -> float:
    """An estimate (bytes, float64) of what a run of ``n_steps`` holds before it starts stepping:
    the saved samples (t, q, q̇, q̈, the loads' states and, with ``every_output``, every recorded
    output: poses, reactions, energies and the loads' diagnostics; else only ``names``) and the
    water's excitation and elevation tables on the integrator's grid (two points a step, RK4's),
    for ``cases`` runs. ``loads`` are those known before the water is built (the config's and the
    extra ones): the water's share comes from the model's hydro bodies."""
    from .. import results

    n = model.n_coordinates
    n_saved = n_steps // max(int(save_every), 1) + 1
    specs, coords = results.record_specs(model, loads)
    size = lambda dims: math.prod(len(coords.get(d, ())) or 1 for d in dims)  # noqa: E731
    per_sample = 3 * n + 2 + sum(ld.n_states for ld in loads)
    per_sample += sum(size(dims) for name, (dims, _) in specs.items()
                      if every_output or name in names)
    tables = 0
    if model.hydro is not None:
        dofs = 6 * len(model.hydro.body_index)
        if every_output:
            per_sample += 1 + dofs + 6 * dofs          # eta, xi, hydro_force (6 components)
        tables = (2 * n_steps + 1) * (dofs + 1)
    return 8.0 * cases * (n_saved * per_sample + tables)


def refuse_impossible(model, loads, n_steps, save_every, *, cases=1, every_output=True, names=(),
                      what="duration"):
    """Raise a ValueError before any work when the run's memory (:func:`run_bytes`) is more than
    this process may use (:func:`usable_memory`: the machine, a container's limit, ulimits, what
    is free): a run that would otherwise allocate until it fails, hangs or is killed without a
    word (a duration of 1e15 s; a 2 GB batch in a 1.5 GB container). The message gives the
    estimate, the limit it meets and how to proceed."""
    need = run_bytes(model, loads, n_steps, save_every, cases=cases, every_output=every_output,
                     names=names)
    have, limit = usable_memory()
    if have and need > have:
        raise ValueError(
            f"{what}: {n_steps:.4g} steps{f' × {cases} cases' if cases > 1 else ''} would hold "
            f"about {need / 1e9:.3g} GB before the first step (the saved samples and the wave "
            f"tables), more than the {have / 1e9:.3g} GB this process may use ({limit}): "
            f"shorten the run, keep fewer "
            f"samples (save_every=k keeps every k-th), split it into runs from the last state "
            f"(q0=, qd0=, t0=), or record fewer outputs (simulate_batch(outputs=...))")


# the kernel's product integration (hydro.prepare.HydroSpec.kernel) samples K this many times a
# step (its default)
KERNEL_SUBDIVISIONS = 16


def _convolution_lags(spec, dt: float, memory) -> tuple[float, int]:
    """(T_K, N): the convolution's memory (s; ``memory``, or from the decay of K) and its
    lags N = max(⌈T_K/dt⌉, 2) + 1, as :meth:`hydro.prepare.HydroSpec.kernel` counts them."""
    T_K = spec.memory() if memory is None else float(memory)
    return T_K, max(int(math.ceil(T_K / dt)), 2) + 1


def convolution_bytes(spec, dt: float, memory, n_offsets: int) -> float:
    """An estimate (bytes) of the peak that building the convolution's weights takes
    (:meth:`mfm.loads.radiation.Convolution.build`, :meth:`hydro.prepare.HydroSpec.kernel`), at
    n_τ = 16 (N + 1) + 1 samples of K(τ) over its N = ⌈T_K/dt⌉ + 1 lags:

        8 [n_τ max(4.2 n², 1.1 n_all² + 0.5 n² + 6 (n_ω + 300)) + 3 S N n²]

    n the moved hydro dofs, n_all all of them, n_ω the database's frequencies (+ the 300 nodes of
    K's tail), S the stage offsets: the impulse response of every entry on the Filon weights of
    the damping's nodes, then four arrays of the moved entries' samples at once in the product
    integration, and the weights. The constants are measured (numpy's allocations under
    ``tracemalloc``) on the sphere, RM3, M4 134, Stansby & Li and Wu & Yuan model 1: the estimate
    is 1 % to 16 % above each one's peak."""
    _, N = _convolution_lags(spec, dt, memory)
    n, n_all = len(spec.moving), len(spec.A_inf_db)
    n_omega = int(spec.database()["omega"].size)
    n_tau = (N + 1) * KERNEL_SUBDIVISIONS + 1
    per_sample = max(4.2 * n * n, 1.1 * n_all * n_all + 0.5 * n * n + 6.0 * (n_omega + 300))
    return 8.0 * (n_tau * per_sample + 3.0 * int(n_offsets) * N * n * n)


def refuse_convolution(model, *, dt: float, memory, n_offsets: int, why: str = "") -> None:
    """Raise a ValueError before the convolution's weights are built when they would take more
    memory (:func:`convolution_bytes`) than this process may use (:func:`usable_memory`): a long
    memory T_K over many moved dofs (Wu & Yuan's 90, T_K 234 s from a 10-frequency grid: about
    30 GB) was killed by the system without a word. ``why``: how the run came to the convolution
    (an ``auto`` run whose fit was judged off), said first."""
    spec = model.hydro
    if spec is None:
        return
    need = convolution_bytes(spec, dt, memory, n_offsets)
    have, limit = usable_memory()
    if not have or need <= have:
        return
    T_K, N = _convolution_lags(spec, dt, memory)
    n = len(spec.moving)
    raise ValueError(
        f"radiation: {why + ': ' if why else ''}the convolution's weights (memory T_K "
        f"{T_K:.4g} s{' from the decay of K' if memory is None else ''} / dt {dt:.4g} s = {N} lags "
        f"× {n}² moved hydro dofs, K sampled {KERNEL_SUBDIVISIONS} times a step) would take "
        f"about {need / 1e9:.3g} GB to build, more than the {have / 1e9:.3g} GB this process may "
        f"use ({limit}): give radiation='state_space' (the fitted state space: no kernel), a "
        f"shorter memory= (s; the window the database's ω grid resolves is π/Δω), or a larger "
        f"dt")


def nonfinite_message(model, integ, t, q, qd, dt, loads, k):
    coords = [model.coordinates[j] for j in range(model.n_coordinates)
              if not (np.isfinite(q[k, j]) and np.isfinite(qd[k, j]))]
    k_ok = max(k - 1, 0)
    head = (f"the state went non-finite at t = {t[k]:.6g} s (first saved sample; last finite at "
            f"t = {t[k_ok]:.6g} s) in coordinate(s) {coords}.")
    for ld in loads:
        cause = ld.describe_nonfinite(model, q[k_ok], qd[k_ok])
        if cause:
            return f"{head} {cause}"
    # linearised at the start, as the stability warning is: the last finite state of a diverging
    # run is itself far from any equilibrium
    T_min = shortest_natural_period(model, q[0], loads)
    lines = [head]
    if math.isfinite(T_min):
        ratio = 2 * math.pi * dt / T_min
        lines.append(f"Likely cause: dt = {dt:.4g} s against the shortest natural period "
                     f"{T_min:.4g} s (ω dt = {ratio:.3g}; {integ.name} is stable for ω dt < "
                     f"{integ.stability_limit:.3g}).")
        if ratio >= 0.5 * integ.stability_limit:
            lines.append(f"Reduce dt below {stable_dt(T_min, integ):.3g} s or use integrator='newmark'.")
        else:
            lines.append("dt is inside the stability limit, so look at the loads or the model: "
                         "large rotations of a free root near pitch = ±90° (Euler angle "
                         "singularity), a load that grows without bound, or a bad parameter.")
    else:
        lines.append("No restoring stiffness at the last finite state: look at the loads, a "
                     "parameter, or a free root near pitch = ±90° (Euler angle singularity).")
    return " ".join(lines)


def warn_accuracy(model, sea, dt, integ, tol=0.01):
    """Warn when the shortest wave period with energy (amplitude ≥ 5 % of the largest component)
    is resolved with a period error above ``tol`` by the integrator (its leading error term,
    :func:`mfm.integrators.phase_error`)."""
    # a sea read by a model's own load where it has no water: deep water and standard g
    comps = sea.components() if model.hydro is None else \
        sea.components(water_depth=model.hydro.water_depth, g=model.hydro.g)
    amp = np.abs(np.asarray(comps.amplitude, dtype=float))
    if not amp.size or amp.max() <= 0:
        return
    w_hi = float(np.max(np.asarray(comps.omega)[amp >= 0.05 * amp.max()]))
    err = _integrators.phase_error(integ, w_hi * dt)
    if err > tol:
        # the dt that brings the error to tol (phase_error is a power of ω dt)
        p = 4 if getattr(integ, "order", 2) >= 4 else 2
        dt_ok = dt * (tol / err) ** (1.0 / p)
        warnings.warn(
            f"dt = {dt:.4g} s is coarse for the sea: its shortest period with energy is "
            f"{2 * math.pi / w_hi:.4g} s (ω dt = {w_hi * dt:.3g}), where {integ.name} makes a "
            f"period (phase) error of about {100 * err:.2g} % per wave period, which accumulates "
            f"into amplitudes and power. Use dt ≤ {dt_ok:.3g} s for {100 * tol:g} %.",
            AccuracyWarning, stacklevel=3)


def stable_dt(T_min: float, integ) -> float:
    """The largest stable dt at the shortest natural period T_min: ω dt < the integrator's limit."""
    return T_min * integ.stability_limit / (2 * math.pi)


def warn_stability(integ, dt, T_min):
    """Warn (:class:`StabilityWarning`) when ω dt at the shortest natural period T_min (s) is beyond
    the integrator's stability limit."""
    if math.isfinite(integ.stability_limit) and math.isfinite(T_min) \
            and 2 * math.pi * dt / T_min > integ.stability_limit:
        warnings.warn(
            f"dt = {dt:.4g} s is beyond the stability limit of {integ.name}: the shortest natural "
            f"period of the model linearised at q0 is {T_min:.4g} s, ω dt = "
            f"{2 * math.pi * dt / T_min:.3g} > {integ.stability_limit:.3g}. Use dt < "
            f"{stable_dt(T_min, integ):.3g} s or integrator='newmark'.",
            StabilityWarning, stacklevel=3)


def warn_verlet_drift(integ, free):
    """Warn (:class:`AccuracyWarning`) when Verlet integrates coordinates nothing pulls back."""
    if free and integ.name == "verlet":
        warnings.warn(
            f"{free} have no restoring (nothing pulls them back) and integrator='verlet' takes the "
            "velocity-dependent loads at a lagged velocity: a small steady force on them, so their "
            "velocity drifts without bound in a long run (M4 134, 10⁶ steps: surge 147 m against "
            "RK4's 0.32 m; docs/stability.md §3). The other coordinates' statistics are not "
            "affected. Use integrator='rk4' where their position matters, or moor the body.",
            AccuracyWarning, stacklevel=3)
