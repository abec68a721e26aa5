"""Shipped inputs, as data only: AMASS-format motions (``scenes/motions``), DART garments
(``scenes/garments``), batch specs and reconstruction examples. ``darts.shipped`` resolves their
names; this package imports nothing of ``darts`` (the dependency runs one way)."""
from pathlib import Path

MOTIONS_DIR = Path(__file__).parent / "motions"
GARMENTS_DIR = Path(__file__).parent / "garments"
