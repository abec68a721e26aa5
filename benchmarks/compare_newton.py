"""Our solver against Newton's XPBD, VBD and Style3D on one scene, in one process.

    pip install -e ".[bench]"          # adds newton (benchmark-only)
    python benchmarks/compare_newton.py [--frames 30] [--out docs/data/benchmark_newton.json]

Scene (the same for every solver): the shipped short-sleeve top with every seam welded (one
connected triangle mesh; Newton's solvers blew up on its zero-length seam springs), so the seam gap
column is 0 by construction. The default body, posed by the shipped walk at 30 fps, is a deforming
triangle mesh whose points are set and whose BVH is refit every frame; the frames timed are the
first ones, where the body blends from its rest pose into the walk (0.5 s). 10 substeps per frame,
the ground plane, gravity; world frame Z up, metres. Newton's solvers take 10 substeps a frame;
its XPBD gets 10 iterations, VBD 10 (with and without its self-contact), Style3D 4; ours runs at
its defaults (``SimSettings()``), with and without self-contact. Reported per solver, every
quality number measured the same way on each side's particle positions: simulated frames per
second (CPU time of the stepping only, after one untimed frame that compiles the kernels), its
ratio to ours, edge strain (``sim.quality.edge_strain``: the mean over frames of the mean over
edges, and the largest 99th percentile), the largest fraction of particles inside the body over
the frames (by the closest point's sign), the largest seam gap (m) and whether the run stayed
finite and slower than 50 m/s. A solver that refuses the scene is reported with the reason.
"""
from __future__ import annotations

import argparse
import json
import time
import traceback
from pathlib import Path

import numpy as np

from darts.body.io import load_body
from darts.dart.io import load_dart
from darts.geometry.warp_runtime import warp
from darts.motion.amass import load_motion
from darts.shipped import resolve_garment, resolve_motion
from sim.body_track import build_body_track
from sim.engine import kernels
from sim.engine.model import cloth_model
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation
from sim.quality import edge_strain

wp = warp()
SUBSTEPS = 10  # Newton's substeps per frame
MAX_SPEED = 50.0


class Scene:
    """The garment's cloth model in the world frame and the body track it is simulated on."""

    def __init__(self, garment: str, motion: str, frames: int):
        self.dart = load_dart(resolve_garment(garment))
        # Welded: one connected mesh every solver accepts (Newton's zero-length springs blow up).
        self.dart.set_seam("all", "welded")
        self.model = cloth_model(self.dart)
        track = build_body_track(load_body(), load_motion(resolve_motion(motion)), 30.0, 0.5)
        self.track = track
        self.frames = min(frames, len(track.vertices) - 1)
        self.rest = track.place_rest(self.model.rest)
        self.body_faces = np.asarray(track.faces, np.int32)
        self._body = wp.Mesh(points=wp.array(track.vertices[0].astype(np.float32), dtype=wp.vec3),
                             indices=wp.array(self.body_faces.reshape(-1), dtype=wp.int32))

    def measure(self, frame: int, x: np.ndarray) -> tuple[float, float, bool, np.ndarray]:
        """Penetration (fraction of particles inside the body at ``frame``), largest seam-pair gap (m),
        whether all is finite, and every edge's strain."""
        finite = bool(np.all(np.isfinite(x)))
        if not finite:
            return 1.0, float("inf"), False, np.zeros(0)
        self._body.points.assign(self.track.vertices[frame].astype(np.float32))
        self._body.refit()
        xs = wp.array(x.astype(np.float32), dtype=wp.vec3)
        inside = wp.zeros((1, 4), dtype=wp.int32)
        speed = wp.zeros(1, dtype=float)
        ok = wp.ones(1, dtype=wp.int32)
        wp.launch(kernels.frame_measures, dim=len(x),
                  inputs=[self._body.id, self._body.id, 1, 0, xs, wp.zeros_like(xs), wp.zeros(len(x), dtype=wp.int32),
                          inside, speed, ok])
        springs = self.model.springs
        gap = float(np.linalg.norm(x[springs[:, 0]] - x[springs[:, 1]], axis=1).max()) if len(springs) else 0.0
        return float(inside.numpy()[0, 0]) / len(x), gap, finite, edge_strain(self.model, x)


def run_ours(scene: Scene, self_contact: bool = True) -> dict:
    settings = SimSettings(self_contact=self_contact)
    solver = Simulation(scene.model, scene.rest, scene.body_faces, scene.track.vertices[0], settings)
    return _loop(scene, lambda k: solver.step_frame(scene.track.vertices[k]), solver.positions,
                 lambda: float(np.linalg.norm(solver.v.numpy(), axis=1).max()))


def _newton_scene(scene: Scene, kind: str):
    import newton

    builder = newton.ModelBuilder(up_axis=newton.Axis.Z)
    material = scene.model.material
    cloth = dict(pos=wp.vec3(0.0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0.0),
                 vertices=[wp.vec3(*p) for p in scene.rest], indices=scene.model.faces.reshape(-1).tolist(),
                 density=material["density"], particle_radius=material["thickness"])
    if kind == "style3d":
        from newton.solvers import style3d

        newton.solvers.SolverStyle3D.register_custom_attributes(builder)
        # Style3D wants the flat sewing pattern; the rest shape's own x-z coordinates stand in for it.
        style3d.add_cloth_mesh(builder, panel_verts=scene.rest[:, [0, 2]].tolist(),
                               panel_indices=scene.model.faces.reshape(-1).tolist(), **cloth)
    else:
        builder.add_cloth_mesh(tri_ke=1.0e4, tri_ka=1.0e4, tri_kd=1.0e-5, edge_ke=1.0e-2, **cloth)
    body = newton.Mesh(scene.track.vertices[0].astype(np.float32), scene.body_faces.reshape(-1))
    builder.add_shape_mesh(body=-1, mesh=body)
    builder.add_ground_plane()
    if kind == "vbd":
        builder.color()
    model = builder.finalize(device="cpu")
    model.shape_collision_radius.fill_(100.0)  # the body deforms and walks: never cull it
    model.soft_contact_mu = material["friction"]
    return newton, model, body


