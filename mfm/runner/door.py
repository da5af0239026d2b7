"""The runner's host (:class:`RunnerHost`: programs kept on disk, mooring tables kept), the
default host of the core's calls once ``mfm`` is imported (:func:`install`). jax's persistent
compilation cache is turned on by ``mfm.load`` or the first program the runner makes
(:func:`mfm.runner.programs.folder` → :func:`mfm.runner.xla.compilation_cache`), not at import.
"""
from __future__ import annotations

from .. import host


class RunnerHost(host.Host):
    """The runner's host: a program from disk where an earlier process traced it
    (:func:`mfm.runner.programs.program`), a mooring table from the process, the database file or
    the disk where one was kept (:func:`mfm.runner.tables.mooring_table`). The same numbers as
    the plain host."""

    def program(self, jitted, name, args, static=None, *, once=False):
        from . import programs

        return programs.program(jitted, name, args, static, once=once)

    def mooring_table(self, make, x0, z0, extent, step, length, EA, weight, seabed_friction,
                      stored=None):
        from . import tables

        return tables.mooring_table(x0, z0, extent, step, length, EA, weight, seabed_friction,
                                    stored=stored, make=make)


RUNNER = RunnerHost()


def install() -> None:
    """The runner's host as the core's default (``mfm/__init__``: mfm's own state, no setting of
    the user's)."""
    host.set_default(RUNNER)
