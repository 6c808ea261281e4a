"""The options of stereo targets: candidate looks as planner options, and their products.

A stereo target (kind ``STEREO``, its :class:`~jaxspline.readers.stereo_request.Stereo`
request) collects its value through a *product*, a valid pair or triple of looks
(:mod:`jaxspline.screen.stereo_products`). This stage builds, in three steps:

1. **Looks** (:func:`jaxspline.geometry.stereo_looks.stereo_looks`): per (satellite,
   stereo target) the access intervals and, in each, looks centred on a grid of
   midpoints, steered at the target, long enough for their strips to cross its disk.
2. **Products** (:func:`jaxspline.screen.stereo_products.stereo_products`): per target
   the best valid pairs and (``product = "tri"``) triples, with their quality and
   confidence (the chance that the benchmark's random overlap estimates pass).
3. **Options**: the looks that some kept product uses, as :class:`Opportunities` rows
   like every option: ``route`` the target's row, the aim law the planner's roll law
   (:func:`~jaxspline.geometry.pointing.roll_params` of the look's roll and pitch: the
   same boresight as its steering angles), boundary states by
   :func:`~jaxspline.planner.opportunities.option_states` (lines of sight Earth-fixed
   for models that compare them there), ``value`` the target's priority as for area
   strips (a look alone collects nothing: the search values products).

:func:`merge_stereo` merges them into the other options, sorted as
:func:`jaxspline.planner.area_options.merge_options` sorts, and renumbers the products'
looks as rows of the merged table.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from jaxspline.geometry.frames import earth_rotation_angle, rot_z
from jaxspline.geometry.pointing import roll_params
from jaxspline.geometry.stereo_looks import StereoAccess, StereoLooks, stereo_looks
from jaxspline.planner.opportunities import Opportunities, option_states
from jaxspline.readers.mission import Scenario
from jaxspline.screen.options import RouteOptions
from jaxspline.screen.stereo_products import StereoProducts, stereo_products

__all__ = ["StereoMerge", "StereoOptions", "merge_stereo", "stereo_options"]


class StereoOptions(NamedTuple):
    """What the stereo stage built (module docstring).

    Attributes:
      opp: :class:`Opportunities` of the looks that kept products use, sorted by
        (satellite, start, target).
      looks: :class:`~jaxspline.geometry.stereo_looks.StereoLooks`, row k the look of
        ``opp`` row k (steering, pass, slant range, pixel scale, off-nadir, strip).
      products: :class:`~jaxspline.screen.stereo_products.StereoProducts` whose
        ``looks`` are rows of ``opp`` (-1 pads a pair).
      access: :class:`~jaxspline.geometry.stereo_looks.StereoAccess`, the intervals
        ``looks.access`` indexes.
      n_candidates: looks built before those no kept product uses were dropped.
    """

    opp: Opportunities
    looks: StereoLooks
    products: StereoProducts
    access: StereoAccess
    n_candidates: int

    def __len__(self) -> int:
        return len(self.opp)

    @property
    def along(self) -> np.ndarray:
        """float [N], along-track steering of each row [rad]."""
        return self.looks.along

    @property
    def across(self) -> np.ndarray:
        """float [N], across-track steering of each row [rad]."""
        return self.looks.across

    @property
    def pass_id(self) -> np.ndarray:
        """int64 [N], each row's access interval (two rows of one satellite pair only
        with the same id)."""
        return self.looks.access

    @property
    def slant(self) -> np.ndarray:
        """float [N], slant range at the midpoint [m]."""
        return self.looks.slant

    @property
    def scale(self) -> np.ndarray:
        """float [N], pixel scale at the midpoint [m] (NaN without ``ifov``)."""
        return self.looks.scale

    @property
    def off_nadir(self) -> np.ndarray:
        """float [N], combined off-nadir angle of the steering [rad]."""
        return self.looks.off_nadir


class StereoMerge(NamedTuple):
    """The stereo looks merged into the other options (:func:`merge_stereo`).

    Attributes:
      opp: :class:`Opportunities`, all options sorted by (satellite, start, target).
      look_of_row: int64 [N], per row its row in the stereo stage's ``opp`` (-1: not a
        stereo look).
      products: :class:`StereoProducts` whose ``looks`` are rows of ``opp`` (-1 pads).
      order: int64 [N], merged row k is row ``order[k]`` of the other options followed by
        the stereo looks (to carry other per-row arrays along).
    """

    opp: Opportunities
    look_of_row: np.ndarray
    products: StereoProducts
    order: np.ndarray


def _used(products: StereoProducts, n: int) -> np.ndarray:
    """bool [n]: the looks some product uses."""
    used = np.zeros(n, bool)
    ids = products.looks[products.looks >= 0]
    used[ids] = True
    return used


def _earth_fixed(sc: Scenario, scene, o: RouteOptions) -> RouteOptions:
    """Lines of sight and nadir of satellites whose model compares them Earth-fixed, rotated
    there (as the area strips' options)."""
    earth = np.array([s.maneuver.los_frame == "earth_fixed" for s in sc.satellites])[o.sat]
    if not earth.any():
        return o
    th0 = earth_rotation_angle(float(scene.gmst0), o.t_start)
    th1 = earth_rotation_angle(float(scene.gmst0), o.t_end)
    e = earth[:, None]
    return o._replace(
        start_los=np.where(e, rot_z(th0, o.start_los), o.start_los),
        end_los=np.where(e, rot_z(th1, o.end_los), o.end_los),
        start_nadir=np.where(e, rot_z(th0, o.start_nadir), o.start_nadir),
    )


def _look_table(sc: Scenario, scene, looks: StereoLooks) -> Opportunities:
    """The :class:`Opportunities` rows of looks (in their order)."""
    params = np.asarray(roll_params(looks.roll, looks.pitch))
    per_ch = np.array([not s.maneuver.rest_to_rest for s in sc.satellites])
    o = option_states(
        sc, scene, looks.sat, looks.target, looks.t_start, looks.t_end, params, per_ch
    )
    return Opportunities(_earth_fixed(sc, scene, o), np.zeros(len(looks)), params)


def stereo_options(
    sc: Scenario,
    table,
    scene,
    mid_step: float | None = None,
    overlap_margin: float | None = None,
):
    """The stereo stage (module docstring).

    Args:
      sc: Scenario; table: its OrbitTable; scene: its Scene
        (:func:`jaxspline.geometry.windows.orbit_scene`).
      mid_step: spacing of the candidate look midpoints [s] (None: the default of
        :func:`~jaxspline.geometry.stereo_looks.stereo_looks`).
      overlap_margin: overlap kept above ``min_overlap`` (None: the default of
        :func:`~jaxspline.screen.stereo_products.stereo_products`, which keeps products
        the benchmark passes by chance, each with its ``confidence``;
        :data:`~jaxspline.screen.stereo_products.SAFE_OVERLAP_MARGIN` keeps only safe
        ones).
    Returns:
      :class:`StereoOptions`, or None when the scenario has no stereo target.
    """
    if not sc.stereo:
        return None
    kw = {} if mid_step is None else {"mid_step": mid_step}
    access, looks = stereo_looks(sc, table, scene, **kw)
    kw = {} if overlap_margin is None else {"overlap_margin": overlap_margin}
    products = stereo_products(sc, looks, **kw)
    used = np.flatnonzero(_used(products, len(looks)))
    kept = looks.take(used)
    order = np.lexsort((kept.target, kept.t_start, kept.sat))
    kept = kept.take(order)
    row_of = np.full(len(looks), -1, np.int64)
    row_of[used[order]] = np.arange(order.size)
    ids = np.where(products.looks >= 0, row_of[np.maximum(products.looks, 0)], -1)
    products = StereoProducts(ids, *products[1:])
    return StereoOptions(_look_table(sc, scene, kept), kept, products, access, len(looks))


def merge_stereo(opp: Opportunities, stereo: StereoOptions) -> StereoMerge:
    """The other options with the stereo looks, sorted by (satellite, start, target) as
    :func:`jaxspline.planner.area_options.merge_options` sorts (stable: the other options
    first among equal keys).

    Args:
      opp: the other options (point, strip and area targets), an :class:`Opportunities`.
      stereo: :class:`StereoOptions`.
    Returns:
      :class:`StereoMerge`.
    """
    s = stereo.opp
    fields = [
        np.concatenate([np.asarray(x), np.asarray(y)])
        for x, y in zip(opp.options, s.options, strict=True)
    ]
    o = RouteOptions(*fields)
    speed = np.concatenate([opp.speed, s.speed])
    params = np.concatenate([opp.params, s.params])
    look = np.concatenate([np.full(len(opp), -1, np.int64), np.arange(len(s), dtype=np.int64)])
    order = np.lexsort((o.route, o.t_start, o.sat))
    merged = Opportunities(RouteOptions(*(x[order] for x in o)), speed[order], params[order])
    look_of_row = look[order]
    row = np.empty(len(s), np.int64)
    row[look_of_row[look_of_row >= 0]] = np.flatnonzero(look_of_row >= 0)
    ids = stereo.products.looks
    products = StereoProducts(np.where(ids >= 0, row[np.maximum(ids, 0)], -1), *stereo.products[1:])
    return StereoMerge(merged, look_of_row, products, order.astype(np.int64))
