"""Matplotlib plumbing of the plan figures (``plot_plan``, ``plot_attitude``).

matplotlib is imported lazily with the Agg backend; every figure is written as one PNG
atomically (temporary file in the same directory, then ``os.replace``).
"""

from __future__ import annotations

from jaxspline.planner.files import atomic_path

__all__ = ["save_figure"]


def pyplot():
    """matplotlib.pyplot on the Agg backend, imported on first use (plots are optional)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path) -> None:
    """Save ``fig`` to ``path`` atomically (temp file in the same directory + os.replace).

    Args:
      fig: matplotlib Figure; it is closed afterwards, also on failure.
      path: str or Path; written as PNG at 110 dpi.
    """
    try:
        with atomic_path(path, suffix=".tmp.png") as tmp:
            fig.savefig(tmp, dpi=110)
    finally:
        pyplot().close(fig)
