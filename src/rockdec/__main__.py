"""``python -m rockdec``: the ``rockdec`` command."""

import sys

from rockdec.cli import main

sys.exit(main())
