"""CZML export of a plan: satellites, targets, areas, observations and footprints for Cesium.

:func:`write_czml` turns a :class:`jaxspline.planner.result.PlanResult` into a CZML document
(built with the ``czml3`` package, imported lazily) that opens in Cesium
(``viewer.dataSources.add(Cesium.CzmlDataSource.load("plan.czml"))`` or drag and drop
on https://sandcastle.cesium.com):

* the document packet holds the clock over ``[epoch, epoch + duration]``;
* one packet per satellite (id ``sat-<k>``): Earth-fixed (``"FIXED"``) positions in
  metres sampled every ``step`` seconds and interpolated by Cesium with Lagrange
  polynomials, a point, a label and a path of one orbit around the current time;
* one packet per target (id ``target-<r>``): a point at its geodetic position
  (cartographic degrees), green if the plan images it, grey otherwise;
* one packet per observation (id ``obs-<i>``): a straight line from the satellite to
  the target, available only during the imaging interval ``[start, end]``;
* one sensor footprint per observation (id ``footprint-<i>``), during ``[start, end]``:
  for a strip the imaged ground so far, the footprint swept by the satellite's swath
  from the strip's start (:func:`jaxspline.geometry.ground.footprint_lonlat`), growing in
  :data:`FOOTPRINT_FRAMES` steps; for a point a disc as wide as the swath; for an area
  strip the ground it sweeps (``PlanResult.footprints``);
* one packet per part of every area target (id ``area-<a>-<p>``): the polygon with its
  holes, translucent, its covered share in the description; and per planned strip of
  an area (id ``taken-<i>``) its footprint in the satellite's colour from the start of
  its imaging to the end of the horizon (the strips taken).

Satellite positions come from :func:`jaxspline.geometry.orbit.tabulate_orbits` (SGP4 for TLEs,
analytic for circular orbits) and are rotated to Earth-fixed coordinates by the Earth
rotation angle (:mod:`jaxspline.geometry.frames`). :func:`satellite_tracks` and
:data:`SATELLITE_COLORS` are shared with the plan figures (:mod:`jaxspline.products.plot_plan`).
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import jax
import numpy as np

from jaxspline.base.elements import MU_EARTH, gmst
from jaxspline.geometry.frames import earth_rotation_angle, teme_to_ecef
from jaxspline.geometry.ground import footprint_lonlat
from jaxspline.geometry.orbit import orbit_position, tabulate_orbits
from jaxspline.geometry.routes import AREA, KIND_NAMES, STRIP
from jaxspline.planner.files import atomic_write_text, refuse_overwrite

__all__ = ["SATELLITE_COLORS", "satellite_tracks", "write_czml"]

#: Colour of satellite k (``SATELLITE_COLORS[k % len]``), hex RGB: matplotlib's tab10
#: without its green and grey, which mark imaged / not imaged targets.
SATELLITE_COLORS = (
    "#1f77b4",
    "#ff7f0e",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#bcbd22",
    "#17becf",
)
IMAGED_RGBA = (44, 160, 44, 255)  # target imaged by the plan (green)
NOT_IMAGED_RGBA = (150, 150, 150, 200)  # target not imaged (grey)
LAGRANGE_DEGREE = 5  # Cesium interpolation degree of the sampled satellite positions
CLOCK_MULTIPLIER = 60.0  # simulated seconds per wall-clock second when the file opens
SATELLITE_PIXELS = 8.0  # point size of a satellite [px]
TARGET_PIXELS = 6.0  # point size of a target not imaged [px]
IMAGED_PIXELS = 8.0  # point size of an imaged target [px]
PATH_WIDTH = 1.5  # satellite path width [px]
LINK_WIDTH = 2.0  # satellite-to-target line width [px]
LABEL_FONT = "11pt sans-serif"
LABEL_OFFSET_PX = (12.0, 0.0)  # label offset right of the satellite point [px]
POSITION_DECIMALS = 3  # metres rounded to millimetres in the file
DEGREE_DECIMALS = 7  # longitudes / latitudes rounded to ~1 cm in the file
FOOTPRINT_FRAMES = 8  # a strip's footprint grows in this many steps while it is imaged
FOOTPRINT_ALPHA = 160  # opacity of a footprint during imaging (0..255)
TAKEN_ALPHA = 110  # opacity of an area's strip once taken
AREA_RGBA = (255, 215, 0, 60)  # area fill (gold, translucent)
AREA_OUTLINE_RGBA = (255, 215, 0, 255)

# one XLA program per table shape (eager dispatch would compile every primitive)
_orbit_position = jax.jit(orbit_position)


def _rgba(color: str, alpha: int = 255) -> list[int]:
    """[r, g, b, a] (0..255) of a ``#rrggbb`` colour."""
    c = color.lstrip("#")
    return [int(c[i : i + 2], 16) for i in (0, 2, 4)] + [int(alpha)]


