"""``python -m graybox``: the same command as ``graybox``."""

import sys

from ._cli import main

sys.exit(main())
