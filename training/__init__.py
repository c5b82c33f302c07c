"""training: expert datasets, learned baselines, the benchmark harness and the command line."""