def _check_step(step) -> float:
    s = float(step)
    if not (math.isfinite(s) and s > 0):
        raise ValueError(f"step must be finite and > 0 [s], got {step!r}")
    return s


def satellite_tracks(scenario, step: float):
    """Earth-fixed positions of every satellite on a time grid over the horizon.

    Args:
      scenario: :class:`jaxspline.readers.mission.Scenario`.
      step: sample spacing [s] (> 0); the grid is ``0, step, 2 step, ...`` plus the
        horizon end ``scenario.duration``.
    Returns:
      ``(t [M] [s from the epoch], r [S, M, 3] [m] Earth-fixed, ok [S, M] bool)``.
      Positions are the quintic Hermite interpolant of the orbit table with knots every
      ``step`` seconds (exact SGP4 / analytic values at the knots), rotated from TEME
      by ``theta(t) = GMST(epoch) + w_E t``; ``ok`` is False where SGP4 failed at a
      bracketing knot (do not draw those samples).
    """
    step = _check_step(step)
    duration = float(scenario.duration)
    t = np.arange(0.0, duration, step)
    t = np.append(t[t < duration - 1e-9 * step], duration)
    sats = scenario.satellites
    with jax.enable_x64(True):  # metre-level positions need float64 (global config untouched)
        table = tabulate_orbits([s.orbit for s in sats], scenario.epoch_jd, duration, step)
        idx = np.arange(len(sats))[:, None]
        r_teme = np.asarray(_orbit_position(table.orbit, t[None, :], sat=idx), np.float64)
    theta = earth_rotation_angle(float(gmst(scenario.epoch_jd)), t)
    r = teme_to_ecef(r_teme, theta)
    ok = np.stack([table.usable(k, t) for k in range(len(sats))]) & np.all(np.isfinite(r), -1)
    return t, r, ok


def _period(r) -> float:
    """Keplerian period [s] of a circular orbit of the mean radius of samples r [..., 3]."""
    a = float(np.mean(np.linalg.norm(r, axis=-1)))
    return 2.0 * math.pi * math.sqrt(a**3 / MU_EARTH)


def _czml_document(result, *, step: float = 60.0):
    """The CZML document of a plan (a ``czml3.Document``; see the module docstring).

    Args:
      result: :class:`jaxspline.planner.result.PlanResult`.
      step: satellite position sample spacing [s] (> 0).
    Returns:
      ``czml3.Document`` whose first packet (id ``"document"``) carries the clock;
      serialise with ``doc.to_json()``.
    """
    from czml3 import Document
    from czml3.types import TimeInterval

    step = _check_step(step)
    sc = result.scenario
    horizon = TimeInterval(start=sc.at(0.0), end=sc.at(sc.duration))
    packets = [_clock_packet(sc, horizon)]
    packets += _satellite_packets(result, horizon, step)
    packets += _target_packets(result)
    packets += _observation_packets(result)
    packets += _footprint_packets(result, horizon)
    packets += _area_packets(result)
    return Document(packets=packets)


def _line_material(rgba):
    """A solid polyline material of colour ``rgba`` ([r, g, b, a], 0..255)."""
    from czml3.properties import Color, PolylineMaterial, SolidColorMaterial

    return PolylineMaterial(solidColor=SolidColorMaterial(color=Color(rgba=rgba)))


def _clock_packet(sc, horizon):
    """The document packet: the scenario's name and the clock over the horizon."""
    from czml3 import CZML_VERSION, Packet
    from czml3.enums import ClockRanges, ClockSteps
    from czml3.properties import Clock

    return Packet(
        id="document",
        name=sc.name,
        version=CZML_VERSION,
        clock=Clock(
            interval=horizon,
            currentTime=sc.at(0.0),
            multiplier=CLOCK_MULTIPLIER,
            range=ClockRanges.LOOP_STOP,
            step=ClockSteps.SYSTEM_CLOCK_MULTIPLIER,
        ),
    )


