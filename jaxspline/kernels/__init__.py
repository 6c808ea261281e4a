"""Kernels: per-candidate mathematics of the papers (one candidate each, batched once)."""