def run_newton(scene: Scene, kind: str, substeps: int = SUBSTEPS, iterations: int = 10,
               collide_every_substep: bool = False) -> dict:
    """One of Newton's solvers on the scene: ``substeps`` a frame, ``iterations`` (XPBD, VBD), the
    body's contacts found once a frame (its documented loop) or before every substep."""
    newton, model, body = _newton_scene(scene, kind.removesuffix("-no-self-contact"))
    if kind == "xpbd":
        solver = newton.solvers.SolverXPBD(model, iterations=iterations)
    elif kind.startswith("vbd"):
        solver = newton.solvers.SolverVBD(model, iterations=iterations, particle_enable_self_contact=kind == "vbd")
    else:
        solver = newton.solvers.SolverStyle3D(model, config=newton.solvers.SolverStyle3D.Config(iterations=4))
    state, state_next, control = model.state(), model.state(), model.control()
    pipeline = newton.CollisionPipeline(model)
    contacts = pipeline.contacts()
    dt = 1.0 / (30.0 * substeps)
    mesh = body.mesh

    def step(k: int) -> None:
        nonlocal state, state_next
        mesh.velocities.assign(((scene.track.vertices[k] - scene.track.vertices[k - 1]) * 30.0).astype(np.float32))
        mesh.points.assign(scene.track.vertices[k].astype(np.float32))
        mesh.refit()
        for substep in range(substeps):
            if substep == 0 or collide_every_substep:
                pipeline.collide(state, contacts)
            state.clear_forces()
            solver.step(state, state_next, control, contacts, dt)
            state, state_next = state_next, state

    return _loop(scene, step, lambda: state.particle_q.numpy().astype(np.float64),
                 lambda: float(np.linalg.norm(state.particle_qd.numpy(), axis=1).max()))


def _loop(scene: Scene, step, positions, max_speed) -> dict:
    step(1)  # compiles the kernels; not timed
    wall, penetration, gap, stable, message, strains, p99 = 0.0, 0.0, 0.0, True, "", [], 0.0
    for k in range(2, scene.frames + 1):
        start = time.process_time()
        step(k)
        wall += time.process_time() - start
        pen, g, finite, strain = scene.measure(k, positions())
        speed = max_speed()
        if not finite or speed > MAX_SPEED:
            stable, message = False, f"frame {k}: " + ("non-finite positions" if not finite else f"{speed:.0f} m/s")
            break
        penetration, gap = max(penetration, pen), max(gap, g)
        strains.append(float(strain.mean()))
        p99 = max(p99, float(np.percentile(strain, 99)))
    frames = k - 1 if stable else k - 2
    return {"sim_fps": frames / wall if wall > 0 else 0.0, "frames": frames,
            "strain_mean": float(np.mean(strains)) if strains else None, "strain_p99": p99, "max_penetration": penetration,
            "max_seam_gap": gap, "stable": stable, "message": message}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--garment", default="short-sleeve-top")
    parser.add_argument("--motion", default="walk")
    parser.add_argument("--frames", type=int, default=30,
                        help="frames timed, after the first (the settle blend comes first); Newton's VBD with "
                             "self-contact takes about 100 s a frame here")
    parser.add_argument("--solvers", default="ours,ours-no-self-contact,newton-xpbd,newton-vbd-no-self-contact,"
                                              "newton-style3d",
                        help="comma-separated; newton-vbd (with its self-contact, about 100 s a frame here) is left "
                             "out by default")
    parser.add_argument("--newton-substeps", type=int, default=SUBSTEPS, help=f"Newton's substeps a frame (default {SUBSTEPS})")
    parser.add_argument("--newton-iterations", type=int, default=10, help="Newton's XPBD and VBD iterations (default 10)")
    parser.add_argument("--collide-every-substep", action="store_true",
                        help="Newton finds the body's contacts before every substep (default: once a frame)")
    parser.add_argument("--out", type=Path, default=Path("docs/data/benchmark_newton.json"))
    args = parser.parse_args()
    scene = Scene(args.garment, args.motion, args.frames + 1)
    results = {}
    for name in args.solvers.split(","):
        try:
            if name.startswith("ours"):
                row = run_ours(scene, self_contact=name == "ours")
            else:
                row = run_newton(scene, name.removeprefix("newton-"), args.newton_substeps, args.newton_iterations,
                                 args.collide_every_substep)
        except Exception as exc:  # a solver that refuses the scene is a result, not a crash
            row = {"sim_fps": 0.0, "stable": False, "message": f"refused the scene: {type(exc).__name__}: {exc}"}
            traceback.print_exc()
        results[name] = row
        print(name, json.dumps(row), flush=True)
    ours = results.get("ours", {}).get("sim_fps", 0.0)
    for row in results.values():
        row["ratio_to_ours"] = row["sim_fps"] / ours if ours else None
    document = {"scene": {"garment": args.garment, "motion": args.motion, "frames": scene.frames - 1,
                          "particles": len(scene.rest), "triangles": len(scene.model.faces),
                          "seam_springs": len(scene.model.springs), "newton_substeps": args.newton_substeps,
                          "newton_iterations": args.newton_iterations,
                          "newton_collide_every_substep": args.collide_every_substep},
                "results": results}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(document, indent=1))
    print(json.dumps(document, indent=1))


if __name__ == "__main__":
    main()
