"""AMASS-format motions: loading, resampling, posing, and the procedural motions we ship."""
from darts.motion.amass import Motion, load_motion, save_motion
from darts.motion.posing import pose_sequence
from darts.motion.resample import resample

__all__ = ["Motion", "load_motion", "pose_sequence", "resample", "save_motion"]
