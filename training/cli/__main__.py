"""``python -m training.cli``: the ``fetchcarry`` command line."""

import sys

from training.cli import main

sys.exit(main())
