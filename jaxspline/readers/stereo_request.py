"""What a stereo target asks for: the looks that make a product, and how a product is judged.

A stereo target (a row of kind ``STEREO`` in ``scenario.targets``) is imaged by two or
three looks of the same ground disk from different angles: push-broom looks at steering
angles held fixed in the satellite's track frame, in one pass of one satellite or by two
satellites close in time. Its value counts once, when the plan holds a valid *product*:

* a **pair**: two looks whose strips both cover at least ``min_overlap`` of the disk,
  converging at the target by an angle in ``convergence``, with pixel scales (slant
  range times pixel angle) within ``max_scale_ratio`` of each other, their midpoints at
  most ``max_separation`` apart, both of one pass of one satellite or (with
  ``cross_satellite``) of two satellites;
* a **triple** (``product = "tri"``): three looks, every two in mode and time, their
  common overlap at least ``min_overlap``, at least two valid pairs among them and one
  look within ``anchor_off_nadir`` of nadir.

A pair's quality is ``Q = w_g Qg + w_o Qo + w_r Qr`` (``weights``): ``Qg`` 1 inside the
preferred convergence ``band`` and falling by 0.1 a degree outside it, ``Qo =
min(1, overlap / 0.95)``, ``Qr = max(0, 1 - (ratio - 1) / 0.5)``; a triple's is
``min(1, best pair + tri_bonus)``. The target's value is its priority times
``(1 - quality_weight) + quality_weight * Q`` of its best product: 1 (the default) values
quality in full, a small weight ranks products by coverage first and quality second.
"""

from __future__ import annotations

import dataclasses
import math

from jaxspline.readers.config import positive_number

__all__ = ["PRODUCTS", "Stereo"]

#: The products a stereo target may ask for.
PRODUCTS = ("pair", "tri")


def _deg(x: float) -> float:
    return math.radians(x)


@dataclasses.dataclass(frozen=True)
class Stereo:
    """A stereo target's request (module docstring). Angles in radians, times in seconds.

    Attributes:
      name: label (its target's name).
      target: index of its row in ``scenario.targets`` (kind ``STEREO``).
      radius: radius of the ground disk to image about the target [m] (> 0).
      product: ``"pair"`` or ``"tri"`` (a triple preferred; a pair still counts).
      min_overlap: least share of the disk inside every look's strip, in (0, 1].
      convergence: ``(lo, hi)`` accepted convergence angles [rad].
      band: ``(lo, hi)`` preferred convergence angles [rad] (quality).
      max_scale_ratio: largest ratio of the looks' pixel scales (>= 1).
      max_separation: largest time between two looks' midpoints [s].
      cross_satellite: two satellites may make a pair.
      anchor_off_nadir: a triple's anchor look lies within this of nadir [rad].
      weights: ``(geometry, overlap, resolution)`` weights of a pair's quality.
      tri_bonus: added to a triple's best pair quality (capped at 1).
      quality_weight: share of the value that depends on the product's quality, [0, 1].
    """

    name: str
    target: int
    radius: float
    product: str = "pair"
    min_overlap: float = 0.8
    convergence: tuple = (_deg(5.0), _deg(45.0))
    band: tuple = (_deg(8.0), _deg(18.0))
    max_scale_ratio: float = 1.5
    max_separation: float = 3600.0
    cross_satellite: bool = True
    anchor_off_nadir: float = _deg(10.0)
    weights: tuple = (0.5, 0.35, 0.15)
    tri_bonus: float = 0.0
    quality_weight: float = 1.0

    def __post_init__(self):
        who = f"stereo target {self.name!r}"
        positive_number(f"{who}: radius", self.radius)
        if self.product not in PRODUCTS:
            raise ValueError(f"{who}: product must be one of {PRODUCTS}, got {self.product!r}")
        if not 0.0 < float(self.min_overlap) <= 1.0:
            raise ValueError(f"{who}: min_overlap must be in (0, 1], got {self.min_overlap!r}")
        for field, (lo, hi) in (("convergence", self.convergence), ("band", self.band)):
            if not 0.0 <= float(lo) <= float(hi) < math.pi:
                raise ValueError(f"{who}: {field} must be 0 <= lo <= hi < pi rad, got {(lo, hi)!r}")
        if not float(self.max_scale_ratio) >= 1.0:
            raise ValueError(f"{who}: max_scale_ratio must be >= 1, got {self.max_scale_ratio!r}")
        positive_number(f"{who}: max_separation", self.max_separation, allow_zero=True)
        if not 0.0 <= float(self.anchor_off_nadir) < math.pi / 2:
            raise ValueError(
                f"{who}: anchor_off_nadir must be in [0, pi/2), got {self.anchor_off_nadir!r}"
            )
        if len(self.weights) != 3 or any(not (math.isfinite(w) and w >= 0) for w in self.weights):
            raise ValueError(f"{who}: weights must be three numbers >= 0, got {self.weights!r}")
        positive_number(f"{who}: tri_bonus", self.tri_bonus, allow_zero=True)
        if not 0.0 <= float(self.quality_weight) <= 1.0:
            raise ValueError(
                f"{who}: quality_weight must be in [0, 1], got {self.quality_weight!r}"
            )
        object.__setattr__(self, "convergence", tuple(float(x) for x in self.convergence))
        object.__setattr__(self, "band", tuple(float(x) for x in self.band))
        object.__setattr__(self, "weights", tuple(float(x) for x in self.weights))

    def value_share(self, quality: float) -> float:
        """The share of the target's priority a product of ``quality`` collects."""
        w = float(self.quality_weight)
        return (1.0 - w) + w * float(quality)
