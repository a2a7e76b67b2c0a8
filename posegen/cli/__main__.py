"""``python -m posegen.cli``: the same as the ``posegen`` command."""

import sys

from posegen.cli.main import main

sys.exit(main())