def _satellite_packets(result, horizon, step: float) -> list:
    """One packet a satellite: sampled Earth-fixed positions, point, label, one-orbit path."""
    from czml3 import Packet
    from czml3.enums import HorizontalOrigins, InterpolationAlgorithms, LabelStyles
    from czml3.properties import Color, Label, Path, Point, Position
    from czml3.types import Cartesian2Value

    sc, obs = result.scenario, result.observations
    t, r, ok = satellite_tracks(sc, step)
    out = []
    for k, sat in enumerate(sc.satellites):
        rgba = _rgba(SATELLITE_COLORS[k % len(SATELLITE_COLORS)])
        good = ok[k]
        samples = np.column_stack([t[good], np.round(r[k, good], POSITION_DECIMALS)])
        half = 0.5 * _period(r[k, good])
        n_obs = int(np.sum(obs.sat == k))
        out.append(
            Packet(
                id=f"sat-{k}",
                name=sat.name,
                description=f"satellite {sat.name}: model {sat.model}, {n_obs} observations",
                availability=horizon,
                position=Position(
                    epoch=sc.at(0.0),
                    referenceFrame="FIXED",
                    cartesian=samples.ravel().tolist(),
                    interpolationAlgorithm=InterpolationAlgorithms.LAGRANGE,
                    interpolationDegree=LAGRANGE_DEGREE,
                ),
                point=Point(color=Color(rgba=rgba), pixelSize=SATELLITE_PIXELS),
                label=Label(
                    text=sat.name,
                    font=LABEL_FONT,
                    style=LabelStyles.FILL_AND_OUTLINE,
                    fillColor=Color(rgba=rgba),
                    outlineColor=Color(rgba=[0, 0, 0, 255]),
                    outlineWidth=2.0,
                    horizontalOrigin=HorizontalOrigins.LEFT,
                    pixelOffset=Cartesian2Value(values=list(LABEL_OFFSET_PX)),
                ),
                path=Path(
                    leadTime=half,
                    trailTime=half,
                    width=PATH_WIDTH,
                    resolution=step,
                    material=_line_material(rgba),
                ),
            )
        )
    return out


def _target_packets(result) -> list:
    """One packet a target: a point at its position, green when imaged, grey otherwise."""
    from czml3 import Packet
    from czml3.properties import Color, Point, Position

    tg, obs = result.scenario.targets, result.observations
    imaged = np.zeros(len(tg), bool)
    imaged[np.asarray(obs.target, np.int64)] = True
    outline = Color(rgba=[0, 0, 0, 255])
    points = {  # two styles, each built (and validated) once and shared by its targets
        flag: Point(
            color=Color(rgba=list(IMAGED_RGBA if flag else NOT_IMAGED_RGBA)),
            pixelSize=IMAGED_PIXELS if flag else TARGET_PIXELS,
            outlineColor=outline,
            outlineWidth=1.0,
        )
        for flag in (True, False)
    }
    out = []
    for i in range(len(tg)):
        kind = KIND_NAMES[int(tg.kind[i])]
        out.append(
            Packet(
                id=f"target-{i}",
                name=str(tg.name[i]),
                description=(
                    f"{kind} target {tg.name[i]}: value {float(tg.value[i]):g}, "
                    f"{'imaged' if imaged[i] else 'not imaged'}"
                ),
                position=Position(
                    cartographicDegrees=[
                        math.degrees(float(tg.lon[i])),
                        math.degrees(float(tg.lat[i])),
                        float(tg.alt[i]),
                    ]
                ),
                point=points[bool(imaged[i])],
            )
        )
    return out


def _observation_packets(result) -> list:
    """One packet an observation: the satellite-to-target line during its imaging."""
    from czml3 import Packet
    from czml3.enums import ArcTypes
    from czml3.properties import Polyline, PositionList
    from czml3.types import TimeInterval

    sc, obs = result.scenario, result.observations
    out = []
    for i in range(len(obs)):
        k, j = int(obs.sat[i]), int(obs.target[i])
        out.append(
            Packet(
                id=f"obs-{i}",
                name=f"{sc.satellites[k].name} -> {sc.targets.name[j]}",
                description=(
                    f"imaging {float(obs.start[i]):.3f} s to {float(obs.end[i]):.3f} s, "
                    f"maneuver {float(obs.maneuver[i]):.3f} s, slack {float(obs.slack[i]):.3f} s"
                ),
                availability=TimeInterval(start=sc.at(obs.start[i]), end=sc.at(obs.end[i])),
                polyline=Polyline(
                    positions=PositionList(
                        references=[f"sat-{k}#position", f"target-{j}#position"]
                    ),
                    arcType=ArcTypes.NONE,
                    width=LINK_WIDTH,
                    material=_line_material(_rgba(SATELLITE_COLORS[k % len(SATELLITE_COLORS)])),
                ),
            )
        )
    return out


