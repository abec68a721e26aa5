"""Render the figures of docs/body.md, docs/motions.md, docs/templates.md, docs/simulation.md and
docs/dataset.md (``--dataset ROOT``: a contact sheet of a dataset made by ``darts dataset make``).

Flat-shaded meshes drawn with the painter's algorithm, orthographic views.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from darts.body.io import load_body  # noqa: E402
from darts.body.segmentation import PART_NAMES, body_segmentation  # noqa: E402
from darts.motion.amass import load_motion  # noqa: E402
from darts.motion.posing import pose_sequence  # noqa: E402
from darts.motion.procedural import MOTIONS  # noqa: E402
from darts.render import WORLD_FRONT_LEFT, draw_mesh  # noqa: E402
from scenes import MOTIONS_DIR  # noqa: E402


def body_figure(out: Path) -> None:
    body = load_body()
    vertices = body.shaped()[0][0].numpy()
    labels = body_segmentation(body)
    palette = plt.get_cmap("tab20")(np.arange(len(PART_NAMES)) % 20)[:, :3]
    colors = palette[labels[body.faces].max(1)]
    fig, axes = plt.subplots(1, 2, figsize=(11, 6), gridspec_kw={"width_ratios": [2.2, 1]})
    draw_mesh(axes[0], vertices, body.faces, colors, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    draw_mesh(axes[1], vertices, body.faces, colors, np.array([0, 0, 1.0]), np.array([0, 1.0, 0]))
    handles = [plt.Rectangle((0, 0), 1, 1, color=palette[i]) for i in range(len(PART_NAMES))]
    fig.legend(handles, PART_NAMES, loc="lower center", ncol=6, fontsize=8, frameon=False)
    axes[0].set_title("front (canonical frame, Y up)")
    axes[1].set_title("side (front +Z to the right)")
    fig.savefig(out, dpi=90, bbox_inches="tight")
    plt.close(fig)


def draw_world_front_left(ax, points, faces, colors, half_width: float, top: float, title: str, fontsize: int) -> None:
    """A posed scene (AMASS world, Z up, the body facing -Y) seen from the front-left."""
    draw_mesh(ax, points, faces, colors, *WORLD_FRONT_LEFT)
    ax.set_xlim(-half_width, half_width)
    ax.set_ylim(-0.05, top)
    ax.set_title(title, fontsize=fontsize)


def motions_figure(out: Path, names: list[str], frames_per_motion: int = 5) -> None:
    body = load_body()
    fig, axes = plt.subplots(len(names), frames_per_motion, figsize=(2.2 * frames_per_motion, 2.6 * len(names)))
    grey = np.full((len(body.faces), 3), 0.75)
    for row, name in enumerate(names):
        motion = load_motion(MOTIONS_DIR / f"{name}.npz")
        vertices, _ = pose_sequence(body, motion)
        times = [0.0] + [0.5 + 0.75 * k for k in range(frames_per_motion - 1)]  # off the 1 s beat of the jacks
        for col, frame in enumerate(np.minimum(np.round(np.array(times) * motion.fps).astype(int), motion.num_frames - 1)):
            ax = axes[row, col]
            centred = vertices[frame] - [motion.trans[frame, 0], motion.trans[frame, 1], 0]
            draw_world_front_left(ax, centred, body.faces, grey, 1.0, 2.3, f"{name} {frame / motion.fps:.1f} s", 9)
            ax.plot([-0.9, 0.9], [0, 0], color="k", lw=0.8)
    fig.tight_layout()
    fig.savefig(out, dpi=70)
    plt.close(fig)


def garments_figure(out: Path) -> None:
    """Every shipped DART, front and back, panels coloured."""
    from darts.dart.export import panel_colors
    from darts.dart.io import load_dart
    from darts.render import BACK, FRONT

    paths = sorted((Path(__file__).parents[1] / "scenes" / "garments").glob("*.npz"))
    fig, axes = plt.subplots(2, len(paths), figsize=(2.2 * len(paths), 4.6))
    for col, path in enumerate(paths):
        dart = load_dart(path)
        colors = panel_colors(len(dart.panel_names))[dart.panel]
        for row, view in enumerate((FRONT, BACK)):
            draw_mesh(axes[row, col], dart.vertices.astype(float), dart.faces, colors, *view, two_sided=True)
            axes[row, col].set_xlim(-0.95, 0.95)  # one scale for every garment (canonical metres)
            axes[row, col].set_ylim(-1.15, 0.6)
        axes[0, col].set_title(path.stem, fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=60)
    plt.close(fig)


def simulation_figure(out: Path, scenes: list[tuple[str, str]], times: list[float]) -> None:
    """Garments simulated by darts-sim's solver (default settings), a few frames of each."""
    from darts.dart.export import panel_colors
    from darts.dart.io import load_dart
    from scenes import GARMENTS_DIR
    from sim.body_track import build_body_track
    from sim.engine.settings import SimSettings
    from sim.run import simulate

    body = load_body()
    fig, axes = plt.subplots(len(scenes), len(times), figsize=(2.4 * len(times), 3.0 * len(scenes)))
    for row, (garment, motion_name) in enumerate(scenes):
        dart = load_dart(GARMENTS_DIR / f"{garment}.npz")
        motion = load_motion(MOTIONS_DIR / f"{motion_name}.npz")
        track = build_body_track(body, motion, 30.0, 0.5)
        wanted = {int(round(t * 30.0)): col for col, t in enumerate(times)}
        frames: list = []

        def keep(garment_points, body_points, frames=frames, wanted=wanted):
            frames.append((garment_points, body_points) if len(frames) in wanted else None)

        simulate(dart, track, SimSettings(), keep)
        faces = np.concatenate([body.faces, dart.faces + body.num_vertices])
        colors = np.concatenate([np.full((len(body.faces), 3), 0.8), panel_colors(len(dart.panel_names))[dart.panel]])
        for frame, col in wanted.items():
            garment_points, body_points = frames[frame]
            centre = np.array([*body_points[:, :2].mean(0), 0.0])
            points = np.concatenate([body_points, garment_points]) - centre
            draw_world_front_left(axes[row, col], points, faces, colors, 0.9, 2.0,
                                  f"{garment}, {motion_name} {frame / 30.0:.1f} s", 8)
    fig.tight_layout()
    fig.savefig(out, dpi=70)
    plt.close(fig)


