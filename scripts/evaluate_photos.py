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
  true mask given), against the truth;
- **parsing** (``darts.photo.outfit``, issue 44): the garment of the picture's kind (upper, lower,
  dress) among those read: its category against the truth, its parsed mask against the true
  garment mask (IoU); and per garment, the other garment worn (``meta.json``'s ``other``, when
  there is one) read as its own kind, its category against the truth too;
- **garment network** (the previous method, when its weights are shipped): its mask (``segment_garment`` on the crop
  around the found person) against the true garment mask (IoU), and its category.
With ``--reconstruct`` (on every ``--every``-th picture), ``darts.regress.pipeline.reconstruct``
twice with no camera: "oracle", given the true category and the garment's true mask, and "photo",
given nothing but the picture: the parsing's garment of the picture's kind (upper, lower, dress:
the one of ``-o OUT_DIR``'s garments that the truth is about), its mask and category (its lengths
measured, not applied: the default). Each against the
template of its category on the same fitted body without the CRDL:
- **garment IoU**: the garment posed by the fitted body (``darts.crdl.posed.Posing``) and rendered through the
  fitted camera, the fitted body in front of it, against the true mask;
- **surface Chamfer** and **line Chamfer** (cm, unsquared, the two directions averaged; lines:
  each feature line resampled to 64 points, the mean over lines): the rest-pose garment against
  the true DART (``garment.npz``: the garment before the run, on the true body shape; the
  reconstruction is on the fitted shape), when the category is right.