def _degrees_list(lon, lat) -> list[float]:
    """``[lon, lat, 0, lon, lat, 0, ...]`` [deg] of a ring (CZML cartographicDegrees)."""
    pts = np.column_stack([lon, lat, np.zeros(len(lon))])
    return np.round(pts, DEGREE_DECIMALS).ravel().tolist()


def _footprint_packets(result, horizon) -> list:
    """Sensor footprints of every observation and the taken strips of the areas."""
    sc = result.scenario
    obs = result.observations
    tg = sc.targets
    out = []
    for i in range(len(obs)):
        k, j = int(obs.sat[i]), int(obs.target[i])
        color = SATELLITE_COLORS[k % len(SATELLITE_COLORS)]
        if int(tg.kind[j]) == AREA:
            ring = result.footprints[i] if result.footprints else None
            if ring is not None:
                out.append(_ring_packet(sc, obs, i, color, ring))
                out.append(_taken_strip(sc, obs, i, color, horizon, ring))
        elif int(tg.kind[j]) == STRIP:
            out.append(_strip_footprint(sc, obs, i, color))
        else:
            out.append(_disc_footprint(sc, obs, i, color))
    return out


def _ring_packet(sc, obs, i: int, color: str, ring):
    """Observation i of an area: the ground ``ring`` it sweeps, during imaging."""
    from czml3 import Packet
    from czml3.properties import Polygon, PositionList
    from czml3.types import TimeInterval

    k, j = int(obs.sat[i]), int(obs.target[i])
    t0, t1 = float(obs.start[i]), float(obs.end[i])
    return Packet(
        id=f"footprint-{i}",
        name=f"footprint {sc.satellites[k].name} -> {sc.targets.name[j]}",
        availability=TimeInterval(start=sc.at(t0), end=sc.at(t1)),
        polygon=Polygon(
            positions=PositionList(cartographicDegrees=_degrees_list(*ring)),
            material=_footprint_fill(color),
        ),
    )


@functools.cache
def _footprint_fill(color: str):
    """The translucent fill of a footprint during imaging (one per color, shared)."""
    from czml3.properties import Color, Material, SolidColorMaterial

    rgba = _rgba(color, FOOTPRINT_ALPHA)
    return Material(solidColor=SolidColorMaterial(color=Color(rgba=rgba)))


def _disc_footprint(sc, obs, i: int, color: str):
    """Observation i of a point target: a disc as wide as the swath during imaging."""
    from czml3 import Packet
    from czml3.properties import Ellipse, Position
    from czml3.types import TimeInterval

    k, j = int(obs.sat[i]), int(obs.target[i])
    sat, tg = sc.satellites[k], sc.targets
    t0, t1 = float(obs.start[i]), float(obs.end[i])
    return Packet(
        id=f"footprint-{i}",
        name=f"footprint {sat.name} -> {tg.name[j]}",
        availability=TimeInterval(start=sc.at(t0), end=sc.at(t1)),
        position=Position(
            cartographicDegrees=[
                math.degrees(float(tg.lon[j])),
                math.degrees(float(tg.lat[j])),
                0.0,
            ]
        ),
        ellipse=Ellipse(
            semiMajorAxis=sat.swath / 2,
            semiMinorAxis=sat.swath / 2,
            material=_footprint_fill(color),
        ),
    )


def _strip_footprint(sc, obs, i: int, color: str):
    """Observation i of a strip: the ground imaged so far, growing in
    :data:`FOOTPRINT_FRAMES` steps during imaging."""
    from czml3 import Packet
    from czml3.properties import Polygon, PositionList
    from czml3.types import IntervalValue, TimeInterval, TimeIntervalCollection

    k, j = int(obs.sat[i]), int(obs.target[i])
    sat, tg = sc.satellites[k], sc.targets
    t0, t1 = float(obs.start[i]), float(obs.end[i])
    frames = []
    for f in range(FOOTPRINT_FRAMES):
        a, b = (
            t0 + (t1 - t0) * f / FOOTPRINT_FRAMES,
            t0 + (t1 - t0) * (f + 1) / FOOTPRINT_FRAMES,
        )
        lon, lat = footprint_lonlat(tg.lat[j], tg.lon[j], tg.azimuth[j], tg.length[j], sat.swath,
                                    tg.alt[j], (f + 1) / FOOTPRINT_FRAMES)  # fmt: skip
        frames.append(
            IntervalValue(
                start=sc.at(a),
                end=sc.at(b),
                value=PositionList(cartographicDegrees=_degrees_list(lon, lat)),
            )
        )
    return Packet(
        id=f"footprint-{i}",
        name=f"footprint {sat.name} -> {tg.name[j]}",
        availability=TimeInterval(start=sc.at(t0), end=sc.at(t1)),
        polygon=Polygon(
            positions=TimeIntervalCollection(values=frames), material=_footprint_fill(color)
        ),
    )


