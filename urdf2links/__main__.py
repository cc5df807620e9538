"""``python -m urdf2links ...``: the same as the ``urdf2links`` command."""

import sys

from .cli import main

sys.exit(main())
