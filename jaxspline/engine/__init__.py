"""Engine: option tables, screening, maneuver models, search, refinement, checks, planner."""
