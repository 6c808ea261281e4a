"""The aeossp_standard benchmark: case files in and out, the adapter to the planner, and an
independent checker (``check``, ``check_frames``) that shares no code with the planner."""
