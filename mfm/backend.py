"""What XLA does with mfm's time loops: the backend option mfm needs, given to XLA when its backend
starts, and whether it took effect (imported first by ``mfm/__init__``).

**Time loops compiled as one function.** XLA on a CPU runs a compiled program as a sequence of
kernels, and pays about a quarter of a microsecond to dispatch each (benchmarks/RESULTS.md, "Where
the M4 134 step's time goes"). A time step of M4 134 is ~140 such kernels of a few hundred flops
each, so dispatch, not arithmetic, set its cost. XLA can instead compile a while loop whose
iteration touches few bytes as one native function (its ``small_while_loop_hoisting`` pass, keyed
by the backend option ``xla_cpu_small_while_loop_byte_threshold``, default 1 kB). mfm raises that
threshold to :data:`LOOP_BYTES` so that the time loops of its rollouts qualify (M4 134 with exact
radiation reads ~0.5 MB per step): M4 134's step 33 → 17 µs, its mechanics alone 16.5 → 4.3 µs
(``python benchmarks/step_profile.py``). The numbers are the same to round-off (the same HLO, one
emitter instead of another). RM3 in a regular wave, 2,000 steps: RK4 with convolution 241 → 93 ms,
with state space 82 → 18 ms, Verlet with exact radiation 26 → 7 ms. Loops that read more than
16 MiB per iteration keep the kernel-by-kernel runtime, whose library matrix products pay for large
operands. The price is compile time: LLVM optimises the loop as one function (M4 134: Verlet
8.4 → 8.8 s, RK4 14 → 31 s).

The whole-loop compilation refuses scatters, library (LAPACK) calls and library fusions, so the
time step avoids the first two (static 0/1 sums, unrolled elimination) and mfm also turns off
XLA's experimental YNNPACK fusions (``--xla_cpu_experimental_ynn_fusion_type=``), into which XLA
rewrote some small multiply–reduces (this also made batches of 4–128 cases 20–35 % faster).

XLA reads ``XLA_FLAGS`` once, when jax starts its backend. At import, mfm starts jax's backend
with the option added to ``XLA_FLAGS`` for that moment only (:func:`start_backend`): the variable
is given back as it was, so ``import mfm`` leaves ``os.environ`` unchanged and child processes
inherit the user's own setting. Where ``XLA_FLAGS`` already names the option, yours wins
(``=1024`` restores XLA's default). If jax's backend is already running when mfm is imported (jax
used before ``import mfm``), the option cannot take effect any more: :data:`LOOPS_COMPILED_WHOLE`
is then False, a :class:`PerformanceWarning` says so, and results record it (``xla_time_loop`` in
their provenance). The core reads :data:`LOOPS_COMPILED_WHOLE` to shape its products for the
compiler that will run them (:mod:`mfm.mechanics.se3`, :mod:`mfm.mechanics.dynamics`).
"""
from __future__ import annotations

import os
import re
import warnings

OPTION = "xla_cpu_small_while_loop_byte_threshold"
YNN_OPTION = "xla_cpu_experimental_ynn_fusion_type"
# bytes one loop iteration may read and still be compiled whole: above M4 134's ~0.5 MB with room
# for larger trees, below the tens of MB where library matrix products pay (convolution histories,
# batches of many cases)
LOOP_BYTES = 16 * 2**20


class PerformanceWarning(UserWarning):
    """A setting that makes mfm slower than it could be, without changing its results."""


def _backend_running() -> bool:
    try:
        from jax._src import xla_bridge
        return bool(xla_bridge.backends_are_initialized())
    except Exception:   # a jax without this private helper: assume not started
        return False


def with_loop_option(flags: str, threshold: int = LOOP_BYTES) -> str:
    """XLA_FLAGS ``flags`` with the option added (into an existing ``--xla_backend_extra_options``,
    which holds all extra options comma-separated); unchanged if it already names the option."""
    if OPTION in flags:
        return flags
    m = re.search(r"--xla_backend_extra_options=(\S*)", flags)
    if m:
        value = f"{m.group(1)},{OPTION}={threshold}" if m.group(1) else f"{OPTION}={threshold}"
        return flags[:m.start()] + f"--xla_backend_extra_options={value}" + flags[m.end():]
    return f"{flags} --xla_backend_extra_options={OPTION}={threshold}".strip()


def without_library_fusions(flags: str) -> str:
    """XLA_FLAGS ``flags`` with XLA's experimental YNNPACK fusions off (unless they name the
    option): XLA may rewrite a small multiply–reduce of a time step into one (Stansby & Li's HᵀA∞H,
    Wu & Yuan's radiation output), and the whole-loop compilation refuses library fusions, so one
    such product would send the whole loop back to kernel-by-kernel dispatch."""
    if YNN_OPTION in flags:
        return flags
    return f"{flags} --{YNN_OPTION}=".strip()


def start_backend() -> tuple[bool, str]:
    """Start jax's backend with the option in ``XLA_FLAGS`` (then given back as it was); returns
    (whether the option is in effect, the threshold in bytes)."""
    flags = os.environ.get("XLA_FLAGS")
    given = re.search(OPTION + r"=(\d+)", flags or "")
    if given:
        return int(given.group(1)) > 1024, given.group(1)
    if _backend_running():
        warnings.warn(
            "mfm was imported after jax started its backend, so XLA cannot compile mfm's time loops "
            f"as one function any more ({OPTION}; see mfm.backend): rollouts of small models run "
            "up to ~2x slower, with the same results. Import mfm before using jax, or set XLA_FLAGS="
            f"'--xla_backend_extra_options={OPTION}={LOOP_BYTES}' before starting Python.",
            PerformanceWarning, stacklevel=3)
        return False, "1024"
    import jax

    os.environ["XLA_FLAGS"] = without_library_fusions(with_loop_option(flags or ""))
    try:
        jax.devices()              # XLA reads its flags as the backend starts, and only then
    finally:
        if flags is None:
            del os.environ["XLA_FLAGS"]
        else:
            os.environ["XLA_FLAGS"] = flags
    return True, str(LOOP_BYTES)


LOOPS_COMPILED_WHOLE, LOOP_THRESHOLD = start_backend()


# what turns one of mfm's environment switches off (MFM_COMPILATION_CACHE, MFM_PROGRAM_CACHE,
# MFM_GC_FREEZE, MFM_FAST_COMPILE; hydro's MFM_FIT_CACHE reads the same words in hydro's own
# cache module, which never imports mfm)
OFF_VALUES = ("off", "0", "false", "no", "none")


def switched_off(setting: str | None) -> bool:
    """Whether an environment variable's value (None: unset) says off."""
    return (setting or "").strip().lower() in OFF_VALUES


def device_array(x, dtype=None):
    """``x`` (numbers, a list or a numpy array) as a jax array of its numpy dtype (or ``dtype``),
    put on the device as it is: ``jax.device_put(np.asarray(x, dtype))``. The same values and
    dtype as ``jnp.asarray(x)`` under x64, without its conversion program: jax 0.10 compiles a
    small program (``jit(stage)``, or ``broadcast_in_dim`` for ``jnp.zeros``) per new shape,
    ~15 ms of CPU each, dozens in a first answer, none kept by the compilation cache (too small
    to be worth it). Host code that hands numpy data to the core uses this."""
    import jax
    import numpy as np

    return jax.device_put(np.asarray(x) if dtype is None else np.asarray(x, dtype))
