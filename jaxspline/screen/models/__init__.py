"""Maneuver models: what a satellite needs between two observations.

A satellite names its model in ``Satellite.model``; :func:`maneuver_model` returns the
:class:`ManeuverModel` object, which the whole pipeline asks instead of branching on the
name (``Satellite.maneuver`` is the same lookup). Built in:

* ``per_channel`` (:class:`PerChannel`) - exact-T per-channel transfers (SPEC section 1);
* ``eigen_axis`` (:class:`EigenAxis`) - rigid rest-to-rest bang-coast-bang slews;
* ``flexible`` (:class:`Flexible`) - rest-to-rest slews that keep a flexible mode below
  its tolerance (SPEC section 2);
* ``roll_only`` (:class:`RollOnly`) - one roll axis, a bang-coast-bang slew plus
  settling, with its kernels and host functions (the regional_coverage benchmark's
  slew rule); it images area strips only.

A new model is one file: a class with the members of :class:`ManeuverModel` (for a
rest-to-rest slew, a :class:`RestToRest` subclass with its ``profile_time``), passed to
:func:`register_model`.

Part of layer 2 (``screen``): ``base`` <- ``per_channel`` (screens pairs with
:mod:`jaxspline.screen.pairs`), ``rest_to_rest`` (reads
:mod:`jaxspline.screen.slew_table`) <- ``eigen_axis``, ``flexible``, ``roll_only``.
"""

from jaxspline.base.models import (
    BUILTIN_MODELS,
    ManeuverModel,
    maneuver_model,
    model_names,
    register_model,
)
from jaxspline.screen.models.eigen_axis import EigenAxis
from jaxspline.screen.models.flexible import Flexible
from jaxspline.screen.models.per_channel import PerChannel
from jaxspline.screen.models.rest_to_rest import RestToRest
from jaxspline.screen.models.roll_only import (
    RollLimits,
    RollOnly,
    RollTransition,
    roll_min_gap,
    roll_need,
    roll_profile,
    roll_profile_kernel,
    roll_slew_time,
    roll_transition,
    roll_transition_kernel,
)

__all__ = [
    "EigenAxis",
    "Flexible",
    "ManeuverModel",
    "PerChannel",
    "RestToRest",
    "RollLimits",
    "RollOnly",
    "RollTransition",
    "maneuver_model",
    "model_names",
    "register_model",
    "roll_min_gap",
    "roll_need",
    "roll_profile",
    "roll_profile_kernel",
    "roll_slew_time",
    "roll_transition",
    "roll_transition_kernel",
]

for _model in (PerChannel(), EigenAxis(), Flexible(), RollOnly()):
    register_model(_model)
del _model
assert model_names()[: len(BUILTIN_MODELS)] == BUILTIN_MODELS  # noqa: S101  (the names' one list)
