"""The aeossp_standard benchmark: case files in and out, the adapter to the planner, and an
independent checker (``check``, ``check_frames``) that shares no code with the planner.

Layer 8, on top: the adapter (``adapter``, ``cli``) may import anything below. The
checker imports nothing of the package but the case reader (``case``).
"""
