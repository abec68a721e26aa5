"""AMASS-format motions: loading, resampling, posing, and the procedural motions we ship. Names load
on first use (posing needs torch, loading does not)."""
from darts.lazy import lazy_exports as _lazy_exports

__getattr__, __dir__, __all__ = _lazy_exports(__name__, {
    "Motion": "amass", "load_motion": "amass", "save_motion": "amass", "pose_sequence": "posing", "resample": "resampling"})
