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
"""
from __future__ import annotations

import atexit
import concurrent.futures
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


def background(fn, *args, name: str = "mfm-compile") -> concurrent.futures.Future:
    """``fn(*args)`` on a daemon thread of its own, in this thread's context variables (the host
    of :func:`mfm.host.using`); its future."""
    future = concurrent.futures.Future()
    _start(contextvars.copy_context().run, (_run, future, fn, args), name)
    return future


def wait(fn, *args, name: str = "mfm-compile"):
    """``fn(*args)``, made on a daemon thread while this one waits for it: a Ctrl-C here is
    raised at once, where ``fn`` made here (an XLA compilation) would hold it until its end."""
    return background(fn, *args, name=name).result()


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