Times are CPU seconds of each stage (``time.process_time``), one core.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def garment_measures(image: np.ndarray, mask: np.ndarray | None, truth_mask: np.ndarray, category: str | None,
                     folder: Path, body, garment: str | None = None) -> dict:
    """The posed path's garment (given ``mask`` and ``category``, or None: estimated; ``garment``:
    which of the photograph's garments, as ``-o OUT_DIR`` reconstructs each, an unsure category
    taking its most likely) against the template on the same fitted body, both measured against
    ``truth_mask`` (module docstring)."""
    import torch

    from darts.camera import Camera
    from darts.crdl.deform import weld_garment
    from darts.crdl.posed import Posing
    from darts.dart.build import make_dart
    from darts.dart.io import load_dart
    from darts.errors import DartsInputError
    from darts.geometry.distance import SurfaceDistance
    from darts.geometry.loops import feature_lines
    from darts.raycast import cast
    from darts.regress.pipeline import reconstruct
    from darts.templates.defaults import DATASET_EASE, DATASET_EDGE_LENGTH

    start = time.process_time()
    try:
        result = reconstruct(image, body, category, None, mask, edge_length=DATASET_EDGE_LENGTH, garment=garment,
                             accept_low_confidence=garment is not None)
    except DartsInputError as error:
        return {"reconstruct_s": time.process_time() - start, "posed": False, "refused": error.problem}
    seconds = time.process_time() - start
    fit = result.report["body_fit"]
    if not result.report["posed"]:
        return {"reconstruct_s": seconds, "posed": False}
    mask = truth_mask
    pose, betas = np.asarray(fit["pose_axis_angle"]), np.asarray(fit["betas"])
    posed_camera = Camera.from_dict(fit["posed_camera"])
    model = body.to(torch.float64)
    fitted_body = model(torch.tensor(pose)[None], torch.tensor(betas)[None]).vertices[0].numpy()
    garment_folder = json.loads((folder / "meta.json").read_text())["garment_folder"]
    truth = load_dart(Path(folder).parent.parent / garment_folder / "garment.npz")
    truth_vertices = np.asarray(truth.vertices, np.float64)

    def lines_of(dart) -> dict[str, np.ndarray]:
        return feature_lines(dart, dart.vertices)

    truth_lines = lines_of(truth)

    def line_chamfer(dart) -> float | None:
        if dart.category != truth.category:
            return None
        errors = []
        for name, points in lines_of(dart).items():
            d = np.linalg.norm(points[:, None] - truth_lines[name][None], axis=2)
            errors.append(50 * (d.min(1).mean() + d.min(0).mean()))
        return float(np.mean(errors))

    def measures(dart) -> tuple[float, float, float | None]:
        mesh = weld_garment(dart)
        posed = Posing.of(body, pose, betas, mesh.vertices)(torch.as_tensor(mesh.vertices)).numpy()
        render = cast(posed_camera, [(fitted_body, body.faces), (posed, mesh.faces)], 1).which.reshape(mask.shape) == 1
        iou = float((render & mask).sum() / max((render | mask).sum(), 1))
        vertices = np.asarray(dart.vertices, np.float64)
        to_truth = np.abs(SurfaceDistance(truth_vertices, truth.faces).query(vertices, winding=False)[0]).mean()
        from_truth = np.abs(SurfaceDistance(vertices, dart.faces).query(truth_vertices, winding=False)[0]).mean()
        return iou, float(50 * (to_truth + from_truth)), line_chamfer(dart)

    template = make_dart(result.report["category"], body, betas=betas, edge_length=DATASET_EDGE_LENGTH,
                         ease=DATASET_EASE)
    (iou, chamfer, lines), (template_iou, template_chamfer, template_lines) = measures(result.dart), measures(template)
    return {"reconstruct_s": seconds, "posed": True, "category": result.report["category"], "garment_iou": iou,
            "template_iou": template_iou, "surface_chamfer_cm": chamfer, "template_chamfer_cm": template_chamfer,
            "line_chamfer_cm": lines, "template_line_chamfer_cm": template_lines}


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
    from darts.photo.outfit import KIND_OF, read_outfit
    from darts.photo.person import find_person
    from darts.regress.pipeline import classify_image

    torch.set_num_threads(1)
    from darts.photo.garment_net import WEIGHTS

    network = WEIGHTS.is_file()
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
        row = {"sample": f"{folder.parent.name}/{folder.name}", "category": meta["category"], "other": meta.get("other"),
               "motion": meta["motion"]}
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
            start = time.process_time()
            outfit = read_outfit(image, person, fit, body)
            row["parsing_s"] = time.process_time() - start
            kind = KIND_OF[meta["category"]]
            read = outfit.garment(kind) if outfit else None
            row["parsing_category"] = read.category if read else None
            row["parsing_garments"] = [g.category for g in outfit.garments] if outfit else []
            if row["other"]:  # the other garment worn, read as its own kind
                other = outfit.garment(KIND_OF[row["other"]]) if outfit else None
                row["parsing_other_category"] = other.category if other else None
            parsed = outfit.mask(kind) if outfit else np.zeros_like(garment_mask)
            row["parsing_mask_iou"] = float((parsed & garment_mask).sum() / max((parsed | garment_mask).sum(), 1))
            if network:
                from darts.photo.garment_net import segment_garment

                start = time.process_time()
                estimated, ranked = segment_garment(image, person.mask)
                row["garment_s"] = time.process_time() - start
                row["garment_mask_iou"] = float((estimated & garment_mask).sum() / max((estimated | garment_mask).sum(), 1))
                row["garment_network_category"] = ranked[0][0]
            if args.reconstruct:
                oracle = garment_measures(image, garment_mask, garment_mask, meta["category"], folder, body)
                row.update({f"oracle_{k}": v for k, v in oracle.items()})
                photo = garment_measures(image, None, garment_mask, None, folder, body, KIND_OF[meta["category"]])
                row.update({f"photo_{k}": v for k, v in photo.items()})
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
                           for k in ("person_s", "body_fit_s", "classify_s", "garment_s", "oracle_reconstruct_s",
                                     "photo_reconstruct_s") if any(k in r for r in rows)},
    }
    summary["parsing"] = {
        "mask_iou_median": float(np.median([r["parsing_mask_iou"] for r in found])) if found else None,
        "category_accuracy": float(np.mean([r.get("parsing_category") == r["category"] for r in rows])),
        "category_accuracy_every_garment": float(np.mean(
            [r.get("parsing_category") == r["category"] for r in rows]
            + [r.get("parsing_other_category") == r["other"] for r in rows if r.get("other")])),
        "category_accuracy_per_category": {
            c: float(np.mean([r.get("parsing_category") == c for r in rows if r["category"] == c]))
            for c in sorted({r["category"] for r in rows})}}
    if network:
        summary["garment_network"] = {
            "mask_iou_median": float(np.median([r["garment_mask_iou"] for r in found])),
            "category_accuracy": float(np.mean([r.get("garment_network_category") == r["category"] for r in rows]))}
    for kind in ("oracle", "photo"):
        posed = [r for r in rows if r.get(f"{kind}_posed")]
        if posed:
            right = [r for r in posed if r[f"{kind}_category"] == r["category"]]
            summary[kind] = {"reconstructed": len(posed), "category_right": len(right),
                             "refused": sum(f"{kind}_refused" in r for r in rows),
                             **{f"{k}_median": float(np.median([r[f"{kind}_{k}"] for r in posed]))
                                for k in ("garment_iou", "template_iou")},
                             **{f"{k}_median_category_right":
                                float(np.median([r[f"{kind}_{k}"] for r in right])) if right else None
                                for k in ("surface_chamfer_cm", "template_chamfer_cm", "line_chamfer_cm",
                                          "template_line_chamfer_cm")},
                             "garment_iou_better": int(sum(r[f"{kind}_garment_iou"] > r[f"{kind}_template_iou"] for r in posed))}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"summary": summary, "pictures": rows}, indent=1))
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
