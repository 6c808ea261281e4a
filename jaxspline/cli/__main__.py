"""``python -m jaxspline.cli``: the ``jaxspline`` command from the current checkout."""

import sys

from jaxspline.cli import main

if __name__ == "__main__":
    sys.exit(main())
