"""The photograph front end on the posed dataset (held-out renders: a seed nobody trained on), with no
mask and no camera given: is the person found, how well its mask and the fitted body's joints match
the truth, and what the classifier says of the whole picture.

    python scripts/evaluate_photos.py --data ~/.cache/darts/posed-s101 [--out docs/data/photo_posed_eval.json]
                                      [--reconstruct --every 2]

Measures per picture (256 x 256 pixels):
- **found**: ``darts.photo.person.find_person`` returns a person;
- **person mask IoU**: its mask (> 0.5) against the picture's ``person_mask.png`` (body and both garments);
- **joint error**: the fitted body's 22 body joints (forward kinematics of ``darts.photo.fit``),
  projected by the fitted camera, against the true joints (the body's joint regressor applied to
  its posed vertices) projected by the true camera, over the joints in view: the median distance
  in pixels, and the same over the person mask's box height (%);
- **category**: the classifier's top answer on the whole picture, and on the garment alone (the
  true mask given), against the truth.
With ``--reconstruct`` (on every ``--every``-th picture): ``darts.regress.pipeline.reconstruct``
given the picture, the true category and the garment's true mask but no camera (the posed path: the
body fitted to the person, the template on it fitted through the pose), against the template on
the same fitted body without the CRDL:
- **garment IoU**: the garment posed by the fitted body (``PosedTerm``) and rendered through the
  fitted camera, the fitted body in front of it, against the true mask;
- **surface Chamfer** (cm, unsquared, the two directions averaged): the rest-pose garment against
  the true DART (``garment.npz``: the garment before the run, on the true body shape; the
  reconstruction is on the fitted shape).
Times are CPU seconds of each stage (``time.process_time``), one core.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def garment_measures(image: np.ndarray, mask: np.ndarray, meta: dict, folder: Path, body) -> dict:
    """The posed path's garment against the template on the same fitted body (module docstring)."""
    import torch

    from darts.crdl.deform import weld_garment
    from darts.crdl.outline import Outline
    from darts.crdl.posed import PosedTerm
    from darts.dart.build import make_dart
    from darts.dart.io import load_dart
    from darts.geometry.distance import SurfaceDistance
    from darts.photo.fit import FLIP
    from darts.camera import Camera
    from darts.raycast import cast
    from darts.regress.pipeline import reconstruct
    from darts.templates.defaults import DATASET_EDGE_LENGTH

    start = time.process_time()
    result = reconstruct(image, body, meta["category"], None, mask, edge_length=DATASET_EDGE_LENGTH)
    seconds = time.process_time() - start
    fit = result.report["body_fit"]
    if not result.report["posed"]:
        return {"reconstruct_s": seconds, "posed": False}
    pose, betas = np.asarray(fit["pose_axis_angle"]), np.asarray(fit["betas"])
    camera = Camera.from_dict(result.report["camera"])
    posed_camera = Camera(camera.width, camera.height, camera.fx, camera.fy, camera.cx, camera.cy, FLIP,
                          np.asarray(fit["translation_m"]))
    model = body.to(torch.float64)
    fitted_body = model(torch.tensor(pose)[None], torch.tensor(betas)[None]).vertices[0].numpy()
    truth = load_dart(Path(folder).parent.parent / json.loads((folder / "meta.json").read_text())["garment_folder"] / "garment.npz")
    truth_vertices = np.asarray(truth.vertices, np.float64)

    def measures(dart) -> tuple[float, float]:
        mesh = weld_garment(dart)
        posing = PosedTerm(Outline(mask, posed_camera), body, pose, betas).bind(mesh.vertices, mesh.faces)
        posed = posing.posed(torch.as_tensor(mesh.vertices)).numpy()
        render = cast(posed_camera, [(fitted_body, body.faces), (posed, mesh.faces)], 1).which.reshape(mask.shape) == 1
        iou = float((render & mask).sum() / max((render | mask).sum(), 1))
        vertices = np.asarray(dart.vertices, np.float64)
        to_truth = np.abs(SurfaceDistance(truth_vertices, truth.faces).query(vertices, winding=False)[0]).mean()
        from_truth = np.abs(SurfaceDistance(vertices, dart.faces).query(truth_vertices, winding=False)[0]).mean()
        return iou, float(50 * (to_truth + from_truth))

    template = make_dart(meta["category"], body, betas=betas, edge_length=DATASET_EDGE_LENGTH)
    (iou, chamfer), (template_iou, template_chamfer) = measures(result.dart), measures(template)
    return {"reconstruct_s": seconds, "posed": True, "garment_iou": iou, "template_iou": template_iou,
            "surface_chamfer_cm": chamfer, "template_chamfer_cm": template_chamfer}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--out", type=Path, default=Path("docs/data/photo_posed_eval.json"))
    parser.add_argument("--reconstruct", action="store_true", help="also reconstruct with the true mask (slow)")
    parser.add_argument("--every", type=int, default=1, help="only every N-th picture")
    args = parser.parse_args()
    import torch
    from PIL import Image

    from darts.body.io import load_body
    from darts.camera import Camera
    from darts.fileio import read_npz
    from darts.photo.fit import fit_body
    from darts.photo.person import find_person
    from darts.regress.pipeline import classify_image

    torch.set_num_threads(1)
    body = load_body(None)
    model = body.to(torch.float64)
    folders = sorted(p.parent for p in args.data.glob("*/g*-*/image.png"))[::args.every]
    if not folders:
        raise SystemExit(f"{args.data}: no samples (make them: darts dataset make {args.data} --count 240 --seed 101 --posed)")
    rows = []
    for folder in folders:
        meta = json.loads((folder / "meta.json").read_text())
        image = np.asarray(Image.open(folder / "image.png").convert("RGB"))
        truth_mask = np.asarray(Image.open(folder / "person_mask.png")) > 127
        garment_mask = np.asarray(Image.open(folder / "mask.png")) > 127
        keypoints = read_npz(folder / "keypoints.npz")
        camera = Camera.from_json(folder / "camera.json")
        row = {"sample": f"{folder.parent.name}/{folder.name}", "category": meta["category"], "motion": meta["motion"]}
        start = time.process_time()
        person = find_person(image)
        row["person_s"] = time.process_time() - start
        row["found"] = person is not None
        start = time.process_time()
        row["classified"] = classify_image(image)[0][0]
        row["classified_garment_alone"] = classify_image(image, garment_mask)[0][0]
        row["classify_s"] = time.process_time() - start
        if person is not None:
            found = person.mask > 0.5
            row["person_mask_iou"] = float((found & truth_mask).sum() / max((found | truth_mask).sum(), 1))
            start = time.process_time()
            fit = fit_body(person, body, image.shape[1], image.shape[0])
            row["body_fit_s"] = time.process_time() - start
            joints = model(torch.tensor(fit.pose)[None], torch.tensor(fit.betas)[None]).joints[0].numpy()[:22]
            predicted, _ = fit.posed_camera.project(joints)
            truth, _ = camera.project(keypoints["joints"][:22].astype(np.float64))
            seen = keypoints["in_view"][:22]
            error = np.linalg.norm(predicted - truth, axis=1)[seen]
            rows_, cols = np.nonzero(truth_mask)
            height = float(rows_.max() - rows_.min() + 1) if len(rows_) else float(image.shape[0])
            row["joint_error_px"] = float(np.median(error))
            row["joint_error_pct_height"] = 100 * float(np.median(error)) / height
            if args.reconstruct:
                row.update(garment_measures(image, garment_mask, meta, folder, body))
        rows.append(row)
        print(json.dumps(row), flush=True)
    found = [r for r in rows if r["found"]]
    summary = {
        "data": str(args.data), "pictures": len(rows), "found": len(found),
        "person_mask_iou_median": float(np.median([r["person_mask_iou"] for r in found])) if found else None,
        "joint_error_px_median": float(np.median([r["joint_error_px"] for r in found])) if found else None,
        "joint_error_pct_height_median": float(np.median([r["joint_error_pct_height"] for r in found])) if found else None,
        "category_accuracy": float(np.mean([r["classified"] == r["category"] for r in rows])),
        "category_accuracy_garment_alone": float(np.mean([r["classified_garment_alone"] == r["category"] for r in rows])),
        "found_per_category": {c: f"{sum(r['found'] for r in rows if r['category'] == c)}/{sum(r['category'] == c for r in rows)}"
                               for c in sorted({r["category"] for r in rows})},
        "seconds_median": {k: float(np.median([r[k] for r in rows if k in r]))
                           for k in ("person_s", "body_fit_s", "classify_s", "reconstruct_s") if any(k in r for r in rows)},
    }
    posed = [r for r in rows if r.get("posed")]
    if posed:
        summary["reconstructed"] = len(posed)
        summary.update({f"{k}_median": float(np.median([r[k] for r in posed]))
                        for k in ("garment_iou", "template_iou", "surface_chamfer_cm", "template_chamfer_cm")})
        summary["garment_iou_better"] = int(sum(r["garment_iou"] > r["template_iou"] for r in posed))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"summary": summary, "pictures": rows}, indent=1))
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
