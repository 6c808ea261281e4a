"""Geometry: time scales and frames, orbits, pointing laws, routes, visibility windows."""
