"""Small tensors on one thread."""
from __future__ import annotations

from contextlib import contextmanager


@contextmanager
def one_torch_thread():
    """Run the block on one torch thread, restoring the caller's count afterwards. A photograph's
    reconstruction (a body fit, templates and CRDLs of a few thousand vertices) only loses from
    more: 13.5 s of CPU on two threads against 8.1 s on one for a photograph of two garments, and
    longer on the clock too."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)
