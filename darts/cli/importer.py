"""``darts import``: a garment mesh made elsewhere (OBJ, PLY, STL, glTF, USD) as a DART."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from darts.errors import DartsInputError
from darts.fileio import atomic_path, check_input_file, check_output
from darts.meshimport.read import UNITS
from darts.templates.categories import CATEGORIES


def parse_transform(text: str) -> np.ndarray:
    """A 4x4 affine (column vectors: x' = M x) from 16 comma-separated numbers, row by row, or from
    a text file of 4 rows of 4; refused unless finite, with last row 0 0 0 1 and det > 0."""
    source = None
    if "," in text:
        try:
            values = np.array([float(v) for v in text.split(",")])
        except ValueError:
            raise DartsInputError(None, f"--transform: not 16 numbers: {text!r}") from None
    else:
        source = check_input_file(text, "transform file")
        try:
            values = np.loadtxt(source, ndmin=2)
        except ValueError as exc:
            raise DartsInputError(source, f"not 4 rows of 4 numbers ({exc})") from None
    if values.size != 16 or not np.isfinite(values).all():
        raise DartsInputError(source, "--transform must be 16 finite numbers (a 4x4, row by row)")
    matrix = values.reshape(4, 4)
    if not np.allclose(matrix[3], [0, 0, 0, 1]) or np.linalg.det(matrix[:3, :3]) <= 0:
        raise DartsInputError(source, "--transform must be an affine 4x4 (last row 0 0 0 1) that keeps orientation")
    return matrix


#: The colour scale's top of the import picture's distances (mm; issue 47's p95 bar): farther is
#: drawn as this.
PICTURE_MAX_MM = 8.0
#: Beyond this p95 of the mesh's distance to the registered template (mm), the command suggests
#: --own-mesh.
OWN_MESH_HINT_MM = 8.0


def render_import_png(result, path) -> None:
    """Front and side: the mesh as placed on the body coloured by its distance to the registered
    template, the template coloured by its distance to the mesh (0 to ``PICTURE_MAX_MM``, per face
    the mean of its corners'), and the DART's panels (the template is the DART unless
    ``--own-mesh``)."""
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure

    from darts.dart.export import panel_colors
    from darts.render import FRONT, SIDE, draw_mesh

    dart, report = result.dart, result.report
    scale, ramp = Normalize(0.0, PICTURE_MAX_MM), colormaps["viridis"]

    def by_distance(faces, distance):
        return ramp(scale(1e3 * distance[faces].mean(1)))[:, :3]

    template = result.template
    fitted = "DART" if template is dart else "template"  # with --own-mesh the DART is the mesh; the template lent its panels
    views = [(result.placed_vertices, result.faces, by_distance(result.faces, result.distances.mesh_to_dart),
              f"mesh → {fitted}\n" + "mean {mean_mm:.2f}, p95 {p95_mm:.2f} mm".format(**report["mesh_to_dart"])),
             (template.vertices.astype(np.float64), template.faces, by_distance(template.faces, result.distances.dart_to_mesh),
              f"{fitted} → mesh\n" + "mean {mean_mm:.2f}, p95 {p95_mm:.2f} mm".format(**report["dart_to_mesh"])),
             (dart.vertices.astype(np.float64), dart.faces, panel_colors(len(dart.panel_names))[dart.panel],
              f"DART ({dart.category})\npanels")]
    fig = Figure(figsize=(12, 8))
    axes = fig.subplots(2, 3)
    for row, (right, up) in enumerate((FRONT, SIDE)):
        for ax, (vertices, faces, colors, title) in zip(axes[row], views):
            draw_mesh(ax, vertices, faces, colors, right, up, two_sided=True)
            if row == 0:
                ax.set_title(title, fontsize=10)
    axes = axes.reshape(-1)
    span = 1.05 * max(max(np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim())) for ax in axes)
    for ax in axes:  # one scale for every view
        ax.set_xlim(np.mean(ax.get_xlim()) - span / 2, np.mean(ax.get_xlim()) + span / 2)
        ax.set_ylim(np.mean(ax.get_ylim()) - span / 2, np.mean(ax.get_ylim()) + span / 2)
    fig.colorbar(ScalarMappable(scale, ramp), ax=list(axes), shrink=0.6, label="distance to the other surface (mm)")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, bbox_inches="tight", format="png")


def import_mesh(args) -> int:
    from darts.dart.io import save_dart
    from darts.meshimport.pipeline import ImportOptions, import_garment

    check_output(args.output, (".npz",))
    if args.report:
        check_output(args.report, (".json",))
    if args.png:
        check_output(args.png, (".png",))
    transform = None if args.transform is None else parse_transform(args.transform)
    options = ImportOptions(args.category, args.units, args.up, args.prim, transform, args.body, args.betas,
                            args.fit_scale, args.own_mesh)
    quiet = args.quiet
    result = import_garment(args.mesh, options, progress=None if quiet else lambda text: print(f"darts import: {text}"))
    save_dart(result.dart, args.output)
    if args.report:
        with atomic_path(args.report) as tmp:
            Path(tmp).write_text(json.dumps(result.report, indent=1))
    if args.png:
        render_import_png(result, args.png)
    report, dart = result.report, result.dart
    fitted = "template" if args.own_mesh else "DART"
    made = (f"the file's own mesh, {len(dart.vertices)} vertices cut into {len(set(dart.panel.tolist()))} panels "
            f"joined by {len(dart.pairs)} seam pairs; the template that lent them: surface distance") if args.own_mesh \
        else f"{len(dart.vertices)} vertices; surface distance"
    print(f"wrote {args.output}: {report['category']}, {made} mean {report['dart_to_mesh']['mean_mm']:.2f} mm ({fitted} to mesh) "
          f"/ {report['mesh_to_dart']['mean_mm']:.2f} mm (mesh to {fitted}), feature lines within "
          f"{max(v['max_mm'] for v in report['feature_lines'].values()):.1f} mm, {100 * report['inside_body']:.2f} % of "
          f"{fitted} vertices inside the body")
    far = report["mesh_to_dart"]
    places = ", ".join(f"{100 * p['share']:.0f} % over the {p['body_part'].replace('_', ' ')}" for p in far["worst_body_parts"])
    print(f"the mesh's farthest 5 % from the {fitted} ({far['p95_mm']:.1f} mm and beyond, up to {far['max_mm']:.1f} mm): "
          f"{places}; nearest {fitted} panel {far['worst'][0]['panel']}")
    edits = ", ".join(f"{name} {edit['length_cm']:+.1f} / {edit['width_cm']:+.1f}" for name, edit in report["line_edits"].items())
    print(f"its openings against the template's (cm, longer / wider, as `darts deform --edit` takes them): {edits}")
    for note in [] if quiet else report["notes"]:
        print(f"note: {note}")
    if not args.own_mesh and far["p95_mm"] > OWN_MESH_HINT_MM:
        print(f"over 5 % of the mesh lies more than {OWN_MESH_HINT_MM:g} mm from the template (a collar, a pocket, a shape "
              f"it lacks?): --own-mesh keeps the file's own surface")
    return 0


def add_parser(groups, add_body_args) -> None:
    """Register ``darts import``."""
    parser = groups.add_parser(
        "import", help="make a DART from a garment mesh (OBJ, PLY, STL, GLB/GLTF, USD)",
        description="Read a garment mesh made elsewhere, place it on the body, name its openings as feature lines "
                    "and register the category's template onto it with the CRDL: the result keeps the template's "
                    "panels, seams and regimes.")
    parser.add_argument("mesh", metavar="MESH", help="a .obj, .ply, .stl, .glb, .gltf or .usd/.usda/.usdc/.usdz file")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.npz", help="the DART")
    parser.add_argument("--category", choices=sorted(CATEGORIES), help="default: guessed from the openings")
    parser.add_argument("--units", choices=sorted(UNITS), help="the file's unit (default: what the file says, else guessed)")
    parser.add_argument("--up", choices=("y", "z"), help="the file's up axis (default: what the file says, else y)")
    parser.add_argument("--prim", metavar="PATH", help="the USD mesh prim (default: the first mesh)")
    parser.add_argument("--transform", metavar="M", help="4x4 from the file's points to the DART's frame (Y up, metres): "
                                                         "16 comma-separated numbers row by row, or a text file; "
                                                         "replaces the alignment")
    parser.add_argument("--fit-scale", action="store_true",
                        help="resize the garment to the template (one uniform scale; for a garment made for another "
                             "avatar); default: it keeps its size")
    parser.add_argument("--own-mesh", action="store_true",
                        help="the file's own triangles become the DART, cut into the registered template's panels and "
                             "seams (details the template lacks, such as a collar, stay); default: the template "
                             "registered onto the file")
    parser.add_argument("--report", metavar="REPORT.json", help="category, transform, surface distances, line residuals")
    parser.add_argument("--png", metavar="OUT.png", help="before/after picture")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    add_body_args(parser)
    parser.set_defaults(run=import_mesh)
