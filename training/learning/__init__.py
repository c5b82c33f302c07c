"""Learning on the candidate-phase interface: the expert through it, masked baselines, learning checks."""
