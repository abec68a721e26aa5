"""Starting Warp once, quietly: no banner, and no native warning about a missing CUDA driver on
CPU-only machines (Warp prints it to stderr from C during initialisation)."""
from __future__ import annotations

import contextlib
import os
import sys


@contextlib.contextmanager
def _native_stderr_silenced():
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def warp():
    """The initialised ``warp`` module."""
    import warp as wp

    if not getattr(warp, "_ready", False):
        wp.config.log_level = wp.LOG_WARNING
        with _native_stderr_silenced():
            wp.init()
        warp._ready = True
    return wp
