"""``python -m jaxspline.cli``: the ``jaxspline`` command from the current checkout."""

import sys

from jaxspline.cli import main

sys.exit(main())
