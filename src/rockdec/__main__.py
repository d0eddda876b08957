"""``python -m rockdec``: the ``rockdec`` command."""

import sys

from rockdec.cli import main

__all__: list[str] = []

sys.exit(main())
