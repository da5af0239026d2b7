"""Python's cyclic garbage collector and the objects that live as long as the process.

Importing jax, xarray, hydro and mfm leaves ~150,000 objects the collector tracks (modules,
functions, classes; a full collection then finds no garbage among them). Every later full
collection walks them all again, and so does the interpreter's exit: a process that imported mfm
spent 0.5 s in its exit, and one that had also run M4 134 1.0–1.3 s, before it returned to the
shell (its last line's time against the shell's clock; 0.1 s with ``os._exit``: the collections
at exit, not the work of the run). benchmarks/RESULTS.md has the whole processes' figures.

The command line (``mfm ...``), which owns its process, moves what exists once it has imported
mfm into the collector's permanent generation (:func:`freeze`, the standard library's
:func:`gc.freeze`, its tool for long-lived objects): later collections and the exit skip them.
Nothing is lost: those objects are the libraries' own and live to the end of the process anyway,
and everything made afterwards is collected as before. It also freezes at its exit whatever its
command made (:func:`freeze_at_exit`): it has closed its files by then, and the objects would only
be collected to be thrown away with the process. ``MFM_GC_FREEZE=off`` keeps Python's default.

``import mfm`` does neither (issue 52: the library changes no global state a user did not ask
for): a script of the user's, whose own objects may rely on being collected, gets the same
shorter collections by calling ``gc.freeze()`` itself after its imports (README, Speed).
"""
from __future__ import annotations

import atexit
import gc
import os

from .xla import switched_off


def enabled() -> bool:
    """Whether ``MFM_GC_FREEZE`` leaves the freezing on (the default)."""
    return not switched_off(os.environ.get("MFM_GC_FREEZE"))


def freeze() -> bool:
    """Move every object the collector tracks now into its permanent generation (unless
    ``MFM_GC_FREEZE=off``); returns whether it did."""
    if not enabled():
        return False
    gc.freeze()
    return True


_at_exit = False


def freeze_at_exit() -> None:
    """Freeze whatever exists when the interpreter exits, before its final collections (the
    command line's: see the module docstring). Registered once however often it is called."""
    global _at_exit
    if not _at_exit:
        atexit.register(freeze)
        _at_exit = True
