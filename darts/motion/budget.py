"""How long a sequence may be: the limits every per-frame allocation checks before it is made, so
that a frame rate of 1e9 or a settle of 1e9 s is refused at the door instead of exhausting memory."""
from __future__ import annotations

from darts.errors import DartsInputError

#: The most frames a motion may have once resampled or joined to its settle (about 2.8 hours at 30
#: fps; the longest AMASS recordings are minutes). The motion's parameters take about 1.3 kB a frame.
MAX_FRAMES = 300_000
#: The most memory (bytes) posed body vertices and joints may take: float32 [T, V + J, 3].
MAX_POSED_BYTES = 4 << 30


def check_frames(count: int, source, what: str) -> None:
    """Raise a DartsInputError naming ``source`` if ``what`` ("resampled to 1e+06 fps", ...) makes
    ``count`` frames, more than ``MAX_FRAMES``."""
    if count > MAX_FRAMES:
        raise DartsInputError(source, f"{what} is {count:.4g} frames, more than the {MAX_FRAMES} a run may have "
                                      "(use a lower frame rate, a shorter settle or --start/--end)")


def check_posed_bytes(frames: int, points: int, source) -> None:
    """Raise a DartsInputError naming ``source`` if posing ``frames`` frames of ``points`` body
    vertices and joints (float32 xyz) takes more than ``MAX_POSED_BYTES``."""
    size = frames * points * 3 * 4
    if size > MAX_POSED_BYTES:
        raise DartsInputError(source, f"posing {frames} frames of a {points}-point body takes {size / 2**30:.3g} GiB, "
                                      f"more than the {MAX_POSED_BYTES / 2**30:.0f} GiB a run may use "
                                      "(use fewer frames or a lower frame rate)")
