"""A garment mesh made elsewhere as a DART: read, repair, place on the body, name its openings,
register the category template onto it, and with ``own_mesh`` cut the mesh itself into the
template's panels (``darts import``).

Frames: the file's points as stored -> (``SourceMesh.to_canonical``: units, up axis, a USD prim's
transform) canonical frame, Y up, metres -> (the alignment, or ``--transform``) on the body, posed
with the arms lowered by the angle that fits best (``darts.meshimport.pose``; 0 for a garment at
rest). The report's ``transform`` is the product: the file's points straight to the DART's frame in
that pose; the DART itself is taken back to the rest pose.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, replace

import numpy as np

from darts.errors import DartsInputError
from darts.meshimport.read import read_garment_mesh
from darts.meshimport.repair import repair_garment_mesh
from darts.templates.categories import CATEGORIES

#: How many of the winning category's poses (arm angles), closest placement first, are registered;
#: the best registration (both directions' mean distance) is kept. The placement alone misjudges
#: the angle: on Newton's shirt it prefers 60 deg, whose registration fits worse than 45 deg's.
#: Without ``--transform`` the closest placement is also refined on its openings' fitted edit
#: (``darts.meshimport.register.placed_on_edit``) and registered as one more candidate.
REGISTERED_POSES = 2
#: Largest extent (metres) a garment may have once read; beyond, the units are wrong.
GARMENT_EXTENT = (0.05, 3.0)


@dataclass
class ImportOptions:
    """What ``darts import`` may be told: the category, units, up axis, USD prim, an explicit 4x4
    (file -> DART frame, replacing the alignment), the body and its shape, whether the placement
    may resize the garment (``fit_scale``; default rigid, ``darts.meshimport.align``) and whether
    the file's own mesh becomes the DART (``own_mesh``, ``darts.meshimport.own_mesh``)."""

    category: str | None = None
    units: str | None = None
    up: str | None = None
    prim: str | None = None
    transform: np.ndarray | None = None
    body: str | os.PathLike | None = None
    betas: list[float] | None = None
    fit_scale: bool = False
    own_mesh: bool = False


@dataclass
class ImportResult:
    """The DART, the report, the mesh as placed on the body (canonical frame) it was fitted to, the
    registered template at rest (the DART unless ``own_mesh``) and the two distances of its
    registration per point (``darts.meshimport.register.RegistrationDistances``)."""

    dart: object
    report: dict
    placed_vertices: np.ndarray
    faces: np.ndarray
    distances: object
    template: object


def _candidates(path, loops: list, category: str | None) -> list[str]:
    """The categories whose openings the mesh's ``loops`` can be (one line per loop)."""
    if category is not None:
        if category not in CATEGORIES:
            raise DartsInputError(None, f"unknown category '{category}' (see 'darts template --list')")
        names = CATEGORIES[category].line_names
        if len(names) != len(loops):
            raise DartsInputError(path, f"has {len(loops)} openings, but a {category} has {len(names)} "
                                        f"({', '.join(names)})")
        return [category]
    found = [c.id for c in CATEGORIES.values() if len(c.line_names) == len(loops)]
    if not found:
        openings = f"{len(loops)} opening" + ("" if len(loops) == 1 else "s")
        raise DartsInputError(path, f"has {openings}; garments have 2 (skirts), 3 (pants) or 4 (tops and "
                                    "dresses): check the mesh's holes")
    return found


def _check_extent(path, vertices: np.ndarray, units_note: str) -> None:
    extent = float(np.ptp(vertices, axis=0).max())
    if not GARMENT_EXTENT[0] <= extent <= GARMENT_EXTENT[1]:
        raise DartsInputError(path, f"is {extent:.3g} m across in metres ({units_note}), not the "
                                    f"{GARMENT_EXTENT[0]}-{GARMENT_EXTENT[1]} m of a garment: check --units")


def _template(category: str, body, options: ImportOptions):
    """The category's template on the body: the shipped DART when the body is the bundled one at
    its mean shape (``scripts/make_garments.py`` made it with these defaults), else built."""
    from darts.dart.build import make_dart
    from darts.dart.io import load_dart
    from scenes import GARMENTS_DIR

    shipped = GARMENTS_DIR / f"{category}.npz"
    if options.body is None and not options.betas and shipped.is_file():
        return load_dart(shipped)
    return make_dart(category, body, options.betas)


