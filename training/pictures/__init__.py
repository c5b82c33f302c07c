"""Every picture of the training side: episodes (stills, GIFs) and the benchmark's plots."""
