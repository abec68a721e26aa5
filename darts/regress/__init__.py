"""Reconstruction from one image (docs/reconstruction.md): the garment classifier and the
feature-line regressor of the paper's section 3, their losses, data and shipped weights."""
