"""``python -m wgpuviewer.export``: the export command alone (``command.main``).

May import: this room.
"""

import sys

from .command import main

sys.exit(main())
