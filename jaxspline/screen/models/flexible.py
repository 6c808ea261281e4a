"""The ``flexible`` model: a rest-to-rest slew that keeps a structural mode quiet.

The slew follows the profile of SPEC section 2 whose ramp time tau suppresses the
satellite's flexible mode (``sat.flex``: frequency, damping, tolerance) to its tolerance
(:func:`jaxspline.kernels.flex.tau_for_tolerance`,
:func:`jaxspline.kernels.slew.slew_profile_time`), then settles. The profile's jerk is
bounded by ``accel / tau``. Its time drops once, at the switch from profile A to C
(:meth:`Flexible.time_drops`).
"""

from __future__ import annotations

import math

from jaxspline.screen.models.rest_to_rest import RestToRest

__all__ = ["Flexible"]


def _flex_tau(sat) -> float:
    """Ramp time tau [s] of a flexible satellite's profile (its mode at its tolerance).

    Raises:
      ValueError: naming the satellite if no ramp time suppresses the mode.
    """
    from jaxspline.kernels.flex import tau_for_tolerance

    f = sat.flex
    tau = float(
        tau_for_tolerance(f.tolerance, f.freq, f.damping, sat.limits.rate, sat.limits.accel)
    )
    if not math.isfinite(tau):
        raise ValueError(
            f"satellite {sat.name!r}: flex mode freq={f.freq!r} rad/s is too low for "
            f"tolerance={f.tolerance!r} at these limits (no ramp time suppresses it)"
        )
    return tau


class Flexible(RestToRest):
    """Mode-suppressing rest-to-rest slews (see the module docstring)."""

    name = "flexible"
    extra_fields = ("flex",)

    def check(self, sat) -> None:
        """A flexible satellite needs its mode: ``flex=FlexMode(...)``."""
        if sat.flex is None:
            raise ValueError(f"satellite {sat.name!r}: model 'flexible' needs flex=FlexMode(...)")

    def profile_time(self, sat, theta):
        """Profile time [s] through angles theta [rad] with the mode's ramp time."""
        from jaxspline.kernels.slew import slew_profile_time

        rate, accel = float(sat.limits.rate), float(sat.limits.accel)
        return slew_profile_time(theta, rate, accel, _flex_tau(sat))

    def time_drops(self, sat, gap_margin: float, rel: float, abs_: float) -> list:
        """The drop at the A -> C switch, with a bound of its left limit.

        The time is non-decreasing on pieces with one downward jump where the profile
        switches from A to C, at ``theta_s = 7/6 omega^2/eps`` (A: ``T_d = sqrt(8
        phi/eps)``, increasing, up to ``sqrt(28/3) omega/eps``; C then D from ``3
        omega/eps``, increasing and continuous; SPEC section 2,
        :func:`jaxspline.kernels.slew.slew_profile_kernel`).

        Args:
          sat: the satellite.
          gap_margin: float [s], as :meth:`slew_time`.
          rel: relative half-width of the angle window ``theta_s (1 -+ rel) -+ abs_``
            [rad] the switch may fall in after rounding (of the kernel's test
            ``a <= 7/6 b^2`` and of the angle).
          abs_: its absolute half-width [rad].
        Returns:
          list of ``(lo, hi, t)``: the drop lies in ``[lo, hi]`` [rad], and every angle
          there that the kernel evaluates with profile A needs at most t [s] (profile A
          forced at hi, increasing in the angle), settle and margin included.
        """
        from jaxspline.kernels.slew import slew_profile_time

        rate, accel = float(sat.limits.rate), float(sat.limits.accel)
        theta_s = 7.0 / 6.0 * rate * rate / accel
        lo, hi = theta_s * (1.0 - rel) - abs_, min(math.pi, theta_s * (1.0 + rel) + abs_)
        t_a = float(slew_profile_time(hi, rate, accel, _flex_tau(sat), kind="A"))
        return [(lo, hi, t_a + sat.settle + gap_margin)] if lo < math.pi else []

    def jerk_limit(self, sat) -> float:
        """The profile's jerk bound ``accel / tau`` [rad/s^3]."""
        return float(sat.limits.accel) / _flex_tau(sat)
