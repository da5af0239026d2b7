"""A run in chunks: under a progress bar (a run or a batch in 20 to 100 chunks of one compiled
function, the bar, tqdm on stderr, updated between them), and a long run's pipeline (its outputs
made on a second thread while its steps go on, :func:`run_pipelined`); the same steps in the same
order, so the same numbers as the run in one call."""
from __future__ import annotations

import sys
import threading
import time

import jax
import numpy as np

from .threads import Serial, interrupted, result


def chunk_plan(n_blocks: int, fewest: int = 20, most: int = 100,
               multiple: int = 1) -> tuple[int, int]:
    """(chunk length in saved blocks, number of chunks) for a progress bar: between ``fewest``
    and ``most`` updates, the length that wastes the fewest blocks past the end (the last chunk
    has the same length, so one compilation serves every chunk; its extra blocks are dropped).
    ``multiple``: the length a multiple of it (a pipelined run's chunks, whose outputs are made
    in groups of that many samples: :func:`run_pipelined`)."""
    if n_blocks <= fewest and multiple == 1:
        return 1, n_blocks
    up = lambda x: -(-x // multiple) * multiple                 # noqa: E731
    lo = up(-(-n_blocks // most))
    lengths = range(lo, max(lo, up(-(-n_blocks // fewest))) + 1, multiple)
    c = min(lengths, key=lambda c: (-(-n_blocks // c) * c - n_blocks, c))
    return c, -(-n_blocks // c)


# a recorded run that saves this many samples or more is pipelined (:func:`run_pipelined`): its
# outputs, whose cost goes with the samples saved, made on a second thread as the loop goes on.
# It then has three programs to compile instead of one (start, steps, outputs); fewer samples'
# outputs (~20 µs a sample at most, M4 134's) take under 0.2 s, and RM3's README command (2,000
# samples, empty caches, 2 cores) took 24.7 and 23.9 s pipelined against 22.2 and 24.0 s in one
# program
PIPELINE_MIN_SAMPLES = 10_000
# without a bar, in this many chunks at most: each costs two program calls and a hand-over
# between threads (~0.1 ms), and the last chunk's outputs are not hidden behind any stepping
PIPELINE_CHUNKS = 8


def pipeline_plan(n_blocks: int, multiple: int = 1) -> tuple[int, int]:
    """(chunk length in saved blocks, number of chunks) for a pipelined run without a bar
    (:func:`run_pipelined`): 4 to :data:`PIPELINE_CHUNKS` chunks of one length, a multiple of
    ``multiple``, the fewest blocks wasted past the end (:func:`chunk_plan`)."""
    return chunk_plan(n_blocks, fewest=4, most=PIPELINE_CHUNKS, multiple=multiple)


def progress_options(progress):
    """The tqdm options of ``progress`` (True, or a dict of tqdm options), or None for no bar."""
    if progress is None or progress is False:
        return None
    if progress is True:
        return {}
    if isinstance(progress, dict):
        # tqdm's own switch: a disabled bar is no bar (tqdm makes one without its clock)
        return None if progress.get("disable") is True else dict(progress)
    raise ValueError(f"progress: {progress!r}; give False (no bar, the default), True (a bar on "
                     "stderr) or a dict of tqdm options, e.g. {'delay': 5}")


def progress_bar(options, total, desc):
    """A tqdm bar on stderr with ``options`` (from :func:`progress_options`), or None."""
    if options is None:
        return None
    from tqdm.auto import tqdm

    try:
        bar = tqdm(**{"total": total, "unit": "step", "desc": desc, "file": sys.stderr, **options})
    except (TypeError, KeyError) as e:     # tqdm's TqdmKeyError for an unknown option
        raise ValueError(f"progress: {options!r} is not a set of tqdm options ({e})") from None
    if bar.delay > 0:
        # a phase said before the end of the delay is not shown then (see _say): show it at that
        # end, else a minute's radiation fit would show no bar until its end
        timer = threading.Timer(bar.delay, lambda: bar.disable or bar.refresh())
        timer.daemon = True
        timer.start()
    return bar


def _due(bar) -> bool:
    """Whether ``bar`` is past its ``delay`` (tqdm's option: no bar for a run shorter than that)."""
    return bar._time() >= bar.start_t + bar.delay


def _say(bar, what: str):
    """Put ``what`` after the bar, shown now only once the bar is past its delay (tqdm's own
    ``set_postfix_str`` shows it at once, delay or not: a short run in a log got a bar)."""
    bar.set_postfix_str(what, refresh=False)
    if _due(bar):
        bar.refresh()


def phase(bar, what: str):
    """Say on ``bar`` (or nowhere, for None) which phase of the preparation is under way; a
    Ctrl-C that Python lost before it is raised here (:func:`mfm.runner.threads.interrupted`)."""
    interrupted()
    if bar is not None:
        _say(bar, what)


def _restart(bar, n: int):
    """Count ``bar``'s rate, elapsed time and ETA from now, at ``n`` steps done (the compilation,
    seconds to a minute, would else show as slow steps and a far-off ETA). tqdm's ``reset``
    would also move the start of the ``delay`` to now, and ``close`` would then take a bar shown
    before as never shown and leave it at its last refresh: in a log (``mininterval`` 10 s) the
    bar of a run whose steps take less than that stayed at the first chunk, "1 %". Here the
    delay keeps its end (the time left of it, none once passed)."""
    from tqdm.std import EMA

    now = bar._time()
    bar.delay = max(0.0, bar.start_t + bar.delay - now)
    bar.start_t = bar.last_print_t = now
    bar.initial = bar.n = bar.last_print_n = n
    bar._ema_dn, bar._ema_dt, bar._ema_miniters = (EMA(bar.smoothing) for _ in range(3))


def _advance(bar, done: int, take: int, save_every: int, began: float):
    """``bar`` past a chunk of ``take`` blocks, ``done`` in all. After the first chunk (compiled
    by then) its rate, elapsed time and ETA count from now, else the compilation (seconds to a
    minute) shows as slow steps and a far-off ETA; it says how long that took since ``began``."""
    if done == take:
        compiled = time.perf_counter() - began
        _restart(bar, take * save_every)
        _say(bar, f"compiled in {compiled:.0f} s")
    else:
        bar.update(take * save_every)


def run_chunked(start, chunk, n_blocks, save_every, bar, time_axis, began=None, c=None):
    """Run ``start()`` then ``chunk(carry, c)`` (``c`` blocks, from :func:`chunk_plan`) until
    ``n_blocks`` are done,
    updating ``bar`` between chunks; stops early once a chunk has a non-finite q or q̇ (the caller
    finds where). Returns the saved outputs as numpy, the initial state first, as the unchunked
    rollout does: the same compiled steps in the same order, so the same numbers.

    ``start()`` gives (carry, the initial sample's outputs), or (carry, None) where each chunk
    gives its incoming carry's outputs first (a head: kept from the first chunk, dropped from the
    others). ``began``: when the compilation began (``time.perf_counter()``), where it was done
    before the call; the bar says how long it took. ``c``: the chunk length (None: from
    :func:`chunk_plan`)."""
    c = chunk_plan(n_blocks)[0] if c is None else c
    n_chunks = -(-n_blocks // c)
    if began is None:
        # compiled by the first calls below; else before this call, under its own phase
        _say(bar, "compiling")
        began = time.perf_counter()
    carry, first = start()
    headed = first is None
    pieces = [] if headed else [
        jax.tree_util.tree_map(lambda a: np.expand_dims(np.asarray(a), time_axis), first)]
    done = 0
    try:
        for _ in range(n_chunks):
            carry, traj = chunk(carry, c)
            take = min(c, n_blocks - done)
            # a head is the incoming carry's sample: the run's first in the first chunk, else
            # the previous chunk's last
            lo = int(headed and done > 0)
            hi = take + int(headed)
            cut = (slice(None),) * time_axis + (slice(lo, hi),)
            traj = jax.tree_util.tree_map(lambda a: np.asarray(a)[cut], traj)
            pieces.append(traj)
            done += take
            _advance(bar, done, take, save_every, began)
            if not (np.isfinite(traj[1]).all() and np.isfinite(traj[2]).all()):
                break
    finally:
        # the last count is shown, whatever ``mininterval`` held back (close shows it only for
        # a bar past its delay: a run shorter than that shows none)
        bar.close()
    return jax.tree_util.tree_map(lambda *a: np.concatenate(a, axis=time_axis), *pieces)


def run_pipelined(carry, steps, outputs, c, n_blocks, save_every, bar=None, began=None):
    """A recorded run whose outputs are made apart from its steps, in chunks of ``c`` blocks:
    ``steps(carry)`` gives (carry, the chunk's saved carries, stacked) in this thread, and
    ``outputs(head, carries)`` (the incoming carry's sample, then the chunk's) runs on a second
    thread while the next chunk steps. A time loop is one thread's work; the outputs pass (poses,
    reactions, the loads' parts: M4 134, ~20 µs a sample, more than a Verlet step) is vectorised
    over the samples and overlaps it, so a run costs its stepping and the last chunk's outputs
    instead of their sum. Every chunk is the same two compiled programs, and ``c`` a multiple
    of the outputs' group width (:data:`~.record.DEFERRED_RECORD_WIDTH`), so that every sample
    takes the same place in its group as in the run made in one call (a sample's outputs may
    differ in the last bit with its place: the double pendulum's kinetic energy did, by 1 ulp):
    the same numbers.

    ``bar`` (or None) is updated as the chunks step; stops early once a chunk has a non-finite q
    or q̇ (the caller finds where, from the outputs made up to that chunk). Returns the saved
    samples as numpy, the initial one first, as the unchunked rollout does."""
    n_chunks = -(-n_blocks // c)
    # a daemon thread (mfm.runner.threads): a Ctrl-C does not wait for the chunk it makes
    pool = Serial("mfm-outputs")

    def finish(head, carries, cut):
        return jax.tree_util.tree_map(lambda a: np.asarray(a)[cut], outputs(head, carries))

    done, made = 0, []
    try:
        for _ in range(n_chunks):
            head = carry
            carry, carries = steps(carry)
            take = min(c, n_blocks - done)
            # the head is the incoming carry's sample: the run's first in the first chunk, else
            # the previous chunk's last (kept there)
            made.append(pool.submit(finish, head, carries, slice(int(done > 0), take + 1)))
            state = carries[0]
            finite = (np.isfinite(np.asarray(state.q)[:take]).all()
                      and np.isfinite(np.asarray(state.qd)[:take]).all())
            done += take
            if bar is not None:
                _advance(bar, done, take, save_every, began)
            if not finite:
                break
        pieces = [result(f) for f in made]
    finally:
        # an interrupted run (Ctrl-C) waits neither for the chunk being made nor for those queued
        pool.close()
        if bar is not None:
            bar.close()
    return jax.tree_util.tree_map(lambda *a: np.concatenate(a, axis=0), *pieces)
