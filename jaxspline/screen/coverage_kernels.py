"""Strip-coverage kernels: edge ground points and point-in-strip quad ranges (pure, one item).

The regional_coverage geometry (RULES.md, roll-only pointing): at a sample, with the
Earth-fixed satellite position ``p`` and velocity ``v`` (relative to the rotating Earth),
``nadir = -p/|p|``, ``along = v - (v.nadir) nadir`` normalized, ``across = along x nadir``.
A look angle ``a`` points along ``nadir + tan(a) across``; its ground point is the first
intersection of that ray with the WGS84 ellipsoid. A strip of roll ``r`` and field of
view ``f`` has the inner edge angle ``sign(r) (|r| - f/2)`` and the outer edge angle
``sign(r) (|r| + f/2)``; consecutive samples a, b form the quadrilateral
``(inner_a, outer_a, outer_b, inner_b)`` in (longitude, latitude) degrees, and a grid
sample inside or on the border of any quad is covered.

Kernels here take ONE item (one sample, or one (strip piece, point) pair); the engine
(:mod:`jaxspline.screen.coverage`) batches them once with ``jit(vmap(...))``. They follow
the input dtype and are branchless: a ray that misses the Earth is a value
(``hit = False``), never an exception.

Point-in-quad test. With ``orient(a, b, p) = (b_x - a_x)(p_y - a_y) - (b_y - a_y)(p_x - a_x)``
(twice the signed area of a, b, p), a point is inside or on a convex quad iff its four
edge orientations are all >= 0 or all <= 0. The cross edge ``inner_k -> outer_k`` of a
sample is shared by quads k-1 and k; it is evaluated once per sample (``s_k``) and enters
quad k as ``s_k`` and quad k-1 as ``-s_k`` (float negation is exact), so two adjacent quads
never leave a rounding gap between them and a point exactly on the shared edge is in
both. Longitudes are unwrapped by whole turns towards a reference longitude
(``lon + 360 round((ref - lon) / 360)``, exact when no turn is added), so a strip across
the antimeridian is one connected strip.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxspline.base.elements import R_EARTH, WGS84_E2, WGS84_F
from jaxspline.geometry.pointing import roll_look_direction

__all__ = [
    "WGS84_B",
    "look_point",
    "edge_points",
    "unwrap_lon",
    "orient",
    "quad_range",
]

WGS84_B = R_EARTH * (1.0 - WGS84_F)  # m, polar semi-axis
FULL_TURN_DEG = 360.0


def look_point(pos, vel, look_deg, pitch_deg=0.0):
    """Ground point of the look angle ``look_deg`` at one sample (one ray).

    ``d = down + tan(a) across`` (the held pointing offset, ``down`` nadir pitched by
    ``pitch_deg`` forward: :func:`jaxspline.geometry.pointing.roll_look_direction`; with
    pitch 0 the roll-only law ``nadir + tan(a) across``); scaled by the semi-axes
    (``P = p / (a, a, b)``, ``D = d / (a, a, b)``) the ray meets the unit sphere where
    ``|P + t D|^2 = 1``; the first root is ``t = C / (-B + sqrt(B^2 - A C))`` with
    ``A = D.D``, ``B = P.D``, ``C = P.P - 1`` (the cancellation-free form). Geodetic
    latitude of a surface point: ``atan2(z, (1 - e^2) hypot(x, y))``.

    Args:
      pos: float [3], Earth-fixed position [m].
      vel: float [3], Earth-fixed velocity relative to the rotating Earth [m/s].
      look_deg: float [], look angle across track [deg] (positive towards
        ``along x nadir``).
      pitch_deg: float [], pitch [deg] (positive forward).
    Returns:
      (lon_deg [], lat_deg [], hit bool []): geodetic longitude/latitude [deg] of the hit;
      where ``hit`` is False (the ray misses the ellipsoid) lon/lat are finite junk.
    """
    d = roll_look_direction(pos, vel, look_deg, pitch_deg)
    scale = jnp.stack([1.0 / R_EARTH, 1.0 / R_EARTH, 1.0 / WGS84_B]).astype(pos.dtype)
    p_s, d_s = pos * scale, d * scale
    a = jnp.sum(d_s * d_s)
    b = jnp.sum(p_s * d_s)
    c = jnp.sum(p_s * p_s) - 1.0
    disc = b * b - a * c
    hit = (disc >= 0.0) & (b < 0.0) & (c > 0.0)
    denom = jnp.where(hit, -b + jnp.sqrt(jnp.where(hit, disc, 0.0)), 1.0)
    t = jnp.where(hit, c / denom, 0.0)
    g = pos + t * d
    lon = jnp.degrees(jnp.arctan2(g[1], g[0]))
    lat = jnp.degrees(jnp.arctan2(g[2], (1.0 - WGS84_E2) * jnp.hypot(g[0], g[1])))
    return lon, lat, hit


def edge_points(pos, vel, roll_deg, fov_deg, pitch_deg=0.0):
    """Inner and outer strip-edge ground points at one sample.

    Inner edge angle ``sign(r) (|r| - f/2)``, outer ``sign(r) (|r| + f/2)``
    (``sign(0) = +1``), both at the strip's pitch.

    Args:
      pos: float [3], Earth-fixed position [m].
      vel: float [3], Earth-fixed velocity relative to the rotating Earth [m/s].
      roll_deg: float [], roll r [deg].
      fov_deg: float [], cross-track field of view f [deg].
      pitch_deg: float [], pitch [deg] (0: the roll-only law).
    Returns:
      (inner [2], outer [2], hit bool []): (lon, lat) [deg] of the two edge ground
      points; ``hit`` is True iff both rays meet the ellipsoid.
    """
    sign = jnp.where(roll_deg < 0.0, -1.0, 1.0)
    half = 0.5 * fov_deg
    lon_i, lat_i, hit_i = look_point(pos, vel, sign * (jnp.abs(roll_deg) - half), pitch_deg)
    lon_o, lat_o, hit_o = look_point(pos, vel, sign * (jnp.abs(roll_deg) + half), pitch_deg)
    return jnp.stack([lon_i, lat_i]), jnp.stack([lon_o, lat_o]), hit_i & hit_o


def unwrap_lon(lon, ref_lon):
    """Longitude moved by whole turns to within half a turn of ``ref_lon`` (generic).

    ``lon + 360 round((ref - lon) / 360)``: exactly ``lon`` when no turn is added.
    numpy arrays in, a numpy array out (the same bits: each step is one IEEE operation),
    without the small program JAX compiles for every new shape of an eager call.

    Args:
      lon: float [...], longitude [deg].
      ref_lon: float [...], reference longitude [deg] (broadcast).
    Returns:
      float [...], unwrapped longitude [deg].
    """
    host = isinstance(lon, np.ndarray) and isinstance(ref_lon, np.ndarray)
    xp = np if host else jnp
    return lon + FULL_TURN_DEG * xp.round((ref_lon - lon) / FULL_TURN_DEG)


def orient(ax, ay, bx, by, px, py):
    """Twice the signed area of (a, b, p): > 0 when p is left of a -> b (generic).

    Args:
      ax, ay, bx, by, px, py: float [...] (broadcast), planar coordinates.
    Returns:
      float [...], ``(b_x - a_x)(p_y - a_y) - (b_y - a_y)(p_x - a_x)``.
    """
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax)


def quad_range(inner, outer, n_quads, ref_lon, point):
    """First and last quad of a strip piece that contain one point (border inclusive).

    Quad j of the piece is ``(inner_j, outer_j, outer_{j+1}, inner_{j+1})``, for
    ``j < n_quads``; its edge orientations are ``s_j``, ``orient(outer_j, outer_{j+1}, p)``,
    ``-s_{j+1}`` and ``orient(inner_{j+1}, inner_j, p)`` with
    ``s_k = orient(inner_k, outer_k, p)``; the point is in quad j iff all four are >= 0
    or all <= 0 (convex quads). Longitudes of vertices and point are unwrapped towards
    ``ref_lon``. A NaN point or vertex is in no quad.

    Args:
      inner: float [G+1, 2], inner-edge (lon, lat) of the piece's samples [deg].
      outer: float [G+1, 2], outer-edge (lon, lat) [deg].
      n_quads: int [], number of valid quads (<= G); the rest are ignored.
      ref_lon: float [], reference longitude for unwrapping [deg].
      point: float [2], (lon, lat) of the grid sample [deg].
    Returns:
      (first int32 [], last int32 [], count int32 []): the smallest and largest j whose
      quad contains the point (G and -1 when none) and the number of such quads.
    """
    g = inner.shape[0] - 1
    ix, iy = unwrap_lon(inner[:, 0], ref_lon), inner[:, 1]
    ox, oy = unwrap_lon(outer[:, 0], ref_lon), outer[:, 1]
    px, py = unwrap_lon(point[0], ref_lon), point[1]
    s = orient(ix, iy, ox, oy, px, py)
    o = orient(ox[:-1], oy[:-1], ox[1:], oy[1:], px, py)
    i = orient(ix[1:], iy[1:], ix[:-1], iy[:-1], px, py)
    a, c = s[:-1], -s[1:]
    pos = (a >= 0.0) & (o >= 0.0) & (c >= 0.0) & (i >= 0.0)
    neg = (a <= 0.0) & (o <= 0.0) & (c <= 0.0) & (i <= 0.0)
    j = jnp.arange(g, dtype=jnp.int32)
    inside = (pos | neg) & (j < n_quads)
    first = jnp.min(jnp.where(inside, j, g)).astype(jnp.int32)
    last = jnp.max(jnp.where(inside, j, -1)).astype(jnp.int32)
    return first, last, jnp.sum(inside).astype(jnp.int32)
