"""Measuring policies: splits, the benchmark runner, its metrics and report, the expert in physics, checks."""
