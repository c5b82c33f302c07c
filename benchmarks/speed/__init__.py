"""Speed benchmarks (``python -m benchmarks env|planner|...``): commands that print figures, never tests."""
