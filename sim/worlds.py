"""Many worlds: several garment-on-body jobs stepped by one solver, the way NVIDIA Newton runs many
worlds in one model.

Each job (a world) brings its garments (a DART, or an outfit) and its body track. Their particles,
constraints and contacts go side by side into one ``ClothModel`` (``join_models(worlds=True)``:
world k's particles carry world k, and each world keeps its own layers) and their bodies into one
body mesh; the solver steps them all with one launch per kernel. Each world is moved in the ground
plane (x, y of the Z-up world frame) into its own cell of a square grid (``world_offsets``) whose
cells are wider than any world's body sweeps over its whole motion, plus ``WORLD_MARGIN``: every
contact query (the body's, within the contact reach; the garment's own, within the self-contact
reach) stays inside the world's cell, so no contact between jobs is ever found, and each world's
measures are its own (``Simulation.measure_worlds``; the self-contact search's velocity statistics
per world). The ground stays at z = 0 for every world. Each world's frames are handed back in its
own world frame (the offset taken off), to a ``JobRecorder`` exactly as a single run's.

Worlds may differ in garments, motions, body shapes and lengths; a world whose motion has ended
holds its body at its last frame and is no longer recorded. A world that goes unstable stops with
its message and its good frames (``JobRecorder.stopped``), its particles are put back where they
were at its last good frame, at rest, with its body held there, and the other worlds go on. One
solver means one set of ``SimSettings`` and one thickness and friction: ``sim.api.simulate_many``
groups jobs that can share one.

Precision: positions are float32; a 16 x 16 grid of 4 m cells reaches 32 m from the origin, where
a float32 coordinate is good to 4 micrometres (a single run's, near the origin, to 0.1).
"""
from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass

import numpy as np

from darts.interrupts import raise_if_interrupted
from sim.body_track import BodyTrack
from sim.engine.model import ClothModel, join_models
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation
from sim.run import JobRecorder, RunResult, job_model

#: metres between the sweeps of two neighbouring worlds' bodies (far beyond any contact reach)
WORLD_MARGIN = 1.0


@dataclass
class World:
    """One job of a many-world run: its garments (a DART or an ``Outfit``), its body track, where
    its recorded frames go (``sink(garment [V,3], body [B,3])``, the job's own world frame), and
    how it is stepped and measured (``simulate_grouped`` puts jobs that agree on these into one
    solver; ``simulate_worlds`` is given them)."""

    garments: object
    track: BodyTrack
    sink: object = None
    settings: SimSettings | None = None
    winding: bool = False
    measure_every: int = 1

    def solver_key(self) -> tuple:
        """What jobs stepped by one solver must share: the settings (resolved), the cloth's
        thickness and friction (one per model), and how the frames are measured."""
        from sim.engine.solvers import resolved_settings
        from sim.outfit import Outfit

        material = self.garments.model.material if isinstance(self.garments, Outfit) else self.garments.material
        settings = resolved_settings(self.settings or SimSettings())
        return (json.dumps(asdict(settings), sort_keys=True), float(material["thickness"]), float(material["friction"]),
                self.winding, self.measure_every)


