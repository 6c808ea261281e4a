"""Readers: scenario files in, validated mission types out.

``config`` holds the planner's settings (:class:`PlannerConfig`, :class:`Margins`);
``mission`` the types every later stage reads (:class:`Scenario`, :class:`Satellite`,
:class:`Targets`, :class:`Area`, ...); ``fields`` the checked TOML/CSV field readers;
``ranges`` the physical range of every number of a scenario file; ``case_files`` the
benchmark cases' shared file checks; ``satellites`` the satellite tables
(TLE checks); ``targets`` the target tables (CSV and TOML); ``area_files`` the
GeoJSON/TOML areas and their sample files; ``scenario`` the TOML scenario reader (the
full schema is its docstring). Readers read: the planner lays areas out and plans them
(:mod:`jaxspline.planner.area_options`).
"""

from jaxspline.readers.area_files import AREA_KEYS as AREA_KEYS
from jaxspline.readers.area_files import GRID_PER_SWATH as GRID_PER_SWATH
from jaxspline.readers.area_files import MAX_AREA_SAMPLES as MAX_AREA_SAMPLES
from jaxspline.readers.area_files import MAX_RADIUS_DEG as MAX_RADIUS_DEG
from jaxspline.readers.area_files import AreaSpec as AreaSpec
from jaxspline.readers.area_files import parse_areas as parse_areas
from jaxspline.readers.area_files import polygon_center as polygon_center
from jaxspline.readers.area_files import read_geojson as read_geojson
from jaxspline.readers.area_files import read_samples as read_samples
from jaxspline.readers.config import MAX_EXACT_OPTIONS as MAX_EXACT_OPTIONS
from jaxspline.readers.config import Margins as Margins
from jaxspline.readers.config import PlannerConfig as PlannerConfig
from jaxspline.readers.mission import DEFAULT_SWATH as DEFAULT_SWATH
from jaxspline.readers.mission import Area as Area
from jaxspline.readers.mission import FlexMode as FlexMode
from jaxspline.readers.mission import Power as Power
from jaxspline.readers.mission import Satellite as Satellite
from jaxspline.readers.mission import Scenario as Scenario
from jaxspline.readers.mission import Targets as Targets
from jaxspline.readers.mission import make_targets as make_targets
from jaxspline.readers.ranges import EPOCH_RANGE as EPOCH_RANGE
from jaxspline.readers.ranges import HORIZON as HORIZON
from jaxspline.readers.ranges import MAX_NAME_CHARS as MAX_NAME_CHARS
from jaxspline.readers.ranges import MAX_SCAN_SPEEDS as MAX_SCAN_SPEEDS
from jaxspline.readers.ranges import MAX_TLE_AGE_DAYS as MAX_TLE_AGE_DAYS
from jaxspline.readers.ranges import RANGES as RANGES
from jaxspline.readers.ranges import bounds as bounds
from jaxspline.readers.ranges import range_text as range_text
from jaxspline.readers.satellites import SATELLITE_KEYS as SATELLITE_KEYS
from jaxspline.readers.satellites import parse_satellites as parse_satellites
from jaxspline.readers.satellites import tle_epoch as tle_epoch
from jaxspline.readers.scenario import DEFAULT_SCENARIO_PATH as DEFAULT_SCENARIO_PATH
from jaxspline.readers.scenario import default_scenario as default_scenario
from jaxspline.readers.scenario import load_scenario as load_scenario
from jaxspline.readers.scenario import parse_scenario as parse_scenario
from jaxspline.readers.scenario import scenario_from as scenario_from
from jaxspline.readers.targets import CSV_OPTIONAL as CSV_OPTIONAL
from jaxspline.readers.targets import CSV_REQUIRED as CSV_REQUIRED
from jaxspline.readers.targets import TARGET_SECTIONS as TARGET_SECTIONS
from jaxspline.readers.targets import load_targets_csv as load_targets_csv
from jaxspline.readers.targets import scenario_targets as scenario_targets
