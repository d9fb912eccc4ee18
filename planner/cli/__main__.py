"""``python -m qsplan.planner.cli``: the ``qsplan`` command."""

import sys

from qsplan.planner.cli.main import main

sys.exit(main())
