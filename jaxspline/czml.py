"""CZML export of a plan: satellites, targets and observations for a Cesium viewer.

:func:`write_czml` turns a :class:`jaxspline.engine.result.PlanResult` into a CZML document
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
  the target, available only during the imaging interval ``[start, end]``.

Satellite positions come from :func:`jaxspline.geometry.orbit.tabulate_orbits` (SGP4 for TLEs,
analytic for circular orbits) and are rotated to Earth-fixed coordinates by the Earth
rotation angle (:mod:`jaxspline.geometry.frames`). :func:`satellite_tracks` and
:data:`SATELLITE_COLORS` are shared with the plan figures (:mod:`jaxspline.plot_plan`).
"""

from __future__ import annotations

import math
from pathlib import Path

import jax
import numpy as np

from jaxspline.engine._io import atomic_write_text, refuse_overwrite
from jaxspline.geometry.frames import earth_rotation_angle, gmst, teme_to_ecef
from jaxspline.geometry.orbit import MU_EARTH, orbit_position, tabulate_orbits

__all__ = ["SATELLITE_COLORS", "czml_document", "satellite_tracks", "write_czml"]

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
      scenario: :class:`jaxspline.engine.mission.Scenario`.
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


def czml_document(result, *, step: float = 60.0):
    """The CZML document of a plan (a ``czml3.Document``; see the module docstring).

    Args:
      result: :class:`jaxspline.engine.result.PlanResult`.
      step: satellite position sample spacing [s] (> 0).
    Returns:
      ``czml3.Document`` whose first packet (id ``"document"``) carries the clock;
      serialise with ``doc.to_json()``.
    """
    from czml3 import CZML_VERSION, Document, Packet
    from czml3.enums import (
        ArcTypes,
        ClockRanges,
        ClockSteps,
        HorizontalOrigins,
        InterpolationAlgorithms,
        LabelStyles,
    )
    from czml3.properties import (
        Clock,
        Color,
        Label,
        Path,
        Point,
        Polyline,
        PolylineMaterial,
        Position,
        PositionList,
        SolidColorMaterial,
    )
    from czml3.types import Cartesian2Value, TimeInterval

    step = _check_step(step)
    sc = result.scenario
    obs = result.observations
    epoch, end = sc.at(0.0), sc.at(sc.duration)
    horizon = TimeInterval(start=epoch, end=end)

    def material(rgba):
        return PolylineMaterial(solidColor=SolidColorMaterial(color=Color(rgba=rgba)))

    packets = [
        Packet(
            id="document",
            name=sc.name,
            version=CZML_VERSION,
            clock=Clock(
                interval=horizon,
                currentTime=epoch,
                multiplier=CLOCK_MULTIPLIER,
                range=ClockRanges.LOOP_STOP,
                step=ClockSteps.SYSTEM_CLOCK_MULTIPLIER,
            ),
        )
    ]

    t, r, ok = satellite_tracks(sc, step)
    for k, sat in enumerate(sc.satellites):
        rgba = _rgba(SATELLITE_COLORS[k % len(SATELLITE_COLORS)])
        good = ok[k]
        samples = np.column_stack([t[good], np.round(r[k, good], POSITION_DECIMALS)])
        half = 0.5 * _period(r[k, good])
        n_obs = int(np.sum(obs.sat == k))
        packets.append(
            Packet(
                id=f"sat-{k}",
                name=sat.name,
                description=f"satellite {sat.name}: model {sat.model}, {n_obs} observations",
                availability=horizon,
                position=Position(
                    epoch=epoch,
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
                    material=material(rgba),
                ),
            )
        )

    tg = sc.targets
    imaged = np.zeros(len(tg), bool)
    imaged[np.asarray(obs.target, np.int64)] = True
    for i in range(len(tg)):
        kind = "strip" if int(tg.kind[i]) == 1 else "point"
        packets.append(
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
                point=Point(
                    color=Color(rgba=list(IMAGED_RGBA if imaged[i] else NOT_IMAGED_RGBA)),
                    pixelSize=IMAGED_PIXELS if imaged[i] else TARGET_PIXELS,
                    outlineColor=Color(rgba=[0, 0, 0, 255]),
                    outlineWidth=1.0,
                ),
            )
        )

    for i in range(len(obs)):
        k, j = int(obs.sat[i]), int(obs.target[i])
        rgba = _rgba(SATELLITE_COLORS[k % len(SATELLITE_COLORS)])
        packets.append(
            Packet(
                id=f"obs-{i}",
                name=f"{sc.satellites[k].name} -> {tg.name[j]}",
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
                    material=material(rgba),
                ),
            )
        )
    return Document(packets=packets)


def write_czml(result, path, *, force: bool = False, step: float = 60.0) -> Path:
    """Write the CZML document of a plan to ``path`` atomically (see :func:`czml_document`).

    Args:
      result: :class:`jaxspline.engine.result.PlanResult`.
      path: output file (conventionally ``*.czml``).
      force: overwrite an existing file (otherwise ``FileExistsError``, file untouched).
      step: satellite position sample spacing [s] (> 0).
    Returns:
      ``Path(path)``.
    """
    refuse_overwrite(path, force)
    text = czml_document(result, step=step).to_json(indent=1) + "\n"
    return atomic_write_text(path, text, force=force)
