"""Where a long preparation says how far it has got, to whoever shows it.

A front door with a progress display (``mfm.load`` and ``mfm.simulate`` with ``progress=``, so
``mfm simulate``) runs its work under :func:`reporting`; a long computation inside it (the
state-space fit's orders and passivity iterations, MoorPy's mooring tables) calls :func:`say`
now and then, and the words reach that display, or nowhere when there is none. A context
variable, not an argument: the fit's options key its cache (:mod:`hydro.fitcache`), and the
loads' ``from_parsed`` share one signature. It is the calling thread's: work handed to another
thread says nothing unless that thread reports too.
"""
from __future__ import annotations

import contextlib
import contextvars
from typing import Callable

_reporter: contextvars.ContextVar = contextvars.ContextVar("hydro_phase_reporter", default=None)


def say(what: str) -> None:
    """Tell the display of the work under way (if any) that ``what`` is being done now."""
    report = _reporter.get()
    if report is not None:
        report(what)


@contextlib.contextmanager
def reporting(report: Callable[[str], None] | None):
    """Send what the computations inside say (:func:`say`) to ``report`` (None: nowhere)."""
    token = _reporter.set(report)
    try:
        yield
    finally:
        _reporter.reset(token)


def every(total: int, parts: int = 10) -> int:
    """How many items of ``total`` to do between two reports, for about ``parts`` reports."""
    return max(1, -(-int(total) // parts))
