"""``darts template``, ``darts inspect`` and ``darts export``: making, describing and exporting DARTs."""
from __future__ import annotations

import json

import numpy as np

from darts.api import load_garment
from darts.dart.accessories import ACCESSORIES
from darts.dart.export import MESH_FORMATS, export_mesh, panel_colors
from darts.dart.model import MATERIALS, Dart, parse_seam_setting
from darts.errors import DartsInputError
from darts.fileio import atomic_path, check_output
from darts.geometry.mesh import loop_length, vertex_normals
from darts.shipped import garment_help
from darts.templates.categories import CATEGORIES
from darts.templates.defaults import DEFAULT_EASE, DEFAULT_EDGE_LENGTH, SEAT_EASE, WEARING_EASE


def template(args) -> int:
    if args.list:
        print("\n".join(CATEGORIES))
        return 0
    if args.category is None or args.output is None:
        raise DartsInputError(None, "darts template needs CATEGORY and -o OUT.npz (or --list)")
    if args.category not in CATEGORIES:
        raise DartsInputError(None, f"unknown category '{args.category}' (see 'darts template --list')")
    from darts import api

    check_output(args.output, (".npz",))
    for text in args.seam:
        parse_seam_setting(text)  # refused before the body loads
    dart = api.template(args.category, args.body, args.betas, args.edge_length, args.seam, args.accessory, args.material,
                        args.seat_ease, args.ease)
    api.save_garment(dart, args.output)
    print(f"wrote {args.output}: {args.category}, {len(dart.vertices)} vertices, {len(dart.faces)} faces, "
          f"{len(dart.panel_names)} panels, {len(dart.seams)} seams, {len(dart.pairs)} seam pairs")
    return 0


def summary(dart: Dart) -> dict:
    """Counts, panels, seams with regimes, feature lines with lengths (metres)."""
    counts = np.bincount(dart.pair_seam, minlength=len(dart.seams))
    active = np.bincount(dart.pair_seam, weights=dart.pair_active, minlength=len(dart.seams))
    gaps = dart.seam_gaps()
    return {
        "category": dart.category, "vertices": len(dart.vertices), "faces": len(dart.faces),
        "body_model": dart.body_model, "material": dart.material_name, "accessories": dart.accessories,
        "panels": {name: int((dart.panel == i).sum()) for i, name in enumerate(dart.panel_names)},
        "seams": {s.name: {"regime": s.regime, "stiffness": s.stiffness, "rest_length": s.rest_length,
                           "pairs": int(counts[i]), "active_pairs": int(active[i]), "max_gap": gaps[s.name]["max"]}
                  for i, s in enumerate(dart.seams)},
        "lines": {name: {"vertices": len(loop), "length_m": round(loop_length(dart.vertices.astype(np.float64), loop), 4)}
                  for name, loop in dart.lines.items()},
    }


def render_png(dart: Dart, path) -> None:
    """Front and back views, panels coloured, feature lines drawn in colour and seam pairs as black
    dots where they face the viewer, one legend for all; the figure takes the garment's proportions."""
    from matplotlib import colormaps
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Rectangle

    from darts.render import BACK, FRONT, draw_mesh

    palette = panel_colors(len(dart.panel_names))
    vertices = dart.vertices.astype(np.float64)
    normals = vertex_normals(vertices, dart.faces.astype(np.int64))
    width = max(np.ptp(vertices @ right) for right, _ in (FRONT, BACK))
    height = np.ptp(vertices @ FRONT[1])
    entries = len(dart.panel_names) + len(dart.lines) + 1
    title, legend = 0.4, 0.25 * -(-entries // 6) + 0.2  # inches above and below the views
    view = 4.8 * height / width  # inches: each view 4.8 in wide, as tall as the garment's proportions
    fig = Figure(figsize=(10, view + title + legend))
    fig.subplots_adjust(left=0.01, right=0.99, wspace=0.04, top=1 - title / (view + title + legend),
                        bottom=legend / (view + title + legend))
    axes = fig.subplots(1, 2)
    line_colors = colormaps["Dark2"](np.arange(len(dart.lines)) % 8)
    for ax, (right, up), title in zip(axes, (FRONT, BACK), ("front", "back")):
        draw_mesh(ax, vertices, dart.faces, palette[dart.panel], right, up, two_sided=True)
        facing = normals @ np.cross(right, up) > 0
        for color, loop in zip(line_colors, dart.lines.values()):
            loop = np.asarray(loop)
            segments = np.stack([loop, np.roll(loop, -1)], 1)
            segments = segments[facing[segments].all(1)]
            ax.add_collection(LineCollection(np.stack([vertices[segments] @ right, vertices[segments] @ up], -1),
                                             colors=[color], linewidths=2.0))
        ends = dart.pairs[:, 0]
        ends = ends[facing[ends]]
        ax.scatter(vertices[ends] @ right, vertices[ends] @ up, s=2, c="k")
        ax.set_title(f"{dart.category} ({title})")
    handles = [Rectangle((0, 0), 1, 1, color=c) for c in palette]
    handles += [Line2D([], [], color=c, linewidth=2.0) for c in line_colors]
    handles.append(Line2D([], [], linestyle="none", marker="o", markersize=3, color="k"))
    labels = dart.panel_names + [f"{name} (line)" for name in dart.lines] + ["seam pairs"]
    fig.legend(handles, labels, loc="lower center", ncol=min(len(handles), 6), fontsize=8, frameon=False)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, bbox_inches="tight", format="png")


