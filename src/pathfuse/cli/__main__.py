"""``python -m pathfuse.cli``: the ``pathfuse`` command."""

import sys

from pathfuse.cli.parser import main

sys.exit(main())
