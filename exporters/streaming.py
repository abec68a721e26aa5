"""The context-manager protocol shared by the streaming writers (USD, mesh sequences)."""
from __future__ import annotations


class StreamingWriter:
    """``with Writer(...) as w:`` closes (publishes) the output on success and discards it on error."""

    def close(self) -> None:
        raise NotImplementedError

    def discard(self) -> None:
        raise NotImplementedError

    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        if kind is None:
            self.close()
        else:
            self.discard()
        return False
