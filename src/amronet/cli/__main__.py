"""``python -m amronet.cli``: the same as the ``amronet`` command."""

import sys

from amronet.cli.main import main

sys.exit(main())
