"""What the photograph front end (darts.photo: the person, and the body fitted to its landmarks)
finds in the real photographs available here without a download, and in pictures without a person:
a figure and the numbers of docs/reconstruction.md.

    python scripts/photo_people.py [--out docs/images/photo_people.png] [--json docs/data/photo_people.json]

Photographs: matplotlib's ``grace_hopper.jpg`` and scikit-image's ``astronaut`` and ``camera``
(scikit-image comes with gpytoolbox). Pictures without a person: random noise, a grey picture,
matplotlib's gift box and logo, and scikit-image's cat, coffee, rocket, horse, brick, motorcycle,
galaxies and retina. Times are CPU seconds (``time.process_time``) of ``find_person`` after one
untimed call that loads the models (LiteRT runs one thread), and of ``fit_body`` (one torch thread).
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def pictures() -> tuple[dict, dict]:
    """(photographs of people, pictures without one): name -> [H,W,3] uint8."""
    import matplotlib
    import skimage.data as data
    from PIL import Image

    sample = Path(matplotlib.get_data_path()) / "sample_data"
    rgb = lambda a: np.repeat(a[..., None], 3, 2) if a.ndim == 2 else np.ascontiguousarray(a[..., :3])  # noqa: E731
    people = {"grace_hopper.jpg (matplotlib)": np.asarray(Image.open(sample / "grace_hopper.jpg").convert("RGB")),
              "astronaut (scikit-image)": rgb(data.astronaut()), "camera (scikit-image)": rgb(data.camera())}
    others = {"noise": np.random.default_rng(0).integers(0, 256, (224, 224, 3), dtype=np.uint8),
              "grey": np.full((300, 200, 3), 128, np.uint8),
              "gift box": np.asarray(Image.open(sample / "Minduka_Present_Blue_Pack.png").convert("RGB")),
              "matplotlib logo": np.asarray(Image.open(sample / "logo2.png").convert("RGB"))}
    for name in ("chelsea", "coffee", "rocket", "horse", "brick", "hubble_deep_field", "retina"):
        others[name] = rgb(getattr(data, name)())
    others["motorcycle"] = rgb(data.stereo_motorcycle()[0])
    for name, image in others.items():
        if image.dtype != np.uint8:
            others[name] = (255 * image / image.max()).astype(np.uint8)
    return people, others


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/images/photo_people.png"))
    parser.add_argument("--json", type=Path, default=Path("docs/data/photo_people.json"))
    args = parser.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from darts.body.io import load_body
    from darts.photo.fit import fit_body
    from darts.photo.person import LANDMARKS, detect_people, find_person, person_in

    body = load_body(None)

    people, others = pictures()
    find_person(people["astronaut (scikit-image)"])  # loads the models: not timed
    record = {"people": {}, "others": {}}
    figure, axes = plt.subplots(1, len(people), figsize=(5 * len(people), 5.6))
    bones = [("left_shoulder", "right_shoulder"), ("left_hip", "right_hip"), ("left_shoulder", "left_hip"),
             ("right_shoulder", "right_hip"), ("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"),
             ("right_shoulder", "right_elbow"), ("right_elbow", "right_wrist"), ("left_hip", "left_knee"),
             ("left_knee", "left_ankle"), ("right_hip", "right_knee"), ("right_knee", "right_ankle")]
    for axis, (name, image) in zip(axes, people.items()):
        start = time.process_time()
        person = find_person(image)
        seconds = time.process_time() - start
        axis.imshow(image)
        fit = None
        if person is not None:
            start = time.process_time()
            fit = fit_body(person, body, image.shape[1], image.shape[0])
            fit_seconds = time.process_time() - start
            pixels, _ = fit.posed_camera.project(fit.vertices)
            axis.triplot(*pixels.T, body.faces[::3], color="white", lw=0.15, alpha=0.6)
            overlay = np.zeros((*image.shape[:2], 4))
            overlay[..., 2] = 1.0
            overlay[..., 3] = 0.35 * (person.mask > 0.5)
            axis.imshow(overlay)
            seen = person.visibility > 0.5
            for a, b in bones:
                i, j = LANDMARKS.index(a), LANDMARKS.index(b)
                if seen[i] and seen[j]:
                    axis.plot(*person.landmarks[[i, j]].T, color="yellow", lw=2)
            axis.scatter(*person.landmarks[seen].T, s=12, color="red", zorder=3)
        axis.set_xlim(0, image.shape[1])
        axis.set_ylim(image.shape[0], 0)
        axis.set_title(f"{name}\nperson {seconds:.2f} s, body fit {fit_seconds:.1f} s CPU, "
                       f"{fit.landmark_error_px:.1f} px off" if person else f"{name}: no person")
        axis.axis("off")
        record["people"][name] = {"found": person is not None, "cpu_s": round(seconds, 3),
                                  "presence": None if person is None else round(person.presence, 4),
                                  "visible_landmarks": None if person is None else int((person.visibility > 0.5).sum()),
                                  "size": list(image.shape[:2]),
                                  "body_fit": None if fit is None else {
                                      "cpu_s": round(fit_seconds, 3), "landmark_error_px": round(fit.landmark_error_px, 2),
                                      "landmarks_used": fit.landmarks_used, "betas": fit.betas.round(3).tolist()}}
    for name, image in others.items():
        detections = detect_people(image)
        presence = person_in(image, detections[0]).presence if detections else None
        record["others"][name] = {"detections": len(detections), "presence": None if presence is None else round(presence, 4),
                                  "found": find_person(image) is not None}
    figure.suptitle("darts.photo on real photographs: the person's mask (blue), landmarks seen (visibility > 0.5) "
                    "and the body fitted to them (white)")
    figure.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=80)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(record, indent=1))
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
