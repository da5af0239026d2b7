"""Work on other threads that never holds the process up: a Ctrl-C (or any exception) in the
main thread ends the process at once, whatever they are doing.

Why not :class:`concurrent.futures.ThreadPoolExecutor`: Python joins its threads at exit, so a
Ctrl-C during compilation waited for every compilation under way on them (XLA's compile of a
program cannot be interrupted: RM3's cold first run exited 9 s after the interrupt, up to 35 s
for larger models; issue 54, item 15). These threads are daemon threads, which the interpreter
does not wait for; what they compute is only ever read through their futures, and a process
that is ending reads none. The main thread waits on a future (:func:`wait`), which a signal
interrupts, rather than compiling itself (a native call that a signal does not interrupt).

At exit (:func:`_at_exit`): a daemon thread still inside XLA when the interpreter finalises
aborts the process as it comes back for Python's lock ("terminate called ...", status -6: a
C++ frame that may not unwind meets the thread's forced exit). So where one of these threads is
still at work, a process ended by a Ctrl-C (an unhandled KeyboardInterrupt, its traceback
printed) flushes its streams and logs and ends as Python ends such a process, by SIGINT, with no
finalisation; any other exit waits for them, as a thread pool's did.

A Ctrl-C that Python loses (:func:`keeping_interrupts`): Python raises the KeyboardInterrupt of
a signal in whatever Python code the main thread runs next, and where that is a callback whose
exceptions the interpreter only prints (a ``gc.callbacks`` entry such as jax's
``_xla_gc_callback``, a ``__del__``, a weakref's finaliser) the interrupt is printed and lost:
RM3's cold run went on to its end (1 in 12 interrupts while it compiled, issue 54 item 15).
Inside :func:`keeping_interrupts` (the front doors' bodies) the interrupts that Python's handler
raised are counted, and the main thread's waits (:func:`result`, :func:`wait`) and the phases
raise again an interrupt counted but not raised through the run.
"""
from __future__ import annotations

import atexit
import concurrent.futures
import contextlib
import contextvars
import os
import queue
import signal
import sys
import threading

# the threads at work (a set: added and removed under the GIL)
_AT_WORK: set = set()


def _run(future: concurrent.futures.Future, fn, args) -> None:
    if not future.set_running_or_notify_cancel():
        return
    try:
        result = fn(*args)
    except BaseException as e:        # handed to whoever reads the future, as an executor does
        future.set_exception(e)
    else:
        future.set_result(result)


def _start(target, args, name) -> None:
    def work():
        try:
            target(*args)
        finally:
            _AT_WORK.discard(thread)
    thread = threading.Thread(target=work, name=name, daemon=True)
    _AT_WORK.add(thread)
    thread.start()


def _at_exit() -> None:
    """See the module's docstring: a Ctrl-C ends the process now; any other exit waits for the
    threads still at work."""
    alive = [t for t in list(_AT_WORK) if t.is_alive()]
    if not alive:
        return
    if isinstance(getattr(sys, "last_value", None), KeyboardInterrupt):
        import logging

        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:
                pass
        logging.shutdown()
        if hasattr(signal, "SIGKILL"):          # POSIX: the status Python gives (-2, 130)
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGINT)
        os._exit(130)
    for t in alive:
        t.join()


atexit.register(_at_exit)


# the interrupts raised by Python's handler in the main thread inside keeping_interrupts (a list
# per block, the innermost last); a block left by the exception forgets its own
_KEPT: list = []

# seconds between the main thread's looks at a lost interrupt while it waits for a future: a
# Ctrl-C raised where Python prints it (above) ends the process this long after at most
_LOOK_S = 0.05


def interrupted() -> None:
    """Raise KeyboardInterrupt if a Ctrl-C was raised by Python's handler inside the current
    :func:`keeping_interrupts` block and the run still goes on: the interrupt was lost in a
    callback whose exceptions Python only prints (see the module's docstring). Only in the main
    thread, where the blocks and the signal's handler are: another thread's run (a script's own
    thread calling simulate) goes on."""
    if _KEPT and _KEPT[-1] and threading.current_thread() is threading.main_thread():
        raise KeyboardInterrupt("mfm: a Ctrl-C raised inside a callback whose exceptions "
                                "Python only prints (the traceback above), raised again here")


@contextlib.contextmanager
def keeping_interrupts():
    """A block (a front door's body) in which the Ctrl-C's that Python loses are raised again
    (module docstring). In the main thread, with a Python SIGINT handler (not ignored, not the OS
    default), that handler is wrapped for the block: an interrupt it raises is counted, the
    exception left as it was; a handler that does not raise (a script's own graceful stop) is
    not changed. A block that ends normally with an interrupt counted raises it. The handler is
    given back on the way out, whatever happens. A context manager, not a decorator, so that the
    warnings of the front door keep pointing at its caller."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGINT)
    if not callable(previous):
        yield
        return
    kept: list = []

    def handler(signum, frame):
        try:
            previous(signum, frame)
        except KeyboardInterrupt:
            kept.append(signum)
            raise

    signal.signal(signal.SIGINT, handler)
    _KEPT.append(kept)
    try:
        yield
        interrupted()
    finally:
        _KEPT.pop()
        signal.signal(signal.SIGINT, previous)


def result(future: concurrent.futures.Future):
    """``future.result()``, looking every ``_LOOK_S`` for an interrupt Python lost
    (:func:`interrupted`)."""
    # wait() and then result(): a TimeoutError that fn raised is fn's, not the look's
    while not concurrent.futures.wait([future], timeout=_LOOK_S).done:
        interrupted()
    return future.result()


def background(fn, *args, name: str = "mfm-compile") -> concurrent.futures.Future:
    """``fn(*args)`` on a daemon thread of its own, in this thread's context variables (the host
    of :func:`mfm.host.using`); its future."""
    future = concurrent.futures.Future()
    _start(contextvars.copy_context().run, (_run, future, fn, args), name)
    return future


def wait(fn, *args, name: str = "mfm-compile"):
    """``fn(*args)``, made on a daemon thread while this one waits for it: a Ctrl-C here is
    raised at once, where ``fn`` made here (an XLA compilation) would hold it until its end."""
    return result(background(fn, *args, name=name))


class Serial:
    """Calls made one after another, in the order given, on one daemon thread (a
    ``ThreadPoolExecutor(1)`` that the process does not wait for at exit)."""

    def __init__(self, name: str):
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._futures: list = []
        _start(self._work, (), name)

    def _work(self) -> None:
        while (item := self._queue.get()) is not None:
            _run(*item)
            del item               # the arguments (a chunk's arrays) not held until the next

    def submit(self, fn, *args) -> concurrent.futures.Future:
        future = concurrent.futures.Future()
        self._futures.append(future)
        self._queue.put((future, fn, args))
        return future

    def close(self) -> None:
        """Cancel the calls not yet begun; the thread ends after the one under way (if any),
        unwaited for."""
        for f in self._futures:
            f.cancel()
        self._futures.clear()
        self._queue.put(None)
