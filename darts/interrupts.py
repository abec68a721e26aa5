"""Ctrl-C that is never lost.

Python turns SIGINT into a KeyboardInterrupt raised wherever the main thread happens to be; when
that is inside a finaliser (``__del__`` of a Warp array, say) Python prints "Exception ignored" and
carries on, and a long run would finish and write its output as if nobody had asked it to stop.
``catching_interrupts`` installs a handler that also records the signal, and
``raise_if_interrupted`` (called between frames and before an output is renamed into place)
raises it again where it cannot be swallowed.
"""
from __future__ import annotations

import contextlib
import signal
import threading

_pending = False


def _on_sigint(signum, frame):
    global _pending
    _pending = True
    raise KeyboardInterrupt


@contextlib.contextmanager
def catching_interrupts():
    """Within the block, SIGINT raises KeyboardInterrupt as usual and is remembered until the block
    ends (outside the main thread, where handlers cannot be set, nothing changes)."""
    global _pending
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _pending = False
    previous = signal.signal(signal.SIGINT, _on_sigint)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        _pending = False


def raise_if_interrupted() -> None:
    """Raise KeyboardInterrupt if a SIGINT arrived, even one a finaliser swallowed."""
    if _pending:
        raise KeyboardInterrupt
