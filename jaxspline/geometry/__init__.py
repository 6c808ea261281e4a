"""Geometry: time scales and frames, orbits, pointing laws, routes, visibility windows.

``frames`` (time scales, Earth rotation, WGS84, Sun) -> ``orbit`` (circular,
SGP4/TLE, tables for many satellites) -> ``pointing`` (aim laws, pointing
states) -> ``routes`` (targets and strips, route models) and ``windows`` (every
visibility window), ``ground`` (local projections, strips between points, footprints,
ground tracks).
"""

from jaxspline.geometry.area_grid import AreaGrid as AreaGrid
from jaxspline.geometry.area_grid import area_grid as area_grid
from jaxspline.geometry.area_passes import AreaSamples as AreaSamples
from jaxspline.geometry.area_passes import Groups as Groups
from jaxspline.geometry.area_passes import StripSensor as StripSensor
from jaxspline.geometry.area_passes import find_groups as find_groups
from jaxspline.geometry.area_passes import roll_grid as roll_grid
from jaxspline.geometry.frames import angle_between as angle_between
from jaxspline.geometry.frames import earth_rotation_angle as earth_rotation_angle
from jaxspline.geometry.frames import ecef_to_geodetic as ecef_to_geodetic
from jaxspline.geometry.frames import ecef_to_teme as ecef_to_teme
from jaxspline.geometry.frames import in_shadow as in_shadow
from jaxspline.geometry.frames import rot_z as rot_z
from jaxspline.geometry.frames import sun_direction as sun_direction
from jaxspline.geometry.frames import sun_elevation as sun_elevation
from jaxspline.geometry.frames import teme_to_ecef as teme_to_ecef
from jaxspline.geometry.ground import equal_area as equal_area
from jaxspline.geometry.ground import footprint_lonlat as footprint_lonlat
from jaxspline.geometry.ground import gnomonic as gnomonic
from jaxspline.geometry.ground import gnomonic_inverse as gnomonic_inverse
from jaxspline.geometry.ground import ground_track as ground_track
from jaxspline.geometry.ground import local_axes as local_axes
from jaxspline.geometry.ground import strip_between as strip_between
from jaxspline.geometry.ground import strip_centerline as strip_centerline
from jaxspline.geometry.ground import strip_footprint as strip_footprint
from jaxspline.geometry.ground import surface_point as surface_point
from jaxspline.geometry.orbit import HermiteOrbit as HermiteOrbit
from jaxspline.geometry.orbit import OrbitTable as OrbitTable
from jaxspline.geometry.orbit import orbit_period as orbit_period
from jaxspline.geometry.orbit import orbit_position as orbit_position
from jaxspline.geometry.orbit import orbit_state as orbit_state
from jaxspline.geometry.orbit import padded_orbit as padded_orbit
from jaxspline.geometry.orbit import propagate_tle as propagate_tle
from jaxspline.geometry.orbit import tabulate_orbits as tabulate_orbits
from jaxspline.geometry.orbit import tle_orbit as tle_orbit
from jaxspline.geometry.pointing import Scene as Scene
from jaxspline.geometry.pointing import aim_angles as aim_angles
from jaxspline.geometry.pointing import aim_geometry as aim_geometry
from jaxspline.geometry.pointing import aim_params as aim_params
from jaxspline.geometry.pointing import aim_state as aim_state
from jaxspline.geometry.pointing import boresight as boresight
from jaxspline.geometry.pointing import off_nadir as off_nadir
from jaxspline.geometry.pointing import off_nadir_flat as off_nadir_flat
from jaxspline.geometry.pointing import pointing_angles as pointing_angles
from jaxspline.geometry.pointing import pointing_state as pointing_state
from jaxspline.geometry.pointing import roll_frame as roll_frame
from jaxspline.geometry.pointing import roll_look_direction as roll_look_direction
from jaxspline.geometry.pointing import roll_params as roll_params
from jaxspline.geometry.pointing import roll_pointing as roll_pointing
from jaxspline.geometry.routes import POINT as POINT
from jaxspline.geometry.routes import STRIP as STRIP
from jaxspline.geometry.routes import RouteSet as RouteSet
from jaxspline.geometry.routes import make_route_set as make_route_set
from jaxspline.geometry.routes import make_route_spec as make_route_spec
from jaxspline.geometry.routes import sample_aim_states as sample_aim_states
from jaxspline.geometry.routes import strip_direction as strip_direction
from jaxspline.geometry.windows import Windows as Windows
from jaxspline.geometry.windows import orbit_scene as orbit_scene
from jaxspline.geometry.windows import visibility_windows as visibility_windows
from jaxspline.geometry.windows import visibility_windows_all as visibility_windows_all
