"""What a plan collects of its stereo targets: the product per target and each look's share.

:func:`look_values` is what each look of a plan adds in time order (a look that completes
a target's best product so far adds the difference, the others 0: a look alone is worth
nothing); :func:`stereo_report` is the ``report["stereo"]`` of a plan, per stereo target
the product it collects (pair or triple, its looks, convergence, overlap, pixel-scale
ratio, quality and the chance that the benchmark's overlap estimates find it valid) or
None.
"""

from __future__ import annotations

import math

import numpy as np

from jaxspline.search.stereo import ProductCounts

__all__ = ["look_values", "stereo_report"]


def look_values(table, chosen, starts) -> np.ndarray:
    """The value each option of ``chosen`` adds to the ones starting before it (0 for
    every option that is not a look).

    Args:
      table: the problem's :class:`jaxspline.search.stereo.ProductTable`.
      chosen: int [M], option ids of the plan; starts: float [M], their starts [s].
    Returns:
      float [M].
    """
    counts = ProductCounts(table)
    out = np.zeros(len(chosen))
    for j in np.argsort(np.asarray(starts), kind="stable"):
        c = int(chosen[j])
        if table.is_look[c]:
            out[j] = counts.change(c, +1)
    return out


def stereo_report(sc, table, products, chosen) -> list:
    """Per stereo target of ``sc`` the product the plan ``chosen`` collects.

    Args:
      sc: Scenario; table: the problem's ProductTable; products: the merged
        :class:`jaxspline.screen.stereo_products.StereoProducts` (same order as the
        table's); chosen: int [M], option ids of the plan.
    Returns:
      list of dict (JSON-ready), one per stereo request in ``sc.stereo`` order:
      ``target``, ``candidates`` (its valid products: 0 when no plan can cover it),
      ``product`` ("pair", "tri" or None), ``looks`` (option ids), and for a product
      ``quality``, ``convergence_deg``, ``overlap``, ``scale_ratio``, ``confidence`` and
      ``value``.
    """
    counts = ProductCounts(table)
    for c in chosen:
        if table.is_look[int(c)]:
            counts.change(int(c), +1)
    out = []
    for req in sc.stereo:
        t = int(req.target)
        p = counts.best[t]
        row = {"target": req.name, "candidates": len(table.target_products[t]),
               "product": None, "looks": [], "quality": None}  # fmt: skip
        if p >= 0:
            row.update(
                product="pair" if int(products.size[p]) == 2 else "tri",
                looks=list(table.looks[p]),
                quality=round(float(products.quality[p]), 6),
                convergence_deg=round(math.degrees(float(products.convergence[p])), 4),
                overlap=round(float(products.overlap[p]), 4),
                scale_ratio=round(float(products.scale_ratio[p]), 4),
                confidence=round(float(products.confidence[p]), 4),
                value=float(table.value[p]),
            )
        out.append(row)
    return out
