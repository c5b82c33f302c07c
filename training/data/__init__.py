"""Where episodes come from and where they go: sources, parallel generation, staging, Minari datasets."""