#: The seam settings of the seams figure (the paper's Fig. 1), left to right.
SEAM_SETTINGS = ("welded", "stiff", "loose:20", "loose:5", "loose:2", "repulsive", "partial")


def seams_figure(out: Path, garment: str, moments: list[tuple[str, float]]) -> None:
    """The paper's Fig. 1 from darts-sim runs: ``garment`` with every seam in each of
    ``SEAM_SETTINGS`` (the default settings otherwise), one row per (motion, seconds after the
    settle), close on the left side under the arm (shoulder, armhole, underarm and side seams), each
    seam pair more than 1 mm open whose ends both face the viewer drawn as a red segment; each panel titled
    with the run's widest seam gap up to that moment (mm; a partial seam's sprung part)."""
    from darts.dart.export import panel_colors
    from darts.dart.io import load_dart
    from darts.geometry.mesh import vertex_normals
    from darts.render import WORLD_FRONT_LEFT
    from scenes import GARMENTS_DIR
    from sim.body_track import build_body_track
    from sim.engine.settings import SimSettings
    from sim.run import simulate

    body = load_body()
    right, up = WORLD_FRONT_LEFT
    view = np.cross(right, up)
    fig, axes = plt.subplots(len(moments), len(SEAM_SETTINGS), figsize=(2.0 * len(SEAM_SETTINGS), 2.3 * len(moments)))
    for row, (motion_name, seconds) in enumerate(moments):
        frame = int(round(seconds * 30.0))
        track = build_body_track(body, load_motion(MOTIONS_DIR / f"{motion_name}.npz"), 30.0, 0.5)
        keep = track.settle_frames + frame + 1
        track.vertices = track.vertices[:keep]
        for col, setting in enumerate(SEAM_SETTINGS):
            dart = load_dart(GARMENTS_DIR / f"{garment}.npz")
            regime, _, stiffness = setting.partition(":")
            dart.set_seam("all", regime, float(stiffness) if stiffness else None)
            last: dict = {}
            result = simulate(dart, track, SimSettings(), lambda g, b, last=last: last.update(garment=g, body=b))
            key = "sprung_max" if regime == "partial" else "max"
            widest = max(g[key] for f in result.frames for g in f["seam_gap"].values())
            cloth = np.asarray(last["garment"], np.float64)
            left = np.isin(dart.pair_seam, [k for k, s in enumerate(dart.seams) if s.name.startswith("left_")])
            centre = cloth[dart.pairs[left]].reshape(-1, 3).mean(0)
            faces = np.concatenate([body.faces, dart.faces + body.num_vertices])
            colors = np.concatenate([np.full((len(body.faces), 3), 0.8), panel_colors(len(dart.panel_names))[dart.panel]])
            ax = axes[row, col]
            # The body drawn 5 mm inside itself: flat-shaded triangles sorted by depth would otherwise show
            # it through cloth that lies a thickness off it.
            shrunk = last["body"] - 0.005 * vertex_normals(np.asarray(last["body"], np.float64), body.faces)
            draw_mesh(ax, np.concatenate([shrunk, cloth]) - centre, faces, colors, right, up)
            facing = vertex_normals(cloth, dart.faces) @ view > 0
            shown = dart.pairs[facing[dart.pairs].all(1)]
            shown = shown[np.linalg.norm(cloth[shown[:, 0]] - cloth[shown[:, 1]], axis=1) > 0.001]
            for a, b in cloth[shown] - centre:
                ax.plot([a @ right, b @ right], [a @ up, b @ up], color="red", lw=1.2)
            ax.set_xlim(-0.2, 0.2)
            ax.set_ylim(-0.17, 0.2)
            ax.set_title(f"{setting}: {1e3 * widest:.1f} mm\n{motion_name} {seconds:g} s", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    plt.close(fig)


def dataset_figure(out: Path, root: Path) -> None:
    """Per category (rows): two test pictures with their lines drawn at their projected pixels,
    the first one's garment mask, and the same garment in the unseen-appearance part."""
    import json

    from PIL import Image

    from darts.fileio import read_npz
    from darts.templates.categories import CATEGORIES

    def picture(folder: Path, lines: bool = True) -> np.ndarray:
        image = np.asarray(Image.open(folder / "image.png")).copy()
        if lines:
            for points in read_npz(folder / "lines_px.npz").values():
                col, row = np.clip(np.floor(points).astype(int), 0, image.shape[0] - 1).T
                image[row, col] = [255, 40, 40]
        return image

    samples = sorted((root / "test").glob("*-0"))
    fig, axes = plt.subplots(len(CATEGORIES), 4, figsize=(7.2, 18))
    for row, category in enumerate(CATEGORIES):
        mine = [f for f in samples if json.loads((f / "meta.json").read_text())["category"] == category][:2]
        mask = np.asarray(Image.open(mine[0] / "mask.png"))
        panels = [picture(mine[0]), np.stack([mask] * 3, -1), picture(mine[1]),
                  picture(root / "test_unseen" / mine[0].name, False)]
        for col, panel in enumerate(panels):
            axes[row, col].imshow(panel)
            axes[row, col].axis("off")
        axes[row, 0].set_title(category, fontsize=8, loc="left")
    fig.suptitle("test garment with its lines (red) | its mask | another test garment | the first in test_unseen", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output-dir", default="docs/images")
    parser.add_argument("--simulation", action="store_true", help="only the simulation figure (runs the solver)")
    parser.add_argument("--deep-poses", action="store_true", help="only the sit and squat figure (runs the solver)")
    parser.add_argument("--seams", action="store_true", help="only the seam regimes figure, the paper's Fig. 1 (runs the solver)")
    parser.add_argument("--dataset", type=Path, metavar="ROOT", help="only the dataset's contact sheet")
    args = parser.parse_args()
    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    if args.dataset:
        dataset_figure(out / "dataset.png", args.dataset)
        print(f"wrote {out}/dataset.png")
        return
    if args.seams:
        seams_figure(out / "seam_regimes.png", "short-sleeve-top", [("walk", 1.0), ("squat", 1.6)])
        print(f"wrote {out}/seam_regimes.png")
        return
    if args.deep_poses:
        simulation_figure(out / "deep_poses.png", [("long-pants", "sit"), ("short-skirt", "sit"), ("long-pants", "squat"),
                                                   ("short-skirt", "squat")], [0.0, 0.9, 1.7, 3.0])
        print(f"wrote {out}/deep_poses.png")
        return
    if args.simulation:
        simulation_figure(out / "simulation.png", [("short-sleeve-top", "walk"), ("tshirt-collar-tie", "wave"),
                                                   ("short-skirt", "run"), ("long-pants", "squat")], [0.0, 1.0, 2.0, 3.0])
        print(f"wrote {out}/simulation.png")
        return
    body_figure(out / "default_body.png")
    motions_figure(out / "motions.png", list(MOTIONS))
    garments_figure(out / "garments.png")
    print(f"wrote {out}/default_body.png, motions.png and garments.png")


if __name__ == "__main__":
    main()
