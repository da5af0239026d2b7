"""``python -m mfm ...`` is the ``mfm`` command."""
import sys

from mfm.cli import main

sys.exit(main())
