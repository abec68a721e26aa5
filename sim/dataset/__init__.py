"""``darts dataset make``: the synthetic training set of the reconstruction networks (docs/dataset.md)."""