def world_offsets(tracks: list[BodyTrack]) -> np.ndarray:
    """[N,3] the shift (m, in x and y only) that puts each track's body, over its whole motion, in
    its own cell of a square grid centred on the origin; a cell is the widest sweep plus
    ``WORLD_MARGIN`` on a side. A lone world stays where it is."""
    if len(tracks) == 1:
        return np.zeros((1, 3))
    low = np.array([t.vertices[..., :2].min(axis=(0, 1)) for t in tracks])
    high = np.array([t.vertices[..., :2].max(axis=(0, 1)) for t in tracks])
    cell = float((high - low).max()) + WORLD_MARGIN
    columns = int(np.ceil(np.sqrt(len(tracks))))
    rows = int(np.ceil(len(tracks) / columns))
    index = np.arange(len(tracks))
    centres = np.stack([index % columns - (columns - 1) / 2, index // columns - (rows - 1) / 2], 1) * cell
    offsets = np.zeros((len(tracks), 3))
    offsets[:, :2] = centres - (low + high) / 2
    return offsets


class WorldBodies:
    """Every world's body in one mesh: world k's vertices are ``slices[k]``, shifted by its offset;
    ``at(k)`` holds a world at its last frame once its motion has ended (or from ``hold[w]`` on)."""

    def __init__(self, tracks: list[BodyTrack], offsets: np.ndarray):
        self.tracks, self.offsets = tracks, offsets
        ends = np.cumsum([0] + [t.vertices.shape[1] for t in tracks])
        self.slices = [slice(a, b) for a, b in zip(ends[:-1], ends[1:])]
        self.faces = np.concatenate([np.asarray(t.faces) + s.start for t, s in zip(tracks, self.slices)])
        parts = [t.parts for t in tracks]
        self.parts = None if any(p is None for p in parts) else np.concatenate(parts)
        self.hold = [len(t.vertices) - 1 for t in tracks]  # the last frame each world's body moves to
        self.world = np.concatenate([np.full(t.vertices.shape[1], k) for k, t in enumerate(tracks)])  # [sum V]

    def at(self, k: int) -> np.ndarray:
        """[sum V, 3] every world's body at frame ``k``."""
        return np.concatenate([t.vertices[min(k, h)] + o for t, h, o in zip(self.tracks, self.hold, self.offsets)])


def join_worlds(models: list[ClothModel]) -> ClothModel:
    """``models`` as the worlds of one model (world k: ``models[k]``; a lone one as it is)."""
    if len(models) == 1:
        return models[0]
    return join_models(models, [f"world{k}" for k in range(len(models))], worlds=True)


def simulate_worlds(worlds: list[World], settings: SimSettings, progress: bool = False, winding: bool = False,
                    measure_every: int = 1) -> list[RunResult]:
    """Each world's ``RunResult``, as ``sim.run.simulate`` would give for it alone (same measures,
    same stop on a blow-up), all stepped by one solver (module docstring). ``wall_seconds`` is the
    whole run's for every world."""
    from tqdm import tqdm

    models = [job_model(w.garments) for w in worlds]
    tracks = [w.track for w in worlds]
    model = join_worlds(models)
    offsets = world_offsets(tracks)
    bodies = WorldBodies(tracks, offsets)
    starts = np.cumsum([0] + [len(m.rest) for m in models])
    particles_of = [slice(a, b) for a, b in zip(starts[:-1], starts[1:])]
    positions = np.concatenate([t.place_rest(m.rest) + o for t, m, o in zip(tracks, models, offsets)])
    solver = Simulation(model, positions, bodies.faces, bodies.at(0), settings, bodies.parts, bodies.world)
    recorders = [JobRecorder(w.garments, m, w.track, solver.settings, w.sink, winding, measure_every)
                 for w, m in zip(worlds, models)]
    active = set(range(len(worlds)))  # the worlds still recording
    total = max(r.total for r in recorders)
    start = time.perf_counter()
    bar = tqdm(total=total - 1, unit="frame", desc=f"simulating {len(worlds)} worlds", disable=not progress, leave=False)
    last_good = positions  # every particle at the last frame (a stopped world's kept where it stopped)
    for k in range(total):
        active -= {w for w in active if k >= recorders[w].total}
        if not active:
            break
        if k > 0:
            raise_if_interrupted()
            solver.step_frame(bodies.at(k))
            for w in active:
                recorders[w].result.simulated_frames += 1
            bar.update(1)
        wants = [recorders[w].wants(k) if w in active else (False, False) for w in range(len(worlds))]
        full, wind = any(f for f, _ in wants), any(d for _, d in wants)
        measures = solver.measure_worlds(winding=wind, bodies=full)
        stopped = [w for w in sorted(active) if recorders[w].stopped(k, measures[w], lambda w=w: solver.diagnose(w))]
        if stopped:
            _freeze(solver, [particles_of[w] for w in stopped], last_good)
            for w in stopped:
                bodies.hold[w] = max(k - 1, 0)
            active -= set(stopped)
            measures = solver.measure_worlds(winding=wind, bodies=full)  # without the stopped worlds' values
        now = solver.positions()
        for w in sorted(active):
            recorders[w].take(k, now[particles_of[w]] - offsets[w], measures[w])
        last_good = now
    bar.close()
    wall = time.perf_counter() - start
    for r in recorders:
        r.result.wall_seconds = wall
    return [r.result for r in recorders]


def _freeze(solver: Simulation, parts: list[slice], positions: np.ndarray) -> None:
    """Put the particles of ``parts`` back at ``positions`` [P,3], at rest."""
    x, v = solver.state.positions(), solver.state.velocities()
    for part in parts:
        x[part], v[part] = positions[part], 0.0
    solver.state.x.assign(x.astype(np.float32))
    solver.state.v.assign(v.astype(np.float32))


def simulate_grouped(worlds: list[World], size: int | None = None, progress: bool = False) -> list[RunResult]:
    """Each world's ``RunResult``, the worlds that can share a solver (``World.solver_key``) stepped
    together (``simulate_worlds``), at most ``size`` to a solver (default: all that can), groups in
    order of their first world."""
    groups: dict[tuple, list[int]] = {}
    for index, world in enumerate(worlds):
        groups.setdefault(world.solver_key(), []).append(index)
    results: dict[int, RunResult] = {}
    for members in groups.values():
        step = size or len(members)
        for first in range(0, len(members), step):
            chunk = members[first:first + step]
            lead = worlds[chunk[0]]
            done = simulate_worlds([worlds[i] for i in chunk], lead.settings or SimSettings(), progress=progress,
                                   winding=lead.winding, measure_every=lead.measure_every)
            results.update(zip(chunk, done))
    return [results[i] for i in range(len(worlds))]
