"""What `darts reconstruct` makes of the real photographs available here, given nothing but the picture:
the person's garment mask (the garment network), the fitted body, and the reconstructed garment
worn by it, seen by the fitted camera.

    python scripts/photo_garments.py [--out docs/images/photo_garments.png] [--json docs/data/photo_garments.json]

The photographs are those of ``scripts/photo_people.py``. Each row: the photograph with the
estimated garment mask (green); the fitted body wearing the reconstructed garment (posed by the
body's skinning, ``darts.crdl.posed.Posing``), rendered through the fitted camera over the
photograph; the garment in the rest pose. ``--accept-low-confidence`` is on (the report says when
it was needed). Times are CPU seconds (``time.process_time``) of ``reconstruct``, one core.
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
    from darts.regress.pipeline import reconstruct
    from darts.raycast import cast
    from darts.render import FRONT, draw_mesh

    torch.set_num_threads(1)
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from photo_people import pictures

    body = load_body(None)
    people, _ = pictures()
    figure, axes = plt.subplots(len(people), 3, figsize=(13, 4.6 * len(people)))
    record = {}
    for row, (name, image) in zip(axes, people.items()):
        start = time.process_time()
        result = reconstruct(image, body, accept_low_confidence=True)
        seconds = time.process_time() - start
        report = result.report
        mask = result.mask if result.mask is not None else np.zeros(image.shape[:2], bool)
        fit = report["body_fit"]
        pose, betas = np.asarray(fit["pose_axis_angle"]), np.asarray(fit["betas"])
        camera = Camera.from_dict(fit["posed_camera"])
        mesh = weld_garment(result.dart)
        worn = Posing.of(body, pose, betas, mesh.vertices)(torch.as_tensor(mesh.vertices)).numpy()
        vertices, _, _ = posed_body(body, pose, betas)
        picture = render_person(camera, vertices, body.faces, [(worn, mesh.faces)], samples=1)
        covered = cast(camera, [(vertices, body.faces), (worn, mesh.faces)], 1).which.reshape(image.shape[:2]) >= 0
        shown = image.astype(np.float64).copy()
        shown[mask] = 0.5 * shown[mask] + [0, 127, 0]
        row[0].imshow(shown.astype(np.uint8))
        row[0].set_title(f"{name}: garment mask estimated")
        blend = np.where(covered[..., None], picture, image)
        row[1].imshow(blend.astype(np.uint8))
        row[1].set_title(f"fitted body wearing the {report['category']} ({100 * report['probability']:.0f} %)")
        draw_mesh(row[2], np.asarray(result.dart.vertices, np.float64), result.dart.faces,
                  np.tile([0.3, 0.45, 0.8], (len(result.dart.faces), 1)), *FRONT, two_sided=True)
        row[2].set_title(f"the DART in the rest pose, {seconds:.1f} s CPU")
        for axis in row:
            axis.axis("off")
        record[name] = {"category": report["category"], "probability": round(report["probability"], 3),
                        "low_confidence": report["low_confidence"], "posed": report["posed"], "cpu_s": round(seconds, 2),
                        "mask_pixels": int(mask.sum()), "times": report["times"]}
    figure.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=70)
    args.json.write_text(json.dumps(record, indent=1))
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
