"""The maneuver-model protocol and the registry that names the models (base layer).

A satellite's ``model`` (a scenario key, e.g. ``"eigen_axis"``) names one
:class:`ManeuverModel`; :func:`maneuver_model` looks it up. A model is a stateless object:
everything satellite-specific (limits, settle time, flex mode) is read from the satellite
it is given. The pipeline asks the model, never the name, what a transition needs:

* how the screen evaluates it (:meth:`ManeuverModel.screen_model`: per-channel
  :class:`~jaxspline.kernels.limits.AxisLimits` or a rest-to-rest
  :class:`~jaxspline.screen.slew_table.SlewTable`) and what a screened pair requires
  (:meth:`~ManeuverModel.need`, :meth:`~ManeuverModel.pair_requirements`);
* the first observation's requirement and the gap beyond which every pair is feasible
  (:meth:`~ManeuverModel.first_requirements`, :meth:`~ManeuverModel.far_gap`);
* the shape of its limits, its own satellite fields and their validation, the jerk limit
  of its flown joins and its attitude law between observations.

A new model is one file: a class with these members (subclass
:class:`~jaxspline.screen.models.rest_to_rest.RestToRest` for a rest-to-rest slew and
give only its profile time), registered with :func:`register_model`. The registry lives
in the base layer so that a scenario's reader can check the model a satellite names
without importing the screen; the built-in models register themselves when
:mod:`jaxspline.screen.models` is imported (``import jaxspline`` does).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

__all__ = ["BUILTIN_MODELS", "ManeuverModel", "maneuver_model", "model_names", "register_model"]

#: Relative safety factor of every model's far gap (rounding of the bound's arithmetic).
FAR_SAFETY = 1.0 + 1e-9
#: Attitude laws between observations a model may ask for.
ATTITUDE_LAWS = ("pointing", "zero_yaw")
#: Frames a model's slews may compare lines of sight in.
LOS_FRAMES = ("inertial", "earth_fixed")

#: The models :mod:`jaxspline.screen.models` registers on import, in that order.
BUILTIN_MODELS = ("per_channel", "eigen_axis", "flexible", "roll_only")

_REGISTRY: dict[str, ManeuverModel] = {}


@runtime_checkable
class ManeuverModel(Protocol):
    """What the planner needs to know about one kind of maneuver.

    Attributes:
      name: the scenario key (``Satellite.model``).
      rest_to_rest: True if every transition is a slew between lines of sight that starts
        and ends at rest (screened through a slew table); False if transitions join the
        exact per-channel states of the observations.
      limit_shape: shape of ``limits.rate`` / ``limits.accel``: ``(3,)`` per channel
        (roll, pitch, yaw) or ``()`` about the eigen-axis.
      extra_fields: satellite fields only this model reads (e.g. ``("flex",)``).
      attitude_law: ``"pointing"`` (the observation's per-channel law carries on) or
        ``"zero_yaw"`` (line-of-sight pointing with zero yaw) between observations.
      los_frame: the frame its slews compare lines of sight in: ``"inertial"`` or
        ``"earth_fixed"`` (the options' ``start_los`` / ``end_los`` are given in it).
      tracks_points: whether it can image point and strip targets (pitch and yaw
        tracking); a model without can image area strips only.
      first_from_nadir: whether its first observation needs the maneuver from nadir
        (False: the attitude is free before the first observation).
    """

    name: str
    rest_to_rest: bool
    limit_shape: tuple
    extra_fields: tuple
    attitude_law: str
    los_frame: str
    tracks_points: bool
    first_from_nadir: bool

    def check(self, sat) -> None:
        """Raise ValueError naming the satellite if a field this model needs is missing."""

    def screen_model(self, sat, gap_margin: float):
        """What the screen evaluates pairs of ``sat`` with (AxisLimits or SlewTable)."""

    def need(self, t_min, T):
        """Required time [s] of feasible screened pairs, from the screen's t_min and T."""

    def pair_requirements(self, sat, options, src, dst, screen_model):
        """Required time [P] [s] of pairs src -> dst of ``sat``; inf where infeasible."""

    def first_requirements(self, sat, options, idx, screen_model):
        """Required time [K] [s] before options idx as the first observation; inf: never."""

    def far_gap(self, sat, options, idx, nadir_rate: float, screen_model) -> float:
        """A gap [s] beyond which every transition between options idx is feasible."""

    def jerk_limit(self, sat) -> float:
        """Bound on the eigen-axis jerk of a flown join [rad/s^3] (inf: none)."""


def register_model(model: ManeuverModel) -> ManeuverModel:
    """Make ``model`` available under ``model.name`` (returns it).

    Raises:
      ValueError: the name is taken by another model, or a member is missing or invalid.
    """
    if not isinstance(model, ManeuverModel):
        raise ValueError(f"{model!r} lacks members of the ManeuverModel protocol")
    if model.attitude_law not in ATTITUDE_LAWS:
        raise ValueError(
            f"model {model.name!r}: attitude_law must be one of {ATTITUDE_LAWS}, "
            f"got {model.attitude_law!r}"
        )
    if model.los_frame not in LOS_FRAMES:
        raise ValueError(
            f"model {model.name!r}: los_frame must be one of {LOS_FRAMES}, got {model.los_frame!r}"
        )
    old = _REGISTRY.get(model.name)
    if old is not None and type(old) is not type(model):
        raise ValueError(f"model name {model.name!r} is taken by {old!r}")
    _REGISTRY[model.name] = model
    return model


def model_names() -> tuple[str, ...]:
    """Names of the registered models, in registration order."""
    return tuple(_REGISTRY)


def maneuver_model(name: str) -> ManeuverModel:
    """The registered model called ``name``.

    Raises:
      ValueError: no model has that name (the message lists the known ones).
    """
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"model must be one of {model_names()}, got {name!r}") from None
