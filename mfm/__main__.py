"""``python -m mfm ...`` is the ``mfm`` command (it imports the package, jax included, first:
the ``mfm`` console script answers ``--help`` faster)."""
import sys

from mfm_cli import main

sys.exit(main())
