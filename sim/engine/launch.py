"""Kernel launches recorded once and replayed, one by one (``Launcher``) or as a captured block
(``Replay``).

``wp.launch`` packs every argument on every call, about 13 µs on the CPU backend; a substep makes
some twenty launches, each with the same arrays every time. ``Launcher`` records a launch the first
time it sees a (kernel, dim, arrays) combination (``record_cmd=True``) and replays it afterwards
(about 2.5 µs), setting a scalar argument again only when its value changed. The kernels run exactly
as with ``wp.launch``: same arguments, same order.
"""
from __future__ import annotations

from darts.geometry.warp_runtime import warp

wp = warp()


def _is_array(value) -> bool:
    return isinstance(value, wp.array)


def _plain(value):
    """A scalar or vector argument as something ``==`` compares by value."""
    return tuple(value) if hasattr(value, "__len__") else value


class Launcher:
    """``launcher(kernel, dim, inputs)`` runs ``kernel`` like ``wp.launch(kernel, dim, inputs, device)``.

    Recorded launches keep their arrays alive, so an array's id names it for as long as the
    launcher lives; the launcher belongs to the object that owns the arrays. With ``record`` off
    every call is a plain ``wp.launch`` (how the solver launched before issue 30; the same results)."""

    def __init__(self, device: str, record: bool = True):
        self.device, self.record = device, record
        self._recorded: dict[tuple, tuple] = {}

    def __call__(self, kernel, dim: int, inputs: list) -> None:
        if dim == 0:
            return
        if not self.record:
            wp.launch(kernel, dim=dim, inputs=inputs, device=self.device)
            return
        key = (kernel, dim, tuple(id(value) if _is_array(value) else None for value in inputs))
        found = self._recorded.get(key)
        if found is None:
            launch = wp.launch(kernel, dim=dim, inputs=inputs, device=self.device, record_cmd=True)
            scalars = {k: _plain(value) for k, value in enumerate(inputs) if not _is_array(value)}
            arrays = [value for value in inputs if _is_array(value)]
            self._recorded[key] = (launch, scalars, arrays)
        else:
            launch, scalars, _ = found
            for index, last in scalars.items():
                value = _plain(inputs[index])
                if value != last:
                    launch.set_param_at_index(index, inputs[index])
                    scalars[index] = value
        launch.launch()


class Replay:
    """``replay.run(key, block)`` runs ``block()`` (a fixed sequence of launches and array fills) as one
    captured graph: on the CPU, Warp's CPU capture (APIC) records the operations once and replays
    them in C++ without Python, about 0.2 µs an operation against the 3-13 µs of a launch from
    Python; on a CUDA device the same calls (``wp.capture_begin`` / ``capture_end`` /
    ``capture_launch``) make and launch a CUDA graph, one launch for the whole block, so ``block``
    must not read anything back to the host.

    A capture holds the arrays it saw and the value of every scalar argument, so ``key`` must
    name everything ``block`` depends on that can change between calls (the arrays' ids, flags,
    step sizes): a new key captures again. The first call with a key runs ``block()`` directly, so
    its kernels are loaded outside the capture, the second captures it, later ones replay. With
    ``capture`` off the block runs directly."""

    def __init__(self, device: str, capture: bool = True):
        self.capture = capture
        self.device = device
        self._graphs: dict = {}

    @property
    def captured(self) -> int:
        """How many blocks have been captured (one per key seen twice)."""
        return sum(graph is not False for graph in self._graphs.values())

    def run(self, key, block) -> None:
        """Run ``block()`` for ``key``: directly, captured, or replayed (see the class). The arrays it
        launches with must stay alive, as they do in the ``Launcher`` records of the launches."""
        if not self.capture:
            block()
            return
        graph = self._graphs.get(key)
        if graph is None:  # first sight: run it and capture next time
            self._graphs[key] = False
            block()
            return
        if graph is False:
            wp.capture_begin(device=self.device)
            try:
                block()
            finally:
                graph = wp.capture_end(device=self.device)
            self._graphs[key] = graph
        wp.capture_launch(graph)