def _taken_strip(sc, obs, i: int, color: str, horizon, ring):
    """Observation i of an area's strip: the ground ``ring`` it swept from the start of
    imaging to the end of the horizon, in the satellite's colour."""
    from czml3 import Packet
    from czml3.properties import Color, Material, Polygon, PositionList, SolidColorMaterial
    from czml3.types import TimeInterval

    k, j = int(obs.sat[i]), int(obs.target[i])
    sat, tg = sc.satellites[k], sc.targets
    lon, lat = ring
    taken = _rgba(color, TAKEN_ALPHA)
    return Packet(
        id=f"taken-{i}",
        name=f"strip {tg.name[j]} ({sat.name})",
        availability=TimeInterval(start=sc.at(float(obs.start[i])), end=horizon.end),
        polygon=Polygon(
            positions=PositionList(cartographicDegrees=_degrees_list(lon, lat)),
            material=Material(solidColor=SolidColorMaterial(color=Color(rgba=taken))),
            outline=True,
            outlineColor=Color(rgba=_rgba(color)),
        ),
    )


def _polygon_parts(geometry: dict):
    """(exterior, holes) rings of a GeoJSON Polygon / MultiPolygon, [lon, lat] lists."""
    polys = geometry["coordinates"]
    if geometry["type"] == "Polygon":
        polys = [polys]
    return [(rings[0], rings[1:]) for rings in polys]


def _area_packets(result) -> list:
    """One translucent polygon per part of every area, its coverage in the description."""
    from czml3 import Packet
    from czml3.properties import (
        Color,
        Material,
        Polygon,
        PositionList,
        PositionListOfLists,
        SolidColorMaterial,
    )

    sc = result.scenario
    if not sc.areas:
        return []
    cover = result.report.get("areas") or [None] * len(sc.areas)
    out = []
    for a_i, (area, cov) in enumerate(zip(sc.areas, cover, strict=True)):
        desc = f"area {area.name}: priority {float(sc.targets.value[area.target]):g}"
        if cov is not None:
            desc += (
                f", {cov['strips']} strips planned, {100 * cov['covered_share']:.1f} % of "
                f"{cov['samples']} samples' weight covered"
            )
        if area.geometry is None:
            continue
        for p_i, (ext, holes) in enumerate(_polygon_parts(area.geometry)):
            ring = np.asarray(ext, np.float64)
            hole_lists = [_degrees_list(*np.asarray(h, np.float64).T) for h in holes]
            out.append(
                Packet(
                    id=f"area-{a_i}-{p_i}",
                    name=area.name,
                    description=desc,
                    polygon=Polygon(
                        positions=PositionList(cartographicDegrees=_degrees_list(*ring.T)),
                        holes=PositionListOfLists(cartographicDegrees=hole_lists)
                        if hole_lists
                        else None,
                        material=Material(
                            solidColor=SolidColorMaterial(color=Color(rgba=list(AREA_RGBA)))
                        ),
                        outline=True,
                        outlineColor=Color(rgba=list(AREA_OUTLINE_RGBA)),
                    ),
                )
            )
    return out


def write_czml(result, path, *, force: bool = False, step: float = 60.0) -> Path:
    """Write the CZML document of a plan to ``path`` atomically (packets: module docstring).

    Args:
      result: :class:`jaxspline.planner.result.PlanResult`.
      path: output file (conventionally ``*.czml``).
      force: overwrite an existing file (otherwise ``FileExistsError``, file untouched).
      step: satellite position sample spacing [s] (> 0).
    Returns:
      ``Path(path)``.
    """
    refuse_overwrite(path, force)
    text = _czml_document(result, step=step).to_json(indent=1) + "\n"
    return atomic_write_text(path, text, force=force)