def inspect(args) -> int:
    if args.png:
        check_output(args.png, (".png",))
    dart = load_garment(args.garment)
    info = summary(dart)
    if args.png:
        render_png(dart, args.png)
    if args.json:
        print(json.dumps(info, indent=1))
        return 0
    print(f"{info['category']}: {info['vertices']} vertices, {info['faces']} faces, body {info['body_model']}, "
          f"material {info['material']}, accessories {', '.join(info['accessories']) or 'none'}")
    print("panels:  " + ", ".join(f"{k} ({v} faces)" for k, v in info["panels"].items()))
    print("seams:")
    for name, seam in info["seams"].items():
        print(f"  {name:16s} {seam['regime']:9s} stiffness {seam['stiffness']:8.1f} N/m  rest {seam['rest_length']:.3f} m  "
              f"pairs {seam['pairs']:4d} ({seam['active_pairs']} active)  max gap {seam['max_gap'] * 1e3:.2f} mm")
    print("feature lines:")
    for name, line in info["lines"].items():
        print(f"  {name:12s} {line['vertices']:4d} vertices, {line['length_m']:.3f} m")
    if args.png:
        print(f"wrote {args.png}")
    return 0


def export(args) -> int:
    check_output(args.output, MESH_FORMATS)
    dart = load_garment(args.garment)
    export_mesh(dart, args.output)
    print(f"wrote {args.output}: {len(dart.vertices)} vertices, {len(dart.panel_names)} panel colours")
    return 0


def add_parsers(groups, add_body_args) -> None:
    """Register the garment subcommands on the ``darts`` parser."""
    make = groups.add_parser("template", help="build a DART (garment.npz) for a category")
    make.add_argument("category", nargs="?", metavar="CATEGORY", help="a category id (see --list)")
    make.add_argument("-o", "--output", metavar="OUT.npz")
    make.add_argument("--list", action="store_true", help="print the category ids, one per line")
    make.add_argument("--edge-length", type=float, default=DEFAULT_EDGE_LENGTH, metavar="L",
                      help=f"target edge length in metres (default {DEFAULT_EDGE_LENGTH})")
    make.add_argument("--seam", action="append", default=[], metavar="NAME=REGIME[:STIFFNESS]",
                      help="seam regime: welded, stiff, loose, repulsive or partial; NAME 'all' sets every seam")
    make.add_argument("--accessory", action="append", default=[], choices=ACCESSORIES, help="stitch a collar or a tie")
    make.add_argument("--material", default="cotton", choices=sorted(MATERIALS))
    make.add_argument("--ease", type=float, metavar="M",
                      help=f"metres off the body (default: the category's, {WEARING_EASE} for tops and dresses, a "
                           f"wearing ease; {DEFAULT_EASE} for skirts and trousers)")
    make.add_argument("--seat-ease", type=float, metavar="M",
                      help=f"trousers only: metres off the body below the waistband (default {SEAT_EASE}, a sitting "
                           f"allowance; {DEFAULT_EASE} cuts them as close as a skirt)")
    add_body_args(make)
    make.set_defaults(run=template)

    show = groups.add_parser("inspect", help="counts, panels, seams and feature lines of a DART")
    show.add_argument("garment", metavar="GARMENT", help=garment_help())
    show.add_argument("--json", action="store_true", help="print JSON")
    show.add_argument("--png", metavar="OUT.png", help="also draw the garment, panels coloured, seams dotted")
    show.set_defaults(run=inspect)

    out = groups.add_parser("export", help=f"write a DART as a mesh ({', '.join(MESH_FORMATS)}) with panel colours")
    out.add_argument("garment", metavar="GARMENT", help=garment_help())
    out.add_argument("-o", "--output", required=True, metavar="OUT")
    out.set_defaults(run=export)
