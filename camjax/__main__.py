"""``python -m camjax``: the ``camjax`` command."""

import sys

from .cli import main

sys.exit(main())
