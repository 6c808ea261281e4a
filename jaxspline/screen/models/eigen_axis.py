"""The ``eigen_axis`` model: a rigid rest-to-rest bang-coast-bang slew.

The slew turns about the eigen-axis through the angle between the two lines of sight
with the satellite's scalar rate and acceleration bounds
(:func:`jaxspline.kernels.slew.bang_coast_bang_time`), then settles for ``sat.settle``.
The time is continuous and non-decreasing in the angle.
"""

from __future__ import annotations

from jaxspline.screen.models.rest_to_rest import RestToRest

__all__ = ["EigenAxis"]


class EigenAxis(RestToRest):
    """Bang-coast-bang eigen-axis slews (see the module docstring)."""

    name = "eigen_axis"

    def profile_time(self, sat, theta):
        """Bang-coast-bang time [s] through angles theta [rad]."""
        from jaxspline.kernels.slew import bang_coast_bang_time

        return bang_coast_bang_time(theta, float(sat.limits.rate), float(sat.limits.accel))
