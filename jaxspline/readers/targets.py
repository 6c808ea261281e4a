"""Targets from scenario files: CSV rows, ``[[targets]]`` tables, ``[random_targets]``.

The TOML schema of the target sections is documented with the rest of the scenario
file in :mod:`jaxspline.readers.scenario`; this module reads them. Angles are degrees in the
files and radians in the :class:`jaxspline.readers.mission.Targets` they become; lengths in
the files are km (strip length) and m (altitude); times are seconds from the scenario
epoch. Every error is a ``ValueError`` naming the source, the field and the value.

CSV targets (``targets_csv``, ``[targets_file]``, :func:`load_targets_csv`): UTF-8
text (a byte-order mark and CRLF line ends are accepted), a header row, then one target
per row, columns in any order; blank rows are skipped and an empty cell takes the
default. Unknown or repeated columns are errors. Target names are unique over all the
targets of a scenario (CSV rows, ``[[targets]]`` tables, random targets). The columns:

================  =====  ==================================================================
column            unit   meaning
================  =====  ==================================================================
``name``          -      target name (column and cell required)
``lat_deg``       deg    geodetic latitude in [-90, 90] (required)
``lon_deg``       deg    longitude in [-180, 180] (required)
``priority``      -      value if imaged, > 0 (column required; an empty cell means 1)
``kind``          -      ``point`` (default), ``strip`` or ``stereo`` (a stereo pair or
                         triple of a disk: :mod:`jaxspline.readers.stereo_files`)
``alt_m``         m      height above the WGS84 ellipsoid in [-12000, 12000] (default 0)
``duration_s``    s      point: imaging time (default 10); must be empty for a strip
``length_km``     km     strip: length, at most 10000 (required for a strip); must be
                         empty for a point
``azimuth_deg``   deg    strip: direction at the start, clockwise from north (default 0);
                         must be empty for a point
``window_lo_s``   s      imaging starts at or after this time from the epoch (default: none)
``window_hi_s``   s      imaging ends at or before this time from the epoch (default: none);
                         needs ``window_hi_s - window_lo_s >=`` the point's imaging time
``sensor``        -      required sensor type (empty = any sensor, the default)
``desired_s``     s      desired time of the imaging midpoint ``(start + end) / 2`` from the
                         epoch (default: none); needs ``tolerance_s``
``tolerance_s``   s      the midpoint must lie within ``desired_s +- tolerance_s`` (>= 0;
                         only with ``desired_s``)
``min_duration_s`` s     shortest accepted imaging time ``end - start`` (default 0): a strip
                         is only scanned at speeds with ``length / speed >=`` it; a point's
                         ``duration_s`` defaults to ``max(10, min_duration_s)`` and must
                         reach it
``product``       -      stereo: ``pair`` or ``tri`` (default: the ``[stereo]`` table's,
                         ``pair``)
``radius_m``      m      stereo: radius of the ground disk to image (default: the table's,
                         5000)
``band_lo_deg``   deg    stereo: preferred convergence angles (default: the table's, 8 to
``band_hi_deg``   deg    18); both or neither, within the table's ``convergence_deg``
``tri_bonus``     -      stereo: a triple's quality over its best pair's (default: the
                         table's, 0.1)
================  =====  ==================================================================

The stereo columns must be empty on other rows, and a stereo row leaves ``duration_s``,
``length_km``, ``azimuth_deg``, ``min_duration_s``, ``desired_s`` and ``tolerance_s``
empty (its looks last what covers its disk, timed by their products).

A bad cell raises e.g. ``cities.csv row 17, column 'lat_deg': must be within [-90, 90],
got '95.2'`` (row = line number in the file, the header is row 1); a missing file
raises ``FileNotFoundError``.

``[[targets]]`` (alias ``[[routes]]``) tables take the same keys, except that the
window is one key ``window_s = [lo, hi]`` and a stereo target's band one key
``band_deg = [lo, hi]``. ``[random_targets]`` draws, with numpy's
``default_rng(seed)``, positions uniform in latitude and longitude over the box (not
uniform in area), then kinds, point durations, strip lengths, azimuths and integer
priorities (``count`` at most :data:`MAX_RANDOM_TARGETS`); with ``land_only`` the
positions are rejection-sampled against ``global_land_mask`` in batches of
``max(4 count, 1024)`` draws, at most 200 batches.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import NamedTuple

import numpy as np

from jaxspline.readers.fields import (
    check_float,
    check_text,
    field_bool,
    field_int,
    field_number,
    field_pair,
    field_str,
    field_table,
    field_tables,
    read_text,
    read_tick,
)
from jaxspline.readers.mission import POINT, STEREO, STRIP, Targets, make_targets
from jaxspline.readers.ranges import MAX_NAME_CHARS, RANGES, bounds
from jaxspline.readers.stereo_files import (
    CSV_STEREO_COLUMNS,
    TARGET_STEREO_KEYS,
    parse_stereo_table,
    stereo_request,
    stereo_template,
    target_stereo,
)
from jaxspline.readers.stereo_request import Stereo

__all__ = [
    "CSV_OPTIONAL",
    "CSV_REQUIRED",
    "TARGET_SECTIONS",
    "TargetRows",
    "load_targets_csv",
    "read_targets",
    "scenario_targets",
]

DEFAULT_POINT_DURATION_S = 10.0
DEFAULT_STRIP_FRACTION = 0.2
DEFAULT_RANDOM_DURATION_S = (10.0, 30.0)
DEFAULT_RANDOM_LENGTH_KM = (20.0, 60.0)
DEFAULT_RANDOM_PRIORITY = (1, 10)
LAT_RANGE_DEG = RANGES["targets[].lat_deg"]
LON_RANGE_DEG = RANGES["targets[].lon_deg"]
ALT_RANGE_M = RANGES["targets[].alt_m"]  # the deepest trench to above the highest peak
MAX_STRIP_KM = RANGES["targets[].length_km"][1]  # longest strip [km] (a quarter great circle)
MAX_RANDOM_TARGETS = RANGES["random_targets.count"][1]
LAND_SAMPLE_ROUNDS = 200  # rejection-sampling batches before giving up on a region
LAND_BATCH_MIN = 1024
LAND_PASS_POINTS = 1 << 21  # draws tested against the land mask in one read

#: Top-level keys and sections of a scenario file that this module reads.
TARGET_SECTIONS = frozenset("targets routes targets_csv targets_file random_targets".split())
CSV_REQUIRED = ("name", "lat_deg", "lon_deg", "priority")
CSV_OPTIONAL = (
    *"kind alt_m duration_s length_km azimuth_deg window_lo_s window_hi_s sensor desired_s "
    "tolerance_s min_duration_s".split(),
    *CSV_STEREO_COLUMNS,
)
_KEYS = {
    "target": frozenset(
        "kind name lat_deg lon_deg alt_m duration_s length_km azimuth_deg priority "
        "window_s sensor desired_s tolerance_s min_duration_s".split()
    )
    | frozenset(TARGET_STEREO_KEYS),
    "targets_file": frozenset(["path"]),
    "random_targets": frozenset(
        "seed count lat_deg lon_deg land_only strip_fraction duration_s "
        "length_km azimuth_deg priority".split()
    ),
}
_KINDS = {"point": POINT, "strip": STRIP, "stereo": STEREO}
_TEXT_COLUMNS = ("name", "kind", "sensor", "product")
#: TOML keys of two values split into the CSV format's two columns.
_SPLIT_KEYS = {
    "window_s": ("window_lo_s", "window_hi_s"),
    "band_deg": ("band_lo_deg", "band_hi_deg"),
}


class TargetRows(NamedTuple):
    """The targets of a scenario file and the requests of its stereo targets.

    Attributes:
      targets: :class:`Targets`, or None (no targets and none required).
      stereo: tuple of :class:`~jaxspline.readers.stereo_request.Stereo`, one per
        target of kind stereo, in row order (``target`` its row of ``targets``).
    """

    targets: Targets | None
    stereo: tuple


def scenario_targets(
    ctx, data: dict, base_dir=None, required: bool = True, horizon: float | None = None
) -> Targets | None:
    """All targets of a parsed scenario table ``data``: :func:`read_targets`'s targets
    (stereo targets checked against the file's ``[stereo]`` table)."""
    stereo = parse_stereo_table(ctx, data)
    return read_targets(ctx, data, base_dir, required, horizon, stereo).targets


def read_targets(
    ctx,
    data: dict,
    base_dir=None,
    required: bool = True,
    horizon: float | None = None,
    stereo: Stereo | None = None,
) -> TargetRows:
    """All targets of a parsed scenario table ``data``, in the order they are read, and
    the requests of its stereo targets.

    First the ``[[targets]]`` (or ``[[routes]]``) tables, then the CSV files of
    ``targets_csv`` and ``[targets_file]``, then ``[random_targets]``.

    Args:
      ctx: :class:`jaxspline.readers.fields.FieldContext` of the file.
      data: dict, the parsed scenario TOML.
      base_dir: folder that relative CSV paths start from (None: the working directory).
      required: raise when the file gives no targets (else return None).
      horizon: the scenario's duration [s]: times from the epoch (windows, desired
        times) must lie in ``[0, horizon]`` (None: the longest horizon).
      stereo: the ``[stereo]`` table's template request
        (:func:`~jaxspline.readers.stereo_files.parse_stereo_table`; None: the defaults).
    Returns:
      TargetRows: Targets (angles in radians, lengths in metres, times in seconds from
      the epoch), or None (no targets and not ``required``), and the stereo requests.
    Raises:
      ValueError: naming the field, also when ``required`` and the file gives no targets.
    """
    stereo = stereo_template() if stereo is None else stereo
    # (Targets, origin of each target: "targets[0]", "t.csv row 5", ..., stereo fields)
    parts = []
    explicit = _toml_targets(ctx, field_tables(ctx, data, "targets", "routes"), horizon, stereo)
    if explicit is not None:
        parts.append(explicit)
    parts += [_read_csv(p, horizon, stereo) for p in _csv_paths(ctx, data, base_dir)]
    if "random_targets" in data:
        tg = _random_targets(ctx, data["random_targets"])
        parts.append((tg, ["random_targets"] * len(tg), [None] * len(tg)))
    if not parts and not required:
        return TargetRows(None, ())
    if not parts:
        raise ctx.error(
            "targets", "no targets: give [[targets]], targets_csv and/or [random_targets]"
        )
    targets, origins, fields = parts[0]
    for more, where, more_fields in parts[1:]:
        targets, origins, fields = targets.concat(more), origins + where, fields + more_fields
    _unique_names(targets.name, origins, lambda k, msg: _name_error(ctx, origins[k], msg))
    requests = tuple(
        stereo_request(stereo, str(targets.name[k]), k, f)
        for k, f in enumerate(fields)
        if f is not None
    )
    return TargetRows(targets, requests)


def _name_error(ctx, origin: str, msg: str) -> ValueError:
    """The error of a bad name at ``origin`` (a TOML table label or ``file row N``)."""
    if " row " in origin:  # a CSV row: named like the CSV reader's errors
        return ValueError(f"{origin}, column 'name': {msg}")
    return ctx.error(f"{origin}.name" if origin.startswith(("targets", "routes")) else origin, msg)


def _unique_names(names, origins, err) -> None:
    """Raise ``err(k, msg)`` at the first target ``k`` whose name an earlier one has."""
    first = {}
    for k, n in enumerate(names.tolist()):
        if n in first:
            raise err(k, f"duplicate target name {n!r} (also {origins[first[n]]})")
        first[n] = k


def _target_row(get, err, default_name, text=False, horizon=None, stereo=None) -> tuple:
    """One target from ``get(column) -> raw or None``; ``err(column)(msg)`` builds errors.

    Columns as in the CSV format, numbers within their ranges
    (:data:`jaxspline.readers.ranges.RANGES`, times within ``[0, horizon]`` s; None: the
    longest horizon); ``stereo`` the template request of a stereo target's defaults.
    Returns (name, kind, lat, lon, alt, duration, length, azimuth, priority, t_lo, t_hi,
    mid_lo, mid_hi, min_duration, sensor, stereo fields or None) in degrees, metres,
    seconds.
    """

    def num(col, key=None, **kw):
        rng = bounds(f"targets[].{key or col}", horizon)
        return check_float(get(col), err(col), text=text, **rng, **kw)

    name = _string(get, err, "name", default_name)
    if not name:  # given but blank: as a satellite's or an area's name, refused
        raise err("name")(f"must be a non-empty string, got {get('name')!r}")
    kind = _string(get, err, "kind", "point")
    if kind not in _KINDS:
        raise err("kind")(f"must be 'point' or 'strip', or 'stereo' for a stereo product, "
                          f"got {kind!r}")  # fmt: skip
    lat, lon = num("lat_deg"), num("lon_deg")
    alt, prio = num("alt_m", default=0.0), num("priority", default=1.0)
    template = stereo_template() if stereo is None else stereo
    pair = target_stereo(get, err, num, kind, lambda c, d: _string(get, err, c, d), template)
    min_dur = num("min_duration_s", default=0.0)
    dur, length, az = _extent(get, err, num, kind, min_dur)
    t_lo, t_hi, mid_lo, mid_hi = _times(get, err, num, dur)
    sensor = _string(get, err, "sensor", "")
    return (name, _KINDS[kind], lat, lon, alt, dur, length, az, prio, t_lo, t_hi, mid_lo,
            mid_hi, min_dur, sensor, pair)  # fmt: skip


def _string(get, err, col, default):
    """The text of column ``col`` (stripped; ``default`` when empty), no control characters
    (before stripping: Python strips some of them as white space)."""
    raw = get(col)
    if raw is None:
        return default
    if not isinstance(raw, str):
        raise err(col)(f"must be a string, got {raw!r}")
    check_text(raw, err(col))
    return check_text(raw.strip(), err(col), MAX_NAME_CHARS)


def _extent(get, err, num, kind, min_dur) -> tuple[float, float, float]:
    """``(duration [s], length [m], azimuth [deg])`` of a point (duration) or a strip
    (length and azimuth; the duration is length / scan speed, 0 here); zeros for a
    stereo target (its looks' durations are the planner's)."""
    if kind == "stereo":
        return 0.0, 0.0, 0.0
    if kind == "strip":
        if get("duration_s") is not None:
            raise err("duration_s")("a strip has no duration_s (it is length / scan speed)")
        return 0.0, 1e3 * num("length_km"), num("azimuth_deg", default=0.0)
    for col in ("length_km", "azimuth_deg"):
        if get(col) is not None:
            raise err(col)("a point has no length_km / azimuth_deg (use kind 'strip')")
    dur = num("duration_s", default=max(DEFAULT_POINT_DURATION_S, min_dur))
    if dur < min_dur:
        raise err("duration_s")(f"must be >= min_duration_s = {min_dur:g}, got {dur:g}")
    return dur, 0.0, 0.0


def _times(get, err, num, dur) -> tuple[float, float, float, float]:
    """``(t_lo, t_hi, mid_lo, mid_hi)`` [s from the epoch] of the imaging window and the
    desired midpoint (infinite when not given), checked against each other and the
    imaging time ``dur`` [s]."""
    t_lo = num("window_lo_s", "window_s", default=-np.inf)
    t_hi = num("window_hi_s", "window_s", default=np.inf)
    if t_hi < t_lo:
        raise err("window_hi_s")(f"window needs lo <= hi, got [{t_lo:g}, {t_hi:g}]")
    if t_hi < t_lo + dur:
        raise err("window_hi_s")(
            f"window [{t_lo:g}, {t_hi:g}] s is shorter than the imaging time {dur:g} s"
        )
    if get("tolerance_s") is not None and get("desired_s") is None:
        raise err("tolerance_s")("only with desired_s (the desired imaging time)")
    if get("desired_s") is None:
        return t_lo, t_hi, -np.inf, np.inf
    desired = num("desired_s")
    if get("tolerance_s") is None:
        raise err("tolerance_s")("missing (required with desired_s) [s]")
    tol = num("tolerance_s")
    if desired + tol < t_lo + dur / 2 or desired - tol > t_hi - dur / 2:
        raise err("desired_s")(
            f"desired time {desired:g} +- {tol:g} s misses the window [{t_lo:g}, {t_hi:g}] s"
        )
    return t_lo, t_hi, desired - tol, desired + tol


def _targets_from_rows(rows) -> Targets:
    """The Targets of rows of :func:`_target_row` (their stereo fields aside)."""
    cols = list(zip(*rows, strict=True))
    num = [np.asarray(c, np.float64) for c in cols[2:14]]
    lat, lon, alt, dur, length, az, prio, t_lo, t_hi, mid_lo, mid_hi, min_dur = num
    return make_targets(
        np.asarray(cols[1], np.int64),
        np.radians(lat),
        np.radians(lon),
        alt=alt,
        duration=dur,
        length=length,
        azimuth=np.radians(az),
        value=prio,
        t_lo=t_lo,
        t_hi=t_hi,
        sensor=np.asarray(cols[14], dtype=object),
        name=np.asarray(cols[0], dtype=str),
        mid_lo=mid_lo,
        mid_hi=mid_hi,
        min_duration=min_dur,
    )


def _toml_targets(ctx, items, horizon=None, stereo=None) -> tuple | None:
    """``(Targets, origins, stereo fields)`` of the ``[[targets]]`` tables (None: none)."""
    rows, origins = [], []
    for i, (f, rt) in enumerate(items):
        rt = dict(field_table(ctx, f, rt, _KEYS["target"]))
        for key, (lo, hi) in _SPLIT_KEYS.items():
            if key in rt:
                two = rt.pop(key)
                if not isinstance(two, list) or len(two) != 2:
                    raise ctx.error(f"{f}.{key}", f"must be a list [lo, hi], got {two!r}")
                rt[lo], rt[hi] = two

        def err(col, f=f):
            key = next((k for k, cols in _SPLIT_KEYS.items() if col in cols), col)
            return lambda m: ctx.error(f"{f}.{key}", m)

        rows.append(_target_row(rt.get, err, f"target_{i + 1}", horizon=horizon, stereo=stereo))
        origins.append(f)
    return (_targets_from_rows(rows), origins, [r[-1] for r in rows]) if rows else None


def load_targets_csv(path) -> Targets:
    """Targets from a CSV file (columns and units: module docstring; angles in degrees).

    Args:
      path: str or Path of the CSV file.
    Returns:
      Targets (converted to radians).
    Raises:
      FileNotFoundError: the file is missing.
      ValueError: naming the file, the row (line number) and the column for bad content.
    """
    return _read_csv(path)[0]


def _read_csv(path, horizon=None, stereo=None) -> tuple[Targets, list[str], list]:
    """:func:`load_targets_csv`, the origin (``file row N``) of each target (times
    within ``[0, horizon]`` s) and its stereo fields (None: not a stereo target;
    ``stereo``: the template request, None: the defaults)."""
    path = Path(path)
    label = path.name
    try:
        text = read_text(path, lambda line: f"{label} row {line}")
    except FileNotFoundError:
        raise FileNotFoundError(f"targets CSV not found: {path}") from None
    rows, origins = [], []
    lines = text.count("\n") + 1  # the rows to read, for the clock (read_tick)
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = [h.strip() for h in next(reader, [])]
        allowed = CSV_REQUIRED + CSV_OPTIONAL
        for h in header:
            if h not in allowed:
                raise ValueError(
                    f"{label} row 1, column {h!r}: unknown column (allowed: {allowed})"
                )
            if header.count(h) > 1:
                raise ValueError(f"{label} row 1, column {h!r}: appears twice")
        for h in CSV_REQUIRED:
            if h not in header:
                raise ValueError(f"{label} row 1, column {h!r}: missing (required: {CSV_REQUIRED})")
        for cells in reader:
            line = reader.line_num
            read_tick(label, line, lines)
            if not any(c.strip() for c in cells):
                continue
            if len(cells) != len(header):
                raise ValueError(
                    f"{label} row {line}: {len(cells)} cells, the header has {len(header)}"
                )
            rec = {h: (c.strip() or None) for h, c in zip(header, cells, strict=True)}
            if rec["name"] is None:
                raise ValueError(f"{label} row {line}, column 'name': must not be empty")

            def err(col, line=line):
                return lambda m: ValueError(f"{label} row {line}, column {col!r}: {m}")

            for col, cell in zip(header, cells, strict=True):  # before stripping
                if col in _TEXT_COLUMNS:
                    check_text(cell, err(col))

            rows.append(
                _target_row(rec.get, err, f"row_{line}", text=True, horizon=horizon, stereo=stereo)
            )
            origins.append(f"{label} row {line}")
    except csv.Error as exc:  # an over-long cell (an unbalanced quote), a NUL byte, ...
        raise ValueError(f"{label} row {reader.line_num}: not readable as CSV: {exc}") from None
    if not rows:
        raise ValueError(f"{label}: no target rows (a header row and at least one target)")
    targets = _targets_from_rows(rows)
    _unique_names(
        targets.name, origins, lambda k, msg: ValueError(f"{origins[k]}, column 'name': {msg}")
    )
    return targets, origins, [r[-1] for r in rows]


def _land_positions(ctx, rng, count, lat, lon):
    """``count`` uniform (lat, lon) [deg] in the box, rejecting sea (:func:`is_land`).

    Rounds of ``batch`` draws (latitudes, then longitudes) until ``count`` land points are
    found, at most :data:`LAND_SAMPLE_ROUNDS`. The first pass tests one round (usually
    enough); later passes test many rounds with one read of the mask each (a read costs
    about a second: 200 single-round reads of a sea box took minutes). The points and the
    state ``rng`` is left in are those of testing the rounds one at a time.
    """
    from jaxspline.base.land import is_land

    batch = max(4 * count, LAND_BATCH_MIN)
    per_pass = max(1, LAND_PASS_POINTS // batch)
    got_lat, got_lon, have, done = [], [], 0, 0
    while done < LAND_SAMPLE_ROUNDS:
        rounds = 1 if done == 0 else min(per_pass, LAND_SAMPLE_ROUNDS - done)
        state = rng.bit_generator.state
        draws = [(rng.uniform(*lat, batch), rng.uniform(*lon, batch)) for _ in range(rounds)]
        keep = is_land(np.concatenate([d[0] for d in draws]), np.concatenate([d[1] for d in draws]))
        kept = keep.reshape(rounds, batch).sum(1)
        need = np.cumsum(kept) + have >= count
        used = int(np.argmax(need)) + 1 if need.any() else rounds
        for (la, lo), k in zip(draws[:used], keep.reshape(rounds, batch)[:used], strict=True):
            got_lat.append(la[k])
            got_lon.append(lo[k])
        have += int(kept[:used].sum())
        if have >= count:
            rng.bit_generator.state = state  # as if the rounds after ``used`` were not drawn
            for _ in range(used):
                rng.uniform(*lat, batch), rng.uniform(*lon, batch)
            return np.concatenate(got_lat)[:count], np.concatenate(got_lon)[:count]
        done += rounds
    raise ctx.error(
        "random_targets.land_only",
        f"found only {have} land points in {LAND_SAMPLE_ROUNDS * batch} draws in "
        f"lat {list(lat)}, lon {list(lon)} deg; widen the region or set land_only = false",
    )


def _random_targets(ctx, rt) -> Targets:
    f = "random_targets"
    rt = field_table(ctx, f, rt, _KEYS[f])

    def integer(key, default):
        return field_int(ctx, f"{f}.{key}", rt.get(key, default), *RANGES[f"{f}.{key}"])

    def pair(key, default):
        return field_pair(ctx, f"{f}.{key}", rt.get(key, list(default)), **bounds(f"{f}.{key}"))

    seed = integer("seed", 0)
    if "count" not in rt:
        raise ctx.error(f"{f}.count", "missing (how many targets to generate)")
    count = integer("count", None)
    lat, lon = pair("lat_deg", LAT_RANGE_DEG), pair("lon_deg", LON_RANGE_DEG)
    land = field_bool(ctx, f"{f}.land_only", rt.get("land_only", False))
    frac = rt.get("strip_fraction", DEFAULT_STRIP_FRACTION)
    frac = field_number(ctx, f"{f}.strip_fraction", frac, **bounds(f"{f}.strip_fraction"))
    dur = pair("duration_s", DEFAULT_RANDOM_DURATION_S)
    length = pair("length_km", DEFAULT_RANDOM_LENGTH_KM)
    az = pair("azimuth_deg", (0.0, 360.0))
    prio = rt.get("priority", list(DEFAULT_RANDOM_PRIORITY))
    if not isinstance(prio, list) or len(prio) != 2:
        raise ctx.error(f"{f}.priority", f"must be a list [lo, hi] of integers, got {prio!r}")
    p_lo, p_hi = (field_int(ctx, f"{f}.priority", p, *RANGES[f"{f}.priority"]) for p in prio)
    if p_lo > p_hi:
        raise ctx.error(f"{f}.priority", f"needs lo <= hi, got {prio!r}")
    rng = np.random.default_rng(seed)
    if land:
        la, lo = _land_positions(ctx, rng, count, lat, lon)
    else:
        la, lo = rng.uniform(*lat, count), rng.uniform(*lon, count)
    kind = np.where(rng.random(count) < frac, STRIP, POINT)
    return make_targets(
        kind,
        np.radians(la),
        np.radians(lo),
        duration=rng.uniform(*dur, count),
        length=1e3 * rng.uniform(*length, count),
        azimuth=np.radians(rng.uniform(*az, count)),
        value=rng.integers(p_lo, p_hi + 1, count).astype(np.float64),
        name=np.array([f"random_{i + 1:04d}" for i in range(count)]),
    )


def _csv_paths(ctx, data, base_dir) -> list[Path]:
    """The target CSV files named by ``targets_csv`` and ``[targets_file]``, resolved."""
    out = []
    sources = [("targets_csv", data.get("targets_csv"))]
    if "targets_file" in data:
        tf = field_table(ctx, "targets_file", data["targets_file"], _KEYS["targets_file"])
        sources.append(("targets_file.path", tf.get("path")))
        if "path" not in tf:
            raise ctx.error("targets_file.path", "missing (the CSV file)")
    for field, value in sources:
        if value is None:
            continue
        for p in value if isinstance(value, list) else [value]:
            p = Path(field_str(ctx, field, p, allow_empty=False))
            if not p.is_absolute() and base_dir is not None:
                p = Path(base_dir) / p
            if not p.is_file():
                raise ctx.error(field, f"targets CSV not found: {p}")
            out.append(p)
    return out
