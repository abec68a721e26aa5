"""How close a reconstructed garment is to a picture's ground truth (canonical frame, Y up, metres).

- **Surface Chamfer** (cm, unsquared): the mean distance from the garment's vertices to the
  ground-truth draped surface and from the draped surface's vertices to the garment, the two
  directions averaged.
- **Mask IoU**: the garment's render through the picture's camera, the body (shaped by the
  picture's betas) in front of it (a hard ray cast, one ray per pixel centre), against the mask.
"""
from __future__ import annotations

import numpy as np


def reconstruction_measures(dart, draped: dict, camera, mask: np.ndarray, body, betas) -> dict[str, float]:
    """{"surface_chamfer_cm", "mask_iou"} of ``dart`` against ``draped`` (vertices, faces) and the
    picture's ``mask`` [H,W] bool seen by ``camera``."""
    from darts.geometry.distance import SurfaceDistance
    from darts.raycast import cast

    vertices = np.asarray(dart.vertices, np.float64)
    to_truth = np.abs(SurfaceDistance(draped["vertices"], draped["faces"]).query(vertices, winding=False)[0])
    from_truth = np.abs(SurfaceDistance(vertices, dart.faces).query(draped["vertices"], winding=False)[0])
    shaped = body.shaped(np.asarray(betas))[0][0].double().numpy()
    render = cast(camera, [(shaped, body.faces), (vertices, dart.faces)], 1).which.reshape(mask.shape) == 1
    return {"surface_chamfer_cm": float(50 * (to_truth.mean() + from_truth.mean())),
            "mask_iou": float((render & mask).sum() / max((render | mask).sum(), 1))}
