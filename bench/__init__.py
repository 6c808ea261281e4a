"""jaxspline CPU benchmark harness: ``python -m bench --help``."""
