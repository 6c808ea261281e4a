"""Numpy baselines that run the SAME kernel formulas as jaxspline, with numpy instead of jnp.

The one-candidate kernels are written against a small numpy-compatible subset of
``jax.numpy`` (where, clip, abs, sqrt, minimum, finfo, ...). Re-binding ``jnp``
to ``numpy`` in a copy of the module's functions gives a numpy-vectorized
implementation of exactly the same formula: the fairest "numpy baseline".
"""

from __future__ import annotations

import importlib
import types

import numpy as np


class _NumpyAsJnp(types.SimpleNamespace):
    """``numpy`` plus the few names jnp has and numpy spells differently."""

    def __getattr__(self, name):
        return getattr(np, name)


def numpy_module(modname: str) -> types.SimpleNamespace:
    """A namespace of ``modname``'s functions whose ``jnp`` is numpy (errors on jax-only calls)."""
    mod = importlib.import_module(modname)
    glb = dict(vars(mod))
    glb["jnp"] = _NumpyAsJnp()
    out = {}
    for name, obj in vars(mod).items():
        if isinstance(obj, types.FunctionType) and obj.__module__ == mod.__name__:
            out[name] = types.FunctionType(
                obj.__code__, glb, name, obj.__defaults__, obj.__closure__
            )
    glb.update(out)  # helpers called by kernels resolve to the numpy copies too
    return types.SimpleNamespace(**out)
