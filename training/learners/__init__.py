"""Learned baselines: one module per learner (bc, dagger, ppo, ensemble), their networks and run folders."""
