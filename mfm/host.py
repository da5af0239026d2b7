"""What the pure core asks of whoever runs it, and nothing more: the two pieces of host work that
the core's own functions cannot leave to their caller.

- **A program to call from the host** (:meth:`Host.program`): a Newton step of the equilibrium
  (:func:`mfm.frequency.rest.jet`), the samples of H(q) that tell a model's water which dofs its
  joints move (:func:`mfm.loads.water.moving_dofs`). By default jax's own ``jit``, traced in this
  process.
- **A mooring line's table** (:meth:`Host.mooring_table`): MoorPy's quasi-static line on a grid,
  made on the host because the compiled time loop cannot call MoorPy
  (:func:`mfm.loads.catenary_tables.make_table`). By default made here and now.

The runner (:mod:`mfm.runner`) names its own host as the default when ``mfm`` is imported
(:func:`set_default`): programs kept on disk and compiled once at a low optimisation level
(:mod:`mfm.runner.programs`), tables kept in the process, in the database file and on disk
(:mod:`mfm.runner.tables`). The numbers are the same either way; only the waiting differs. A
caller hands another host for the length of a block (:func:`using`, a context variable: two
threads may use two hosts); ``using(PLAIN)`` runs the core with jax's jit and MoorPy alone.
"""
from __future__ import annotations

import contextlib
import contextvars
import functools


class Host:
    """The plain host: everything made in this process, nothing kept."""

    def program(self, jitted, name: str, args: tuple, static: dict | None = None, *,
                once: bool = False):
        """``jitted`` (a ``jax.jit``-ed function) ready to call with ``args`` and the static
        keyword arguments ``static``, and to ``compile(*args)`` ahead of the call (on another
        thread, beside other work); ``name`` names it, ``once`` says it runs once per model (a
        host may compile such a program with less optimisation)."""
        return _Jitted(jitted, dict(static or {}))

    def mooring_table(self, make, x0, z0, extent, step, length, EA, weight, seabed_friction,
                      stored=None):
        """(xs, zs, coef) of a catenary line's table, ``make(x0, z0, extent, step, length, EA,
        weight, seabed_friction)`` (the load's maker,
        :func:`mfm.loads.catenary_tables.make_table`, handed in so that this module imports no
        load); ``stored``: the database file where ``mfm fits`` may have stored it, which the
        plain host does not read."""
        return make(x0, z0, extent, step, length, EA, weight, seabed_friction)


class _Jitted:
    """The plain host's program: jax's jit, which compiles at the first call (``compile`` ahead
    of it would compile a second time: jax's ahead-of-time executable is not the call's)."""

    def __init__(self, jitted, static):
        self._call = functools.partial(jitted, **static)

    def __call__(self, *args):
        return self._call(*args)

    def compile(self, *args):
        return None


PLAIN = Host()
_CURRENT: contextvars.ContextVar[Host | None] = contextvars.ContextVar("mfm_host", default=None)
# the host of a call that was handed none: the plain one, until the package that runs the core
# names its own (mfm/__init__: the runner's, mfm.runner.door.install)
_default = [PLAIN]


def current() -> Host:
    """The host of the call under way: the one handed with :func:`using`, else the default
    (the runner's once ``mfm`` is imported; :data:`PLAIN` for the core alone)."""
    return _CURRENT.get() or _default[0]


def set_default(host: Host) -> None:
    """The host of calls that were handed none (the runner names its own, once)."""
    _default[0] = host


@contextlib.contextmanager
def using(host: Host):
    """``host`` for the core's calls inside the ``with`` block (this thread's context)."""
    token = _CURRENT.set(host)
    try:
        yield host
    finally:
        _CURRENT.reset(token)
