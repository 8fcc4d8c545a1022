"""``python -m geofrac ...``: the ``geofrac`` command (runs this checkout's code)."""

import sys

from geofrac.cli import main

sys.exit(main())
