"""``python -m mfm.cli …`` is the ``mfm`` command (as ``python -m mfm`` and the console script).

The command's code is in :mod:`mfm.io.cli` (the sub-commands) and :mod:`mfm_cli` (the argument
parser, outside the package so that ``mfm --help`` starts without jax).
"""
import sys

if __name__ == "__main__":
    from mfm_cli import main

    sys.exit(main())
