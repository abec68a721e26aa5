"""Turning a template into a DART: panels, named seams with default regimes, material, body."""
from __future__ import annotations

import numpy as np

from darts.body.model import BodyModel
from darts.dart.accessories import add_accessory
from darts.dart.model import MATERIALS, Dart, Seam
from darts.dart.panels import split_panels
from darts.errors import DartsInputError
from darts.templates.build import Template, build_template
from darts.templates.categories import CATEGORIES
from darts.templates.defaults import DEFAULT_EDGE_LENGTH


def _panel_name(centroid: np.ndarray, template: Template, family: str) -> str:
    lm = template.landmarks
    side = "left" if centroid[0] >= 0 else "right"
    face = "front" if centroid[2] >= lm.front_z else "back"
    if family in ("top", "dress") and abs(centroid[0]) > abs(lm.j(f"{side}_shoulder")[0]):
        return f"{side}_sleeve"
    if family in ("pants", "skirt") and centroid[1] > lm.waist_y - 0.045:
        return "waistband"
    if family == "pants":
        return f"{side}_{face}"
    if family == "dress":
        return f"{'bodice' if centroid[1] > lm.waist_y else 'skirt'}_{face}" + ("" if face == "front" else f"_{side}")
    return face


def dart_from_template(template: Template, family: str, body_model: str, betas=None, material: str = "cotton") -> Dart:
    """Split ``template`` along its seams; every seam starts 'stiff'."""
    names = sorted(template.seam_edges)
    split = split_panels(template.vertices, template.faces, [template.seam_edges[n] for n in names])
    centroids = np.stack([split.vertices[split.faces[split.panel == p]].mean((0, 1)) for p in range(split.panel.max() + 1)])
    panel_names = [_panel_name(c, template, family) for c in centroids]
    for name in set(panel_names):  # make names unique when a rule gives two panels the same one
        same = [i for i, n in enumerate(panel_names) if n == name]
        for k, i in enumerate(same[1:], start=2):
            panel_names[i] = f"{name}_{k}"
    lines = {name: split.map_loop(template.faces, loop) for name, loop in template.lines.items()}
    hull = template.hull
    return Dart(
        category=template.category, vertices=split.vertices.astype(np.float32), faces=split.faces.astype(np.int32),
        panel=split.panel.astype(np.int32), panel_names=panel_names, lines=lines,
        seams=[Seam(name) for name in names], pairs=split.pairs.astype(np.int32), pair_seam=split.pair_seam.astype(np.int32),
        pair_position=split.pair_position.astype(np.float32), body_model=body_model,
        body_betas=np.zeros(0, np.float32) if betas is None else np.asarray(betas, np.float32),
        material_name=material, material=dict(MATERIALS[material]),
        hull_vertices=None if hull is None else hull[0].astype(np.float32),
        hull_faces=None if hull is None else hull[1].astype(np.int32),
    )


def make_dart(category: str, body: BodyModel, betas=None, edge_length: float = DEFAULT_EDGE_LENGTH,
              seams: list[tuple[str, str, float | None]] = (), accessories: list[str] = (), material: str = "cotton",
              seat_ease: float | None = None, ease: float | None = None) -> Dart:
    """The DART of ``category`` on ``body``: template (cut ``ease`` off the body, None for the
    category's; trousers ``seat_ease`` below the waistband, None for the category's sitting
    allowance), panels, seam settings (name, regime, stiffness; name 'all' for every seam) and
    accessories."""
    if material not in MATERIALS:
        raise DartsInputError(None, f"unknown material '{material}' (one of {', '.join(MATERIALS)})")
    template = build_template(category, body, betas, edge_length, ease, seat_ease)
    dart = dart_from_template(template, CATEGORIES[category].family, body.name, betas, material)
    for name in accessories:
        add_accessory(dart, name, edge_length)
    for name, regime, stiffness in seams:
        dart.set_seam(name, regime, stiffness)
    return dart
