"""Speed benchmarks (``fetchcarry bench``): commands that print figures, never tests."""
