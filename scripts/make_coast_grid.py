"""Write the shipped coastline grid, ``jaxspline/data/coast_cells_30.npz``.

The plan page and the ground-track figure draw coastlines from
:func:`jaxspline.readers.land.land_fraction`; its default 0.25 deg grid is this file:
the ocean cell counts of the GLOBE land mask (``global_land_mask`` package) per
30 x 30 block, with the cell centres. Run from the repository root:

    python scripts/make_coast_grid.py
"""

import numpy as np

from jaxspline.readers.land import COAST_BLOCK, COAST_FILE, ocean_cells


def main() -> None:
    """Stream the mask once and write :data:`COAST_FILE` (arrays lat, lon, ocean_cells)."""
    lat, lon, count = ocean_cells(COAST_BLOCK)
    np.savez_compressed(COAST_FILE, lat=lat, lon=lon, ocean_cells=count)
    print(f"wrote {COAST_FILE} ({COAST_FILE.stat().st_size:,} bytes)")


if __name__ == "__main__":
    main()
