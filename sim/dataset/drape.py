"""A short drape of a DART on the body standing still in its rest pose, in the canonical frame.

The simulator runs in whatever frame its body track and gravity are given in; here both are the
body's canonical frame (Y up, metres): the body is the rest-posed shape at every frame and gravity
is (0, -9.81, 0) m/s^2, with no ground. So the draped garment, the lines and the cameras of a
dataset sample all share the DART's own frame.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from darts.body.model import BodyModel
from darts.body.segmentation import body_segmentation
from darts.dart.model import Dart
from sim.body_track import BodyTrack
from sim.engine.settings import SimSettings
from sim.worlds import World, simulate_grouped

#: The drape's solver per family: chosen when XPBD, before its long-range tethers, let waistbands
#: creep down the hips and the implicit mass-spring solver held them; kept since, so that a dataset
#: made again from its seed is the same garments.
DRAPE_SOLVER = {"top": "xpbd", "dress": "xpbd", "pants": "mass-spring", "skirt": "mass-spring"}


@dataclass
class Drape:
    """The draped DART vertices [V,3] (canonical frame) and what the run measured."""

    vertices: np.ndarray
    stable: bool
    message: str
    max_penetration: float
    seconds: float


def rest_track(body: BodyModel, betas, frames: int, fps: float) -> BodyTrack:
    """The body in its rest pose, shaped by ``betas``, standing still for ``frames`` frames."""
    rest = body.shaped(None if betas is None or len(betas) == 0 else np.asarray(betas))[0][0].double().numpy()
    vertices = np.repeat(rest[None].astype(np.float32), frames + 1, axis=0)
    return BodyTrack(vertices, body.faces, float(fps), 0, np.eye(3), np.zeros(3), np.zeros(3), body_segmentation(body))


def drape_many(garments: list[tuple[Dart, BodyModel, str]], seconds: float = 0.5, fps: float = 30.0,
               device: str = "cpu", worlds: int | None = None) -> list[Drape]:
    """Let each ``(dart, body, family)`` (a DART made for ``body`` in the DART's shape) settle under
    gravity for ``seconds``; those with the same drape solver step together as worlds of one solver
    (``sim.worlds.simulate_grouped``, at most ``worlds`` to a solver). One garment alone is exactly
    a single run."""
    frames = max(1, int(round(seconds * fps)))
    kept = [{} for _ in garments]
    jobs = []
    for (dart, body, family), last in zip(garments, kept):
        settings = SimSettings(fps=fps, solver=DRAPE_SOLVER[family], gravity=(0.0, -9.81, 0.0), ground=False,
                               device=device)
        jobs.append(World(dart, rest_track(body, dart.body_betas, frames, fps),
                          lambda garment, _body, last=last: last.update(vertices=garment), settings))
    results = simulate_grouped(jobs, size=worlds)
    return [Drape(np.asarray(last.get("vertices", np.asarray(dart.vertices, np.float64)), np.float64), result.stable,
                  result.message, max((f["penetration"] for f in result.frames), default=0.0), result.wall_seconds)
            for (dart, _, _), last, result in zip(garments, kept, results)]


def drape(dart: Dart, body: BodyModel, family: str, seconds: float = 0.5, fps: float = 30.0,
          device: str = "cpu") -> Drape:
    """Let ``dart`` (made for ``body`` in the DART's shape) settle under gravity for ``seconds``."""
    return drape_many([(dart, body, family)], seconds, fps, device)[0]
