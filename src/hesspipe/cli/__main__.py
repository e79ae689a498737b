"""``python -m hesspipe.cli``: the command line, as the ``hesspipe`` entry point runs it."""

import sys

from . import main

sys.exit(main())