def import_garment(path: str | os.PathLike, options: ImportOptions | None = None, progress=None) -> ImportResult:
    """The DART of the mesh file ``path`` and its report; see the module docstring.
    ``progress(text)`` is told each step."""
    from darts.body.io import load_body
    from darts.crdl.deform import fit_surface, weld_garment
    from darts.crdl.fit import FitSurface
    from darts.meshimport.align import SCALE_RANGE, align_to_template, apply_matrix, naming_only
    from darts.meshimport.own_mesh import dart_from_mesh
    from darts.meshimport.pose import arm_angles, lower_arms
    from darts.meshimport.register import distance_stats, placed_on_edit, register_template

    options = options or ImportOptions()
    say = progress or (lambda text: None)
    source = read_garment_mesh(path, options.units, options.up, options.prim)
    vertices, faces, loops, repairs = repair_garment_mesh(source.vertices, source.faces, path)
    notes = source.notes + repairs
    if options.transform is None:
        _check_extent(path, vertices, source.units_note)
    candidates = _candidates(path, loops, options.category)
    body = load_body(options.body)

    tried = {}  # category -> [(alignment, the template lowered, its fit surface)] over the arm angles, best first
    for category in candidates:
        say(f"placing on the {category} template")
        template = _template(category, body, options)
        hull = None if template.hull_vertices is None else (template.hull_vertices, template.hull_faces)
        angles = arm_angles(CATEGORIES[category].family) if options.transform is None else (0.0,)
        for degrees in angles:
            lowered = lower_arms(template, body, degrees)
            welded = weld_garment(lowered.template)
            surface = FitSurface(lowered.body_vertices, body.faces, hull)
            if options.transform is not None:
                placed = options.transform @ np.linalg.inv(source.to_canonical)
                alignment = naming_only(vertices, faces, loops, CATEGORIES[category], placed, welded)
            else:
                alignment = align_to_template(vertices, faces, loops, CATEGORIES[category], welded.vertices,
                                              welded.faces, welded.lines, surface, fit_scale=options.fit_scale)
            tried.setdefault(category, []).append((alignment, lowered, surface))
        tried[category].sort(key=lambda placement: placement[0].distance)
    category = min(tried, key=lambda c: tried[c][0][0].distance)
    candidates = [(alignment, lowered, surface, False) for alignment, lowered, surface in tried[category][:REGISTERED_POSES]]
    for alignment, _, _, _ in candidates:
        if options.transform is None and not SCALE_RANGE[0] < alignment.estimated_scale < SCALE_RANGE[1]:
            raise DartsInputError(path, f"would need scaling by {alignment.estimated_scale:g} or beyond to fit the body "
                                        f"(at most {SCALE_RANGE[0]}-{SCALE_RANGE[1]}): check --units")
    if options.transform is None:
        best, lowered, surface, _ = candidates[0]
        say("placing the mesh on its openings' fitted edit")
        candidates.append((placed_on_edit(best, vertices, lowered.template, surface, best.line_targets), lowered, surface,
                           True))
    registered = []  # (two-way mean, alignment, lowered, placed mesh, dart, fit, distances, on the edit) per placement
    for alignment, lowered, surface, on_edit in candidates:
        say(f"registering the {category} template onto the mesh" + (f", arms lowered {lowered.degrees:g} deg"
                                                                     if lowered.degrees else ""))
        placed = apply_matrix(alignment.matrix, vertices)
        dart, fit, distances = register_template(lowered.template, body, placed, faces, alignment.line_targets, surface)
        registered.append((fit["dart_to_mesh"]["mean_mm"] + fit["mesh_to_dart"]["mean_mm"], alignment, lowered, placed,
                           dart, fit, distances, on_edit))
    _, alignment, lowered, placed, posed, fit, distances, on_edit = min(registered, key=lambda r: r[0])
    template = replace(posed, vertices=lowered.rest(posed.vertices).astype(np.float32))
    dart = template
    if options.own_mesh:
        say("cutting the mesh into the template's panels")
        dart, moved = dart_from_mesh(posed, placed, faces, alignment.lines, fit_surface(template, body), lowered)
        fit = {**fit, "moved_out_of_body": {**distance_stats(moved), "share": float((moved > 0).mean())}}
    transform = alignment.matrix @ source.to_canonical
    report = {"source": os.fspath(path), "category": category,
              "category_guess": None if options.category else {c: 1e3 * t[0][0].distance for c, t in tried.items()},
              "transform": transform.tolist(), "scale": alignment.scale,
              "estimated_scale": alignment.estimated_scale,
              "placement": "--transform" if options.transform is not None else
                           "aligned to the template's openings" + (", then to their fitted edit's shape" if on_edit else ""),
              "placement_distance_mm": 1e3 * alignment.distance, "folded_lines": list(alignment.folded),
              "arms_lowered_degrees": lowered.degrees,
              "notes": notes + [f"the {name} opening lies on the garment's own surface (a collar's edge?): placed by the "
                                "template's line put on its surface, and not a target of the registration"
                                for name in alignment.folded],
              "mesh": {"vertices": len(vertices), "faces": len(faces), "openings": len(loops)},
              "dart_surface": "the file's mesh" if options.own_mesh else "the registered template", **fit}
    return ImportResult(dart, report, placed, faces, template=template, distances=distances)
