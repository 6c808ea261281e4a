"""Write the shipped coastline grid, ``jaxspline/data/coast_cells_30.npz``.

The plan page and the ground-track figure draw coastlines from
:func:`jaxspline.base.land.land_fraction`, and :func:`jaxspline.base.land.is_land`
answers land tests, from this file: the ocean cell counts of the GLOBE land mask
(``global_land_mask`` package) per 30 x 30 block with the cell centres, the mask bits
of every block the coast crosses, and the mask's axes. Run from the repository root:

    python scripts/make_coast_grid.py
"""

import numpy as np

from jaxspline.base.land import COAST_BLOCK, COAST_FILE, coast_bits, mask_axes, ocean_cells


def main() -> None:
    """Stream the mask twice and write :data:`COAST_FILE`."""
    lat, lon, count = ocean_cells(COAST_BLOCK)
    bits = coast_bits(count, COAST_BLOCK)
    mask_lat, mask_lon = mask_axes()
    np.savez_compressed(
        COAST_FILE,
        lat=lat,
        lon=lon,
        ocean_cells=count,
        bits=bits,
        mask_lat=mask_lat,
        mask_lon=mask_lon,
    )
    print(f"wrote {COAST_FILE} ({COAST_FILE.stat().st_size:,} bytes)")


if __name__ == "__main__":
    main()
