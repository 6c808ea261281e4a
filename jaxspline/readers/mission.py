"""What a planning problem is: satellites, targets, areas, the scenario (the planner's data types).

A :class:`Scenario` is everything :func:`jaxspline.plan` needs; the product layer
builds it from TOML/CSV files (:mod:`jaxspline.readers.scenario`) and the aeossp adapter from a
benchmark case (:mod:`jaxspline.aeossp.adapter`). All fields are SI units and radians;
times are seconds from the scenario epoch. Every constructor validates eagerly and
raises ``ValueError`` naming the field and the value.

Maneuver models (:data:`jaxspline.base.models.BUILTIN_MODELS` names the built-in ones; each is a
:class:`~jaxspline.screen.models.ManeuverModel`, ``Satellite.maneuver``), one per
satellite:

* ``"per_channel"`` - roll, pitch, yaw each under a rate and acceleration bound, the
  exact-T reachable sets of SPEC section 1; the spacecraft leaves each observation
  with the scan's rates and must meet the next one's (no rest in between);
* ``"eigen_axis"`` - rest-to-rest bang-coast-bang slew about the eigen-axis between
  the two lines of sight, plus a settling time (the aeossp_standard rule);
* ``"flexible"`` - rest-to-rest slew with the continuous-acceleration profile A/C/D of
  SPEC section 2 whose jerk ramp tau is chosen from the structural mode
  (``tau_for_tolerance``), plus a settling time.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import math

import numpy as np

from jaxspline.base.elements import CircularOrbit, julian_date
from jaxspline.base.models import ManeuverModel, maneuver_model
from jaxspline.kernels.limits import AxisLimits
from jaxspline.readers.config import PlannerConfig, positive_number
from jaxspline.readers.stereo_request import Stereo

__all__ = [
    "AREA",
    "HELD_KINDS",
    "KIND_NAMES",
    "POINT",
    "STEREO",
    "STRIP",
    "DEFAULT_STRIP_DURATION",
    "DEFAULT_SWATH",
    "Area",
    "FlexMode",
    "Power",
    "Satellite",
    "Scenario",
    "Targets",
    "make_targets",
]

POINT = 0  # a target imaged from one point
STRIP = 1  # a target imaged along a strip
AREA = 2  # a target imaged by strips at a held roll, valued by the share of its samples covered
STEREO = 3  # a target imaged by two or three looks making a stereo product (its Stereo)
#: Name of each target kind, by kind code (plan files, pages).
KIND_NAMES = ("point", "strip", "area", "stereo")
#: Kinds imaged by looks held fixed in the track frame, any number of them per target.
HELD_KINDS = (AREA, STEREO)
DEFAULT_STRIP_DURATION = (0.0, 60.0)  # [s] shortest and longest area strip when unnamed
_SHARE_TOL = 1e-9  # the samples' shares may exceed 1 by rounding this much
DEFAULT_SWATH = 20e3  # [m] ground width imaged across a strip when a satellite names none


@dataclasses.dataclass(frozen=True)
class Power:
    """Battery and loads of one satellite (aeossp RULES.md rule 8 semantics).

    Attributes:
      capacity_wh: battery capacity [Wh].
      initial_wh: battery level at t = 0 [Wh].
      idle_w: always-on load [W].
      imaging_w: extra load while imaging [W].
      slew_w: extra load while maneuvering [W].
      charge_w: solar charging while sunlit (cylindrical Earth shadow) [W].
    """

    capacity_wh: float
    initial_wh: float
    idle_w: float = 0.0
    imaging_w: float = 0.0
    slew_w: float = 0.0
    charge_w: float = 0.0

    def __post_init__(self):
        positive_number("power.capacity_wh", self.capacity_wh)
        for f in ("initial_wh", "idle_w", "imaging_w", "slew_w", "charge_w"):
            positive_number(f"power.{f}", getattr(self, f), allow_zero=True)
        if self.initial_wh > self.capacity_wh:
            raise ValueError(
                f"power.initial_wh={self.initial_wh!r} exceeds capacity_wh={self.capacity_wh!r}"
            )


@dataclasses.dataclass(frozen=True)
class FlexMode:
    """One structural mode of a flexible spacecraft (model ``"flexible"``, SPEC section 2).

    Attributes:
      freq: circular frequency nu [rad/s] (2 Hz = 4 pi rad/s).
      damping: damping ratio zeta (>= 0).
      tolerance: admissible residual amplitude A(t_k) [rad] (eq. 7).
    """

    freq: float
    damping: float = 0.01
    tolerance: float = 1e-7

    def __post_init__(self):
        positive_number("flex.freq", self.freq)
        positive_number("flex.damping", self.damping, allow_zero=True)
        positive_number("flex.tolerance", self.tolerance)


@dataclasses.dataclass(frozen=True)
class Satellite:
    """One satellite: orbit, agility, sensor, optional battery.

    Attributes:
      name: identifier (unique in a scenario).
      orbit: a :class:`jaxspline.geometry.orbit.CircularOrbit` or the two TLE lines
        ``(line1, line2)`` (SGP4, WGS84 constants).
      model: maneuver model, a registered name (:func:`jaxspline.base.model_names`).
      limits: :class:`AxisLimits`; per_channel: rate [rad/s] and accel [rad/s^2] per
        channel (roll, pitch, yaw), arrays [3]; eigen_axis / flexible: scalars about
        the eigen-axis.
      off_nadir_max: pointing limit [rad] (0 < . < pi/2).
      sensor: sensor type (free text, e.g. "visible"); targets may require one.
      settle: settling time after a rest-to-rest slew [s] (eigen_axis, flexible).
      flex: :class:`FlexMode` (required for ``"flexible"``).
      power: :class:`Power` or None (no battery constraint).
      swath: ground width imaged across the scan direction [m] (> 0), taken as
        independent of the viewing angle; the CZML draws footprints of this width, and
        without ``fov`` it gives the field of view of area strips.
      fov: cross-track field of view of area strips [rad] (None: the swath seen from
        the orbit's altitude at nadir).
      edge_band: ``(lo, hi)``, the off-nadir angles [rad] an area strip's edges must lie
        between (None: only the boresight's ``off_nadir_max``).
      strip_duration: ``(shortest, longest)`` imaging time of an area strip [s].
      duty: imaging seconds allowed in any window of one orbital period (None: no rule).
      ifov: the angle one detector pixel sees [rad] (a look's pixel scale is its slant
        range times it; None: stereo products ignore the pixel scale).
    """

    name: str
    orbit: object
    model: str = "per_channel"
    limits: AxisLimits = AxisLimits(np.radians([2.0, 2.0, 2.0]), np.radians([1.0, 1.0, 1.0]))
    off_nadir_max: float = math.radians(45.0)
    sensor: str = "visible"
    settle: float = 0.0
    flex: FlexMode | None = None
    power: Power | None = None
    swath: float = DEFAULT_SWATH
    fov: float | None = None
    edge_band: tuple | None = None
    strip_duration: tuple = DEFAULT_STRIP_DURATION
    duty: float | None = None
    ifov: float | None = None

    def __post_init__(self):
        who = f"satellite {self.name!r}"
        try:
            maneuver = maneuver_model(self.model)
        except ValueError as exc:
            raise ValueError(f"{who}: {exc}") from None
        if not isinstance(self.orbit, CircularOrbit):
            ok = isinstance(self.orbit, tuple | list) and len(self.orbit) == 2
            if not ok or not all(isinstance(x, str) for x in self.orbit):
                raise ValueError(
                    f"{who}: orbit must be a CircularOrbit or (tle_line1, tle_line2), "
                    f"got {self.orbit!r}"
                )
        rate = np.asarray(self.limits.rate, np.float64)
        accel = np.asarray(self.limits.accel, np.float64)
        shape = maneuver.limit_shape
        for name, x in (("rate", rate), ("accel", accel)):
            if np.shape(x) not in ((), (3,)) or (shape == () and np.ndim(x) != 0):
                raise ValueError(f"{who}: limits.{name} must be {shape or 'a scalar'}, got {x!r}")
            if not (np.all(np.isfinite(x)) and np.all(x > 0)):
                raise ValueError(f"{who}: limits.{name} must be finite and > 0, got {x!r}")
        object.__setattr__(
            self,
            "limits",
            AxisLimits(np.broadcast_to(rate, shape).copy(), np.broadcast_to(accel, shape).copy()),
        )
        if not 0.0 < float(self.off_nadir_max) < math.pi / 2:
            raise ValueError(
                f"{who}: off_nadir_max must be in (0, pi/2), got {self.off_nadir_max!r}"
            )
        positive_number(f"{who}: settle", self.settle, allow_zero=True)
        positive_number(f"{who}: swath", self.swath)
        self._check_area_fields(who)
        maneuver.check(self)

    def _check_area_fields(self, who: str) -> None:
        """The fields of area strips: fov in (0, pi/2), an ordered edge band inside the
        hemisphere, ordered non-negative strip durations, a positive duty."""
        if self.fov is not None and not 0.0 < float(self.fov) < math.pi / 2:
            raise ValueError(f"{who}: fov must be in (0, pi/2), got {self.fov!r}")
        if self.edge_band is not None:
            lo, hi = (float(x) for x in self.edge_band)
            if not 0.0 <= lo < hi < math.pi / 2:
                raise ValueError(
                    f"{who}: edge_band must be 0 <= lo < hi < pi/2, got {self.edge_band!r}"
                )
        lo, hi = (float(x) for x in self.strip_duration)
        if not (math.isfinite(hi) and 0.0 <= lo <= hi and hi > 0.0):
            raise ValueError(
                f"{who}: strip_duration must be 0 <= shortest <= longest, longest > 0 and "
                f"finite, got {self.strip_duration!r}"
            )
        if self.duty is not None:
            positive_number(f"{who}: duty", self.duty)
        if self.ifov is not None:
            positive_number(f"{who}: ifov", self.ifov)

    @property
    def maneuver(self) -> ManeuverModel:
        """The :class:`~jaxspline.screen.models.ManeuverModel` that ``model`` names."""
        return maneuver_model(self.model)


@dataclasses.dataclass(frozen=True)
class Targets:
    """R imaging targets, struct of numpy arrays (build with :func:`make_targets`).

    Attributes:
      name: str [R].
      kind: int [R], POINT (0), STRIP (1) or AREA (2).
      lat, lon: geodetic start point [rad] (the target itself for a point, the centre
        of an area).
      alt: height above the WGS84 ellipsoid [m].
      duration: imaging time of a point [s] (0 for strips).
      length: strip length [m] (0 for points); azimuth: strip direction at the start,
        clockwise from north [rad] (0 for points). A strip is scanned at one of the
        planner's ground speeds, from whichever end the satellite's motion favours.
      value: priority / weight collected if imaged (> 0).
      t_lo, t_hi: imaging window [s]: start >= t_lo and end <= t_hi (-inf/+inf: free).
      sensor: required sensor type [R] ("" = any).
      mid_lo, mid_hi: window of the imaging midpoint [s]: ``mid_lo <= (start + end) / 2
        <= mid_hi`` (-inf/+inf: free); a desired time ``d`` with tolerance ``tol`` is
        ``[d - tol, d + tol]``.
      min_duration: shortest accepted imaging time ``end - start`` [s] (0: any); a
        strip's scan speeds whose ``length / speed`` is shorter are not used.
    """

    name: np.ndarray
    kind: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    alt: np.ndarray
    duration: np.ndarray
    length: np.ndarray
    azimuth: np.ndarray
    value: np.ndarray
    t_lo: np.ndarray
    t_hi: np.ndarray
    sensor: np.ndarray
    mid_lo: np.ndarray
    mid_hi: np.ndarray
    min_duration: np.ndarray

    def __len__(self) -> int:
        return int(self.kind.shape[0])

    def concat(self, other: Targets) -> Targets:
        """The targets of ``self`` followed by those of ``other``.

        Args:
          other: Targets.
        Returns:
          Targets of R + R' entries.
        """
        return Targets(
            **{
                f.name: np.concatenate([getattr(self, f.name), getattr(other, f.name)])
                for f in dataclasses.fields(self)
            }
        )


def make_targets(
    kind,
    lat,
    lon,
    *,
    alt=0.0,
    duration=0.0,
    length=0.0,
    azimuth=0.0,
    value=1.0,
    t_lo=-np.inf,
    t_hi=np.inf,
    sensor="",
    name=None,
    mid_lo=-np.inf,
    mid_hi=np.inf,
    min_duration=0.0,
) -> Targets:
    """Validate and broadcast target fields into :class:`Targets`.

    All fields broadcast together to R targets (scalars allowed).

    Args:
      kind: int [R], POINT (0), STRIP (1) or AREA (2, its samples in a
        :class:`Area`).
      lat: float [R], geodetic latitude of the start point [rad], in [-pi/2, pi/2].
      lon: float [R], longitude of the start point [rad].
      alt: float [R], height above the WGS84 ellipsoid [m].
      duration: float [R], imaging time of a point [s], > 0 for points (0 kept for strips).
      length: float [R], strip length [m], > 0 for strips (0 kept for points).
      azimuth: float [R], strip direction, clockwise from north [rad].
      value: float [R], priority, > 0.
      t_lo: float [R], imaging window start [s from the epoch] (-inf: free).
      t_hi: float [R], imaging window end [s from the epoch] (+inf: free), >= t_lo.
      sensor: str [R], required sensor type ("" = any).
      name: str [R]; None gives "t0", "t1", ...
      mid_lo: float [R], earliest imaging midpoint [s from the epoch] (-inf: free).
      mid_hi: float [R], latest imaging midpoint [s from the epoch] (+inf: free), >= mid_lo.
      min_duration: float [R], shortest imaging time [s], >= 0; a point's ``duration``
        must reach it.
    Returns:
      Targets.
    Raises:
      ValueError: naming the target and field (``targets[i].field``) or the shapes.
    """
    kind = np.atleast_1d(np.asarray(kind, dtype=np.int64))
    num = {
        "lat": lat,
        "lon": lon,
        "alt": alt,
        "duration": duration,
        "length": length,
        "azimuth": azimuth,
        "value": value,
        "t_lo": t_lo,
        "t_hi": t_hi,
        "mid_lo": mid_lo,
        "mid_hi": mid_hi,
        "min_duration": min_duration,
    }
    kind, out = _broadcast_fields(kind, num)
    _check_target_fields(kind, out)
    n = kind.size
    sensor = np.broadcast_to(np.asarray(sensor, dtype=object), (n,)).astype(str)
    names = _target_names(name, n)
    out["duration"] = np.where(kind == POINT, out["duration"], 0.0)
    out["length"] = np.where(kind == STRIP, out["length"], 0.0)
    out["azimuth"] = np.where(kind == STRIP, out["azimuth"], 0.0)
    return Targets(name=names, kind=np.array(kind), sensor=sensor, **out)


def _broadcast_fields(kind: np.ndarray, num: dict) -> tuple[np.ndarray, dict]:
    """Broadcast ``kind`` and the numeric fields ``num`` (name -> value) to one shape
    (ValueError when they do not broadcast). Returns ``(kind, out)``: the broadcast
    kinds and a dict of the fields as fresh writable float64 arrays, in ``num``'s
    order."""
    try:
        arrs = np.broadcast_arrays(kind, *(np.asarray(v, np.float64) for v in num.values()))
    except ValueError as exc:
        raise ValueError(f"target fields are not broadcastable: {exc}") from None
    return arrs[0], dict(zip(num, (np.array(a) for a in arrs[1:]), strict=True))


def _reject_first(field: str, mask: np.ndarray, why: str, values: np.ndarray) -> None:
    """Raise ValueError naming the first target where ``mask`` holds
    (``targets[i].field: why, got value``); nothing when ``mask`` is all False."""
    if mask.any():
        i = int(np.flatnonzero(mask)[0])
        raise ValueError(f"targets[{i}].{field}: {why}, got {values[i]!r}")


def _check_target_fields(kind: np.ndarray, out: dict) -> None:
    """The rules of :func:`make_targets` on the broadcast fields, in order: a known
    kind, finite numbers, latitude within the poles, positive value, a length for
    strips and a duration for points, ordered windows, and a finite non-negative
    ``min_duration`` that a point's duration reaches. Raises ValueError at the first
    target breaking the first rule it breaks."""
    _reject_first(
        "kind",
        ~np.isin(kind, (POINT, STRIP, AREA, STEREO)),
        "must be 0 (point), 1 (strip), 2 (area) or 3 (stereo)",
        kind,
    )
    for f in ("lat", "lon", "alt", "duration", "length", "azimuth", "value"):
        _reject_first(f, ~np.isfinite(out[f]), "must be finite", out[f])
    lat, value, length, duration = out["lat"], out["value"], out["length"], out["duration"]
    _reject_first("lat", np.abs(lat) > np.pi / 2, "must be within [-pi/2, pi/2] rad", lat)
    _reject_first("value", value <= 0, "must be > 0", value)
    _reject_first("length", (kind == STRIP) & (length <= 0), "must be > 0 for a strip", length)
    point = kind == POINT
    _reject_first("duration", point & (duration <= 0), "must be > 0 for a point", duration)
    _reject_first("t_hi", ~(out["t_lo"] <= out["t_hi"]), "must be >= t_lo", out["t_hi"])
    _reject_first("mid_hi", ~(out["mid_lo"] <= out["mid_hi"]), "must be >= mid_lo", out["mid_hi"])
    min_d = out["min_duration"]
    ok = np.isfinite(min_d) & (min_d >= 0)
    _reject_first("min_duration", ~ok, "must be finite and >= 0", min_d)
    short = point & (duration < min_d)
    _reject_first("duration", short, "must be >= min_duration for a point", duration)


def _target_names(name, n: int) -> np.ndarray:
    """The targets' names: ``name`` as str [n], or "t0", "t1", ... when None
    (ValueError when ``name`` has not n entries)."""
    names = np.array([f"t{i}" for i in range(n)]) if name is None else np.asarray(name, str)
    if names.shape != (n,):
        raise ValueError(f"targets.name must have {n} entries, got shape {names.shape}")
    return names


@dataclasses.dataclass(frozen=True)
class Area:
    """An area target: a region whose value is its priority times the share of it imaged.

    The planner lays the area out as weighted samples (the scenario's own, or a grid of
    ``spacing`` over the polygon, :func:`jaxspline.geometry.area_grid.area_grid`) and
    plans strips at a held roll over it (:mod:`jaxspline.planner.area_options`); a sample
    counts once however often it is imaged. Its priority, imaging window and sensor are
    those of its row ``target`` of ``scenario.targets`` (kind :data:`AREA`).

    Attributes:
      name: label (unique among the scenario's areas; its target's name).
      target: index of its row in ``scenario.targets``.
      geometry: GeoJSON geometry dict, ``{"type": "Polygon" | "MultiPolygon",
        "coordinates": ...}``, positions ``[lon, lat]`` in degrees (RFC 7946), or None
        when the samples are given.
      spacing: sample grid spacing [m] (0 when the samples are given).
      samples: float [N, 3], the given samples ``(lon [deg], lat [deg], weight)``, each
        weight the share of the area the sample stands for (summing to at most 1);
        empty [0, 3] when the planner lays out the grid.
      min_share: least share of the area a plan must cover (NaN: none).
    """

    name: str
    target: int
    geometry: dict | None = None
    spacing: float = 0.0
    samples: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3)))
    min_share: float = math.nan

    def __post_init__(self):
        who = f"area {self.name!r}"
        if self.geometry is not None and (
            not isinstance(self.geometry, dict)
            or self.geometry.get("type") not in ("Polygon", "MultiPolygon")
        ):
            raise ValueError(f"{who}: geometry must be a GeoJSON Polygon or MultiPolygon dict")
        smp = np.asarray(self.samples, np.float64)
        if smp.ndim != 2 or smp.shape[1] != 3 or not np.all(np.isfinite(smp)):
            raise ValueError(f"{who}: samples must be finite [N, 3] (lon, lat, weight)")
        if smp.shape[0] and (np.any(smp[:, 2] < 0) or smp[:, 2].sum() > 1.0 + _SHARE_TOL):
            raise ValueError(f"{who}: sample weights must be >= 0 and sum to at most 1")
        object.__setattr__(self, "samples", smp)
        if smp.shape[0] == 0:
            if self.geometry is None:
                raise ValueError(f"{who}: give a polygon (geometry) or the samples")
            positive_number(f"{who}: spacing", self.spacing)
        m = float(self.min_share)
        if not (math.isnan(m) or 0.0 <= m <= 1.0):
            raise ValueError(f"{who}: min_share must be in [0, 1] (NaN: none), got {m!r}")


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A planning problem: who (satellites), what (targets), when (epoch, duration), how.

    Attributes:
      name: label.
      epoch: UTC datetime of t = 0.
      duration: planning horizon [s] (observations lie in [0, duration]).
      satellites: tuple of :class:`Satellite` (unique names).
      targets: :class:`Targets`.
      planner: :class:`PlannerConfig`.
      areas: tuple of :class:`Area`, one per target of kind :data:`AREA` (unique names).
      stereo: tuple of :class:`jaxspline.readers.stereo_request.Stereo`, one per target
        of kind :data:`STEREO`.
    """

    name: str
    epoch: _dt.datetime
    duration: float
    satellites: tuple
    targets: Targets
    planner: PlannerConfig = PlannerConfig()
    areas: tuple = ()
    stereo: tuple = ()

    def __post_init__(self):
        if not isinstance(self.epoch, _dt.datetime):
            raise ValueError(f"epoch must be a datetime, got {self.epoch!r}")
        if self.epoch.tzinfo is None:
            object.__setattr__(self, "epoch", self.epoch.replace(tzinfo=_dt.UTC))
        positive_number("duration", self.duration)
        sats = tuple(self.satellites)
        if not sats:
            raise ValueError("satellites: a scenario needs at least one satellite")
        names = [s.name for s in sats]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"satellites: duplicate name {dup[0]!r}")
        object.__setattr__(self, "satellites", sats)
        if not isinstance(self.targets, Targets):
            raise ValueError(f"targets must be a Targets, got {type(self.targets).__name__}")
        for field, cls, kind in (("areas", Area, AREA), ("stereo", Stereo, STEREO)):
            object.__setattr__(self, field, self._requests(field, cls, kind))

    def _requests(self, field: str, cls, kind: int) -> tuple:
        """``self.<field>`` checked: instances of ``cls``, unique names, exactly one per
        target of ``kind``."""
        items = tuple(getattr(self, field))
        seen = set()
        for a in items:
            if not isinstance(a, cls):
                raise ValueError(
                    f"{field}: every entry must be a {cls.__name__}, got {type(a).__name__}"
                )
            if a.name in seen:
                raise ValueError(f"{field}: duplicate name {a.name!r}")
            seen.add(a.name)
            t = int(a.target)
            if not 0 <= t < len(self.targets) or self.targets.kind[t] != kind:
                raise ValueError(f"{field} {a.name!r}: target {a.target!r} is not of kind {kind}")
        rows = sorted(int(a.target) for a in items)
        if rows != np.flatnonzero(self.targets.kind == kind).tolist():
            raise ValueError(
                f"{field}: every target of kind {kind} needs exactly one {cls.__name__}"
            )
        return items

    @property
    def epoch_jd(self) -> float:
        """Julian date (UTC) of the epoch."""
        return julian_date(self.epoch)

    def at(self, seconds: float) -> _dt.datetime:
        """The UTC instant ``seconds`` after the epoch.

        Args:
          seconds: float [s].
        Returns:
          datetime (UTC).
        """
        return self.epoch + _dt.timedelta(seconds=float(seconds))
