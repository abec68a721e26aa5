"""What `darts reconstruct PHOTO -o OUT_DIR` makes of the real photographs available here, given nothing
but the picture: the person's parsing, the fitted body wearing every reconstructed garment, seen
by the fitted camera, and the DARTs.

    python scripts/photo_garments.py [--out docs/images/photo_garments.png] [--json docs/data/photo_garments.json]

The photographs are those of ``scripts/photo_people.py``. Each row: the photograph with its
parsing (``darts.photo.parsing``: upper garment red, lower blue, dress violet, skin, face and hair);
the fitted body wearing every reconstructed garment (each posed by the body's skinning,
``darts.crdl.posed.Posing``), rendered through the fitted camera over the photograph; the DARTs in
the rest pose side by side. Times are CPU seconds (``time.process_time``) of
``reconstruct_outfit``, one core.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/images/photo_garments.png"))
    parser.add_argument("--json", type=Path, default=Path("docs/data/photo_garments.json"))
    args = parser.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import torch

    from darts.body.io import load_body
    from darts.camera import Camera
    from darts.crdl.deform import weld_garment
    from darts.crdl.posed import Posing
    from darts.photo.synthetic import posed_body, render_person
    from darts.raycast import cast
    from darts.regress.pipeline import reconstruct_outfit
    from darts.render import FRONT, draw_mesh

    torch.set_num_threads(1)
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from photo_people import pictures

    body = load_body(None)
    people, _ = pictures()
    palette = np.array([[0, 0, 0], [220, 60, 60], [60, 90, 220], [190, 60, 190], [235, 200, 160], [110, 70, 40],
                        [80, 190, 80]], np.float64)
    figure, axes = plt.subplots(len(people), 3, figsize=(13, 4.6 * len(people)))
    record = {}
    for row, (name, image) in zip(axes, people.items()):
        start = time.process_time()
        result = reconstruct_outfit(image, body)
        seconds = time.process_time() - start
        parsing = result.outfit.parsing
        labels = np.round(parsing.crop.to_picture(parsing.labels.astype(np.float32), image.shape[1],
                                                  image.shape[0])).astype(int)
        shown = image.astype(np.float64).copy()
        person = labels > 0
        shown[person] = 0.45 * shown[person] + 0.55 * palette[labels[person]]
        row[0].imshow(shown.astype(np.uint8))
        row[0].set_title(f"{name}\nparsed: upper red, lower blue, dress violet, skin, hair", fontsize=9)
        fit = result.garments[0].report["body_fit"]
        pose, betas = np.asarray(fit["pose_axis_angle"]), np.asarray(fit["betas"])
        camera = Camera.from_dict(fit["posed_camera"])
        worn = []
        for garment in result.garments:
            mesh = weld_garment(garment.dart)
            worn.append((Posing.of(body, pose, betas, mesh.vertices)(torch.as_tensor(mesh.vertices)).numpy(), mesh.faces))
        vertices, _, _ = posed_body(body, pose, betas)
        picture = render_person(camera, vertices, body.faces, worn, samples=1)
        covered = cast(camera, [(vertices, body.faces), *worn], 1).which.reshape(image.shape[:2]) >= 0
        row[1].imshow(np.where(covered[..., None], picture, image).astype(np.uint8))
        names = ", ".join(f"{g.report['category']} ({100 * g.report['probability']:.0f} %)" for g in result.garments)
        row[1].set_title(f"the fitted body wearing\n{names}", fontsize=9)
        offset = 0.0
        for garment, colour in zip(result.garments, ([0.3, 0.45, 0.8], [0.8, 0.35, 0.3])):
            points = np.asarray(garment.dart.vertices, np.float64) + [offset, 0.0, 0.0]
            draw_mesh(row[2], points, garment.dart.faces, np.tile(colour, (len(garment.dart.faces), 1)), *FRONT,
                      two_sided=True)
            offset += np.ptp(points[:, 0]) + 0.1
        row[2].set_title(f"the DARTs in the rest pose\n{seconds:.1f} s CPU", fontsize=9)
        for axis in row:
            axis.axis("off")
        record[name] = {"garments": [{"category": g.report["category"], "probability": round(g.report["probability"], 3),
                                      "low_confidence": g.report["low_confidence"], "lengths": g.report["lengths"],
                                      "vertices": g.report["vertices"]} for g in result.garments],
                        "notes": result.outfit.notes, "cpu_s": round(seconds, 2)}
    figure.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=70)
    args.json.write_text(json.dumps(record, indent=1))
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
