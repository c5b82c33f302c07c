"""Policies that need no training: the ``Policy`` protocol, masked random, greedy, and the expert in phases."""
