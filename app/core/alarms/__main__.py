"""``python -m app.core.alarms``: the alarm rules, and the gas sensors' bump tests
and calibrations (see :mod:`app.core.alarms.cli`)."""

import sys

from app.core.alarms.cli import main

sys.exit(main())
