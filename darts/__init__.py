"""DARTs: Deformable Animation Ready Templates for clothing humans.

Subpackages: ``darts.body`` (SMPL-format body model), ``darts.motion`` (AMASS-format motions).
Frames: the body's canonical (rest) frame is Y up, front +Z, left +X (SMPL); the world frame of
posed bodies and motions is AMASS's Z up. Units are metres, seconds, kilograms.
"""
from darts.errors import DartsInputError

__version__ = "0.1.0"
__all__ = ["DartsInputError", "__version__"]
