"""``python -m mfm.cli …`` is the ``mfm`` command (as ``python -m mfm`` and the console script).

The command's code is in :mod:`mfm.io.cli` (the sub-commands) and :mod:`mfm_cli` (the argument
parser, apart so that ``mfm --help`` starts without jax); an old import from here
(``from mfm.cli import main``) finds its name there and warns once with the new path.
"""
import importlib
import sys

_HOMES = ("mfm_cli", "mfm.io.cli")


def __getattr__(name):
    from ._compat import _warn_once

    for home in _HOMES:
        module = importlib.import_module(home)
        if hasattr(module, name):
            _warn_once(f"mfm.cli.{name}", f"{home}.{name}")
            return getattr(module, name)
    raise AttributeError(f"module 'mfm.cli' has no attribute {name!r} (the command's code is in "
                         f"{', '.join(_HOMES)})")


if __name__ == "__main__":
    from mfm_cli import main

    sys.exit(main())
