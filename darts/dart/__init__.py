"""The DART: panels, seams with spring regimes, accessories, and the garment.npz format."""
