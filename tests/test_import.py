"""``darts import``: garment meshes made outside the template builder become DARTs that fit them."""
from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from darts.body.segmentation import PART_NAMES
from darts.dart.io import load_dart
from darts.errors import DartsInputError
from darts.meshimport.align import umeyama, umeyama_mirrored
from darts.meshimport.read import read_garment_mesh, triangulate
from darts.meshimport.register import distance_summary
from darts.meshimport.repair import repair_garment_mesh
from scenes import GARMENTS_DIR
from tests.helpers import cone_skirt_obj, remeshed_shirt, write_usd_mesh

#: Y up -> Z up: (x, y, z) -> (x, -z, y).
Y_TO_Z = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])


def _fits(report):
    """The issue's bar: surface mean <= 5 mm, p95 <= 15 mm both ways; lines within 1 cm; <= 1 % inside."""
    for way in ("dart_to_mesh", "mesh_to_dart"):
        assert report[way]["mean_mm"] <= 5 and report[way]["p95_mm"] <= 15, report[way]
    assert max(line["max_mm"] for line in report["feature_lines"].values()) <= 10, report["feature_lines"]
    assert report["inside_body"] <= 0.01
    for way, key in (("dart_to_mesh", "worst"), ("mesh_to_dart", "worst"), ("mesh_to_dart", "worst_body_parts")):
        shares = [place["share"] for place in report[way][key]]
        assert 0 < sum(shares) <= 1 + 1e-9 and shares == sorted(shares, reverse=True), report[way]
    assert {p["body_part"] for p in report["mesh_to_dart"]["worst_body_parts"]} <= set(PART_NAMES)


def test_the_report_says_which_panels_hold_the_farthest_points():
    """The farthest 5 % (at or beyond the 95th percentile) counted by panel, most first, with each
    panel's largest distance in mm."""
    values = np.r_[np.linspace(0.0, 0.001, 90), np.full(7, 0.04), np.full(3, 0.05)]
    panels = np.r_[np.zeros(90, int), np.full(7, 2), np.full(3, 1)]
    summary = distance_summary(values, panels, ["front", "back", "left_sleeve"])
    assert summary["worst"] == [{"panel": "left_sleeve", "share": 0.7, "max_mm": pytest.approx(40.0)},
                                {"panel": "back", "share": 0.3, "max_mm": pytest.approx(50.0)}]
    assert summary["p95_mm"] == pytest.approx(40.0) and summary["max_mm"] == pytest.approx(50.0)


@pytest.fixture(scope="module")
def shirt():
    return remeshed_shirt(load_dart(GARMENTS_DIR / "short-sleeve-top.npz"))


@pytest.mark.slow
def test_a_cone_skirt_of_quads_is_recognised_and_registered(tmp_path, run_darts):
    cone_skirt_obj(tmp_path / "cone.obj")
    code, out, err = run_darts("import", tmp_path / "cone.obj", "-o", tmp_path / "g.npz", "--report", tmp_path / "r.json",
                               "--png", tmp_path / "p.png", "--quiet")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["category"] == "short-skirt" and set(report["category_guess"]) == {"short-skirt", "long-skirt"}
    _fits(report)
    dart = load_dart(tmp_path / "g.npz")
    assert set(dart.lines) == {"waist", "hem"} and len(dart.seams) > 0 and (tmp_path / "p.png").stat().st_size > 10000
    height = {name: dart.vertices[dart.lines[name]][:, 1].mean() for name in ("waist", "hem")}
    assert dart.lines["waist"].size and height["waist"] > height["hem"]


@pytest.mark.slow
@pytest.mark.parametrize("form", ["obj-cm-y", "usd-cm-z"])
def test_a_remeshed_stretched_turned_shirt_in_centimetres_is_registered(form, shirt, tmp_path, run_darts):
    vertices, faces = shirt
    if form == "obj-cm-y":
        path = tmp_path / "shirt.obj"
        trimesh.Trimesh(vertices, faces, process=False).export(path)
        stored = vertices
    else:
        path = tmp_path / "shirt.usda"
        stored = vertices @ Y_TO_Z.T - [0, 0, 10.0]
        write_usd_mesh(path, stored, faces, 0.01, "z", translate=(0, 0, 10.0))
    resize = ["--fit-scale"] if form == "usd-cm-z" else []
    code, _, err = run_darts("import", path, "-o", tmp_path / "g.npz", "--category", "short-sleeve-top",
                             "--report", tmp_path / "r.json", "--quiet", *resize)
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    _fits(report)
    assert report["folded_lines"] == []  # a plain neckline places it
    assert abs(report["estimated_scale"] - 1.0) < 0.1  # the unit found
    if resize:  # stretched 3-6 %: made smaller to fit the template (0.991; 0.973 on the top cut 6 mm off the body)
        assert 0.9 < report["scale"] < 0.995, report["scale"]
    else:  # kept its size
        assert report["scale"] == 1.0
    # The report's transform takes the file's points as stored onto the DART.
    transform = np.asarray(report["transform"])
    placed = stored @ transform[:3, :3].T + transform[:3, 3]
    dart = load_dart(tmp_path / "g.npz")
    from darts.geometry.distance import SurfaceDistance

    distance, _, _ = SurfaceDistance(dart.vertices, dart.faces).query(placed[::20], winding=False)
    assert np.median(np.abs(distance)) < 0.002


@pytest.mark.slow
def test_a_shirt_made_with_the_arms_hanging_is_registered_on_a_template_with_lowered_arms(tmp_path, run_darts):
    """Garment tools export tops in an A-pose: the shipped T-shirt posed by the body's skinning with
    its arms 40 degrees down (welded, metres, Y up) is recognised as a short-sleeve top only once
    the templates' arms are lowered too, fits both ways, and comes back to the rest pose near the
    shirt it was made from."""
    from darts.body.io import load_body
    from darts.dart.model import welded
    from darts.meshimport.pose import lower_arms

    shipped = load_dart(GARMENTS_DIR / "short-sleeve-top.npz")
    hanging = lower_arms(shipped, load_body(), 40.0).template
    vertices, faces, _ = welded(hanging)
    trimesh.Trimesh(vertices, faces, process=False).export(tmp_path / "a-pose.obj")
    code, out, err = run_darts("import", tmp_path / "a-pose.obj", "-o", tmp_path / "g.npz", "--report", tmp_path / "r.json",
                               "--quiet")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["category"] == "short-sleeve-top" and report["arms_lowered_degrees"] in (30.0, 45.0), report
    for way in ("dart_to_mesh", "mesh_to_dart"):
        assert report[way]["mean_mm"] <= 3 and report[way]["p95_mm"] <= 8, report[way]
    dart = load_dart(tmp_path / "g.npz")
    offset = np.linalg.norm(dart.vertices - shipped.vertices, axis=1)
    assert np.mean(offset) < 0.01, np.mean(offset)


@pytest.mark.slow
def test_an_exported_dart_comes_back_where_it_was(tmp_path, run_darts):
    source = GARMENTS_DIR / "short-skirt.npz"
    assert run_darts("export", source, "-o", tmp_path / "s.obj")[0] == 0
    code, _, err = run_darts("import", tmp_path / "s.obj", "-o", tmp_path / "g.npz", "--quiet")
    assert code == 0, err
    before, after = load_dart(source), load_dart(tmp_path / "g.npz")
    assert after.category == before.category and len(after.vertices) == len(before.vertices)
    assert np.linalg.norm(after.vertices - before.vertices, axis=1).max() < 0.002


@pytest.mark.parametrize("case, problem", [
    ("not a mesh", "the mesh is empty"), ("empty", "the mesh is empty"), ("closed", "no boundary"),
    ("category", "a short-pants has 3"), ("100 m", "check --units"), ("pieces", "separate pieces"),
    ("sheet", "has 1 opening;"),
])
def test_bad_meshes_are_one_line(case, problem, tmp_path, run_darts):
    path = tmp_path / "mesh.obj"
    extra = []
    if case == "not a mesh":
        path.write_bytes(bytes(range(256)) * 4)
    elif case == "empty":
        path.write_text("v 0 0 0\nv 1 0 0\n")
    elif case == "closed":
        trimesh.creation.icosphere(2, 0.3).export(path)
    elif case in ("category", "100 m"):
        cone_skirt_obj(path)
        extra = ["--category", "short-pants"] if case == "category" else ["--units", "m"]
        if case == "100 m":
            cone = trimesh.load(path, process=False)
            trimesh.Trimesh(cone.vertices * 160, cone.faces, process=False).export(path)
    elif case == "pieces":
        a, b = trimesh.creation.annulus(0.1, 0.3, 0.4), trimesh.creation.annulus(0.1, 0.3, 0.4)
        b.apply_translation([1.0, 0, 0])
        trimesh.util.concatenate([a, b]).export(path)
    elif case == "sheet":
        trimesh.Trimesh([[0, 0, 0], [0.5, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0]], [[0, 1, 2], [0, 2, 3]]).export(path)
    code, _, err = run_darts("import", path, "-o", tmp_path / "g.npz", "--quiet", *extra)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and problem in lines[0] and str(path) in lines[0], err
    assert not (tmp_path / "g.npz").exists()


def test_polygons_are_fan_triangulated():
    faces = triangulate(np.array([3, 4, 5]), np.arange(12))
    assert faces.tolist() == [[0, 1, 2], [3, 4, 5], [3, 5, 6], [7, 8, 9], [7, 9, 10], [7, 10, 11]]


def test_umeyama_recovers_a_similarity():
    rng = np.random.default_rng(0)
    points = rng.normal(size=(50, 3))
    rotation = Rotation.from_euler("xyz", [10, 40, -20], degrees=True).as_matrix()
    scale, found, shift = umeyama(points, 1.3 * points @ rotation.T + [0.1, 0.2, 0.3])
    assert abs(scale - 1.3) < 1e-9 and np.allclose(found, rotation) and np.allclose(shift, [0.1, 0.2, 0.3])


def test_umeyama_held_rigid_recovers_a_rigid_motion():
    rng = np.random.default_rng(1)
    points = rng.normal(size=(50, 3))
    rotation = Rotation.from_euler("xyz", [-5, 70, 15], degrees=True).as_matrix()
    target = points @ rotation.T + [0.3, -0.1, 0.2] + rng.normal(0, 1e-3, (50, 3))
    scale, found, shift = umeyama(points, target, scale_range=(1.0, 1.0))
    assert scale == 1.0 and np.allclose(found, rotation, atol=2e-3) and np.allclose(shift, [0.3, -0.1, 0.2], atol=2e-3)


def _welded_skirt(edits=()):
    import darts
    from darts.dart.model import welded

    skirt = darts.load_garment("short-skirt")
    garment = darts.deform(skirt, edits=list(edits))[0] if edits else skirt
    vertices, faces = welded(garment)[:2]
    return skirt, np.asarray(vertices, np.float64), faces


def test_a_turned_skirts_mirror_plane_is_found_and_a_lopsided_one_is_not_symmetric():
    """The shipped short skirt turned 12 deg and tilted 2: its left-right plane is found from the
    unturned one (within 0.2 deg, reflected points within 1 mm of the surface); with one half made
    10 % deeper front to back, its reflection lies farther than the alignment's MIRROR_RESIDUAL."""
    from darts.geometry.symmetry import mirror_plane
    from darts.meshimport.align import MIRROR_RESIDUAL

    _, vertices, faces = _welded_skirt()
    turn = Rotation.from_euler("yz", [12, 2], degrees=True)
    turned = turn.apply(vertices) + [0.2, 0.1, -0.3]
    plane = mirror_plane(turned, faces, np.array([1.0, 0.0, 0.0]))
    assert np.degrees(np.arccos(abs(plane.normal @ turn.apply([1.0, 0, 0])))) < 0.2 and plane.residual < 1e-3
    lopsided = vertices * np.where(vertices[:, :1] > 0, [1.0, 1.0, 1.1], 1.0)
    assert mirror_plane(lopsided, faces, np.array([1.0, 0.0, 0.0])).residual > MIRROR_RESIDUAL


def test_umeyama_on_mirror_planes_keeps_them_together():
    """A rigid motion that takes one plane onto the other is recovered exactly; fitted to points moved
    by one that does not, the result still takes the source plane's normal to the target's."""
    from darts.geometry.symmetry import MirrorPlane

    rng = np.random.default_rng(2)
    points = rng.normal(size=(60, 3))
    source = MirrorPlane(Rotation.from_euler("y", 30, degrees=True).apply([1.0, 0, 0]), 0.2, 0.0)
    target = MirrorPlane(np.array([1.0, 0, 0]), -0.1, 0.0)
    rotation = (Rotation.from_euler("x", 15, degrees=True) * Rotation.from_euler("y", -30, degrees=True)).as_matrix()
    shift = np.array([-0.3, 0.5, 0.2])  # x: the plane's offset -0.1 = 0.2 + shift_x
    scale, found, moved = umeyama_mirrored(points, points @ rotation.T + shift, np.ones(60), (source, target), (1.0, 1.0))
    assert scale == 1.0 and np.allclose(found, rotation) and np.allclose(moved, shift)
    off = Rotation.from_euler("xyz", [15, -25, 4], degrees=True).as_matrix()
    _, found, _ = umeyama_mirrored(points, points @ off.T, np.ones(60), (source, target), (1.0, 1.0))
    assert np.allclose(found @ source.normal, target.normal)


def test_a_mirror_plane_moves_with_its_points():
    """A plane carried by a similarity reflects the carried points as the carried reflections:
    S'(M p) = M S(p), for a turn, a shift and a scale of 1.5."""
    from darts.geometry.symmetry import MirrorPlane
    from darts.meshimport.align import apply_matrix, similarity_matrix

    plane = MirrorPlane(Rotation.from_euler("z", 20, degrees=True).apply([1.0, 0, 0]), 0.15, 0.001)
    matrix = similarity_matrix(1.5, Rotation.from_euler("xyz", [10, -35, 5], degrees=True).as_matrix(), [0.3, -0.2, 0.7])
    points = np.random.default_rng(4).normal(size=(20, 3))
    moved = plane.moved(matrix)
    assert np.allclose(moved.reflect(apply_matrix(matrix, points)), apply_matrix(matrix, plane.reflect(points)))
    assert np.isclose(np.linalg.norm(moved.normal), 1.0) and np.isclose(moved.residual, 0.0015)


def test_a_flared_skirt_is_placed_by_its_mirror_plane_not_turned_by_its_flare():
    """Issue 47's round-trip row 9: a short skirt flared 11.8 cm wider, turned 8.5 deg and tilted 2.5,
    was placed turned 7 deg (its round waist does not fix the turn; its flare pairs with the
    narrower template unevenly); its mirror plane put on the template's places it within 0.5 deg."""
    from darts.body.io import load_body
    from darts.crdl.deform import weld_garment
    from darts.crdl.fit import FitSurface
    from darts.meshimport.align import align_to_template
    from darts.templates.categories import CATEGORIES

    skirt, vertices, faces = _welded_skirt(["hem=0.024", "hem_width=0.118"])
    turn = Rotation.from_euler("yx", [8.5, 2.5], degrees=True)
    moved, faces, loops, _ = repair_garment_mesh(turn.apply(vertices) + [0.3, -0.1, 0.1], faces, "skirt")
    template, body = weld_garment(skirt), load_body(None)
    placed = align_to_template(moved, faces, loops, CATEGORIES["short-skirt"], template.vertices, template.faces,
                               template.lines, FitSurface(body.v_template.double().numpy(), body.faces))
    assert np.degrees(Rotation.from_matrix(placed.matrix[:3, :3] @ turn.as_matrix()).magnitude()) < 0.5


@pytest.mark.slow
def test_an_edited_remeshed_garment_in_millimetres_comes_back_at_its_size_and_place(tmp_path, run_darts, monkeypatch):
    """Issue 47's round trip, one garment: the shipped T-shirt with its hem 4.5 cm and sleeves 7.5 cm
    longer (the CRDL), remeshed isotropically, turned 20 deg, moved and written as GLB in
    millimetres (a node scale of 0.001), imports with its category guessed, its size kept (a fitted
    scale made it 7 % smaller) and within 2 mm of the edited garment both ways on average, every
    seam vertex within 2.2 mm of the original's seams, and the report and the output say the edit
    (the hem 4.5 cm, the cuffs 7.5 cm longer, within 3 mm). All loops placing it lifted it 13 mm (the
    longer hem and cuffs pulled towards the template's); a first registration round that was not
    the lines' edit left seams 4.5 mm off, one that pulled the lines to the file's loops by angle
    2.9 mm (the fitted edit: 1.6 mm)."""
    import darts
    from tests.helpers import isotropic_remesh, round_trip_distances

    original, _ = darts.deform(darts.load_garment("short-sleeve-top"), edits=["hem=0.045", "sleeve=0.075"])
    vertices, faces = isotropic_remesh(original, 1.2)
    moved = Rotation.from_euler("y", 20, degrees=True).apply(vertices) + [0.2, -0.3, 0.1]
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.Trimesh(moved / 0.001, faces, process=False), transform=np.diag([0.001] * 3 + [1.0]))
    scene.export(tmp_path / "shirt.glb")
    monkeypatch.setattr("darts.cli.importer.OWN_MESH_HINT_MM", 0.1)  # the hint's bar under this import's p95
    code, out, err = run_darts("import", tmp_path / "shirt.glb", "-o", tmp_path / "g.npz", "--report", tmp_path / "r.json",
                               "--quiet")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["category"] == "short-sleeve-top" and report["scale"] == 1.0, report["category"]
    assert report["mesh_to_dart"]["p95_mm"] > 0.1 and "--own-mesh keeps the file's own surface" in out
    edits = report["line_edits"]  # the registration's fitted edit: the hem 4.5 cm and the cuffs 7.5 cm longer
    assert abs(edits["hem"]["length_cm"] - 4.5) < 0.3 and abs(edits["left_cuff"]["length_cm"] - 7.5) < 0.3
    assert all(abs(edit["width_cm"]) < 0.3 for edit in edits.values()) and "left_cuff +7.5 / " in out, (edits, out)
    measured = round_trip_distances(load_dart(tmp_path / "g.npz"), original)
    for way in ("imported_to_original", "original_to_imported"):
        assert measured[way]["mean_mm"] <= 2.0 and measured[way]["p95_mm"] <= 5.0, measured
    assert measured["seams"]["max_mm"] <= 2.2, measured["seams"]


@pytest.mark.slow
def test_own_mesh_keeps_a_collar_the_template_lacks(tmp_path, run_darts, run_sim):
    """Issue 47, details: a T-shirt built with the collar accessory, remeshed and written in
    centimetres, imported with ``--own-mesh``: its surface comes back whole, collar included (the
    registered template has no collar), cut into the template's four panels with the collar whole, in
    the one it is sewn to (cut at the shoulder line, where it lies over the shoulder seams, its seam
    vertices were 6.6 mm off the original's), and it simulates."""
    import darts
    from tests.helpers import isotropic_remesh, round_trip_distances

    original = darts.template("short-sleeve-top", accessories=["collar"])
    vertices, faces = isotropic_remesh(original, 1.0)
    trimesh.Trimesh(100.0 * vertices, faces, process=False).export(tmp_path / "collar.obj")
    code, _, err = run_darts("import", tmp_path / "collar.obj", "-o", tmp_path / "g.npz", "--own-mesh", "--report",
                             tmp_path / "r.json", "--quiet")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    dart = load_dart(tmp_path / "g.npz")
    assert report["category"] == "short-sleeve-top" and report["dart_surface"] == "the file's mesh"
    assert report["folded_lines"] == ["neckline"]  # its opening there is the collar's edge, lying on the shirt
    assert len(faces) < len(dart.faces) < 1.05 * len(faces)  # the file's triangles, split where a seam crosses
    assert len(dart.panel_names) == 4 and len(dart.pairs) > 100
    measured = round_trip_distances(dart, original)
    for way in ("imported_to_original", "original_to_imported"):  # the shape is the file's, placed by the
        # template's neckline on its surface (5.7 mm off on average anchored on the collar's edge)
        assert measured[way]["mean_mm"] <= 2.0 and measured[way]["p95_mm"] <= 5.0, measured
    from darts.geometry.distance import SurfaceDistance

    collar = original.vertices[original.faces[original.panel == original.panel_names.index("collar")]].mean(1)
    to_dart, _, _ = SurfaceDistance(dart.vertices, dart.faces).query(collar, winding=False)
    assert np.percentile(np.abs(to_dart), 95) < 0.008  # the collar is there
    collar_faces = SurfaceDistance(dart.vertices, dart.faces).closest_faces(collar)[0]
    assert np.bincount(dart.panel[collar_faces]).max() >= 0.98 * len(collar)  # in one panel
    assert measured["seams"]["max_mm"] <= 5.0, measured["seams"]  # the seams where the original's are
    code, _, err = run_sim(tmp_path / "g.npz", "walk", "--frames", "10", "-o", tmp_path / "walk.usdc", "--stats",
                           tmp_path / "s.json", "--quiet")
    assert code == 0, err
    stats = json.loads((tmp_path / "s.json").read_text())
    assert stats["stable"] and stats["max_penetration"] < 0.01, stats


def test_repair_merges_split_seams_and_drops_specks(tmp_path):
    skirt = load_dart(GARMENTS_DIR / "short-skirt.npz")
    speck = trimesh.creation.icosphere(0, 0.002)
    vertices = np.r_[skirt.vertices, speck.vertices + 2.0]
    faces = np.r_[skirt.faces, speck.faces + len(skirt.vertices)]
    repaired, repaired_faces, loops, notes = repair_garment_mesh(vertices, faces, "s.obj")
    from darts.dart.model import welded

    assert len(repaired) == len(welded(skirt)[0]) and len(loops) == 2
    assert any("merged" in n for n in notes) and any("removed 1 small pieces" in n for n in notes)


def test_units_are_guessed_when_the_file_does_not_say(tmp_path):
    cone_skirt_obj(tmp_path / "m.obj")
    mesh = trimesh.load(tmp_path / "m.obj", process=False)
    trimesh.Trimesh(mesh.vertices * 1000, mesh.faces, process=False).export(tmp_path / "mm.obj")
    read = read_garment_mesh(tmp_path / "mm.obj")
    assert np.allclose(read.vertices, mesh.vertices, atol=1e-6) and "guessed" in read.units_note


@pytest.mark.parametrize("suffix", [".ply", ".stl", ".glb"])
def test_every_trimesh_format_reads_to_the_same_surface(suffix, tmp_path):
    cone_skirt_obj(tmp_path / "cone.obj")
    mesh = trimesh.load(tmp_path / "cone.obj", process=False)
    mesh.export(tmp_path / f"cone{suffix}")
    read = read_garment_mesh(tmp_path / f"cone{suffix}")
    vertices, faces, loops, _ = repair_garment_mesh(read.vertices, read.faces, "cone")
    assert len(faces) == len(mesh.faces) and len(loops) == 2  # STL's unshared corners merged again
    assert np.allclose(np.sort(vertices, axis=0), np.sort(np.asarray(mesh.vertices), axis=0), atol=1e-5)


def test_a_usd_prim_is_picked_by_path_with_its_transform(tmp_path):
    cone_skirt_obj(tmp_path / "cone.obj")
    mesh = trimesh.load(tmp_path / "cone.obj", process=False)
    write_usd_mesh(tmp_path / "cone.usda", mesh.vertices * 1000 - [0, 0, 500.0], mesh.faces, 0.001, "y", (0, 0, 500.0))
    read = read_garment_mesh(tmp_path / "cone.usda", prim="/World/Garment")
    assert np.allclose(read.vertices, mesh.vertices, atol=1e-6)
    with pytest.raises(DartsInputError, match="has no mesh at /World/Nothing"):
        read_garment_mesh(tmp_path / "cone.usda", prim="/World/Nothing")


def test_a_non_manifold_mesh_is_refused():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1.0]])
    with pytest.raises(DartsInputError, match="shared by more than two triangles"):
        repair_garment_mesh(vertices, np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]), "m.obj")


@pytest.mark.slow
def test_an_explicit_transform_replaces_the_alignment(tmp_path, run_darts):
    source = GARMENTS_DIR / "short-skirt.npz"
    assert run_darts("export", source, "-o", tmp_path / "s.obj")[0] == 0
    moved = trimesh.load(tmp_path / "s.obj", process=False)
    moved.apply_translation([0.5, 0.0, 0.0])  # the file is 0.5 m off; the transform brings it back
    moved.export(tmp_path / "moved.obj")
    code, _, err = run_darts("import", tmp_path / "moved.obj", "-o", tmp_path / "g.npz", "--category", "short-skirt",
                             "--transform", "1,0,0,-0.5,0,1,0,0,0,0,1,0,0,0,0,1", "--report", tmp_path / "r.json", "--quiet")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["placement"] == "--transform" and np.allclose(np.asarray(report["transform"])[:3, 3], [-0.5, 0, 0])
    assert np.linalg.norm(load_dart(tmp_path / "g.npz").vertices - load_dart(source).vertices, axis=1).max() < 0.002
    code, _, err = run_darts("import", tmp_path / "moved.obj", "-o", tmp_path / "h.npz", "--transform", "1,2,3")
    assert code == 2 and "16 finite numbers" in err and not (tmp_path / "h.npz").exists()


def test_a_mesh_cut_into_the_template_panels_keeps_its_surface_and_the_template_seams():
    """``dart_from_mesh`` on the shipped short-sleeve top's own welded surface (at rest, outside the
    body): the same triangles, cut into the same four panels, every seam of the template between two
    panels carrying pairs of coincident copies, the openings as lines, nothing moved out."""
    from darts.body.io import load_body
    from darts.crdl.deform import fit_surface, weld_garment
    from darts.meshimport.own_mesh import dart_from_mesh

    template = load_dart(GARMENTS_DIR / "short-sleeve-top.npz")
    welded = weld_garment(template)
    dart, moved = dart_from_mesh(template, welded.vertices.astype(np.float64), welded.faces, welded.lines,
                                 fit_surface(template, load_body()))
    assert len(dart.faces) == len(welded.faces) and set(dart.panel.tolist()) == set(range(len(template.panel_names)))
    agree = (np.asarray(dart.panel) == np.asarray(template.panel)).mean()  # welded faces keep the DART's order
    assert agree > 0.97, agree
    gaps = np.linalg.norm(dart.vertices[dart.pairs[:, 0]] - dart.vertices[dart.pairs[:, 1]], axis=1)
    assert gaps.max() < 1e-6 and moved.max() == 0.0
    cross_panel = {template.seams[s].name for s, (a, b) in zip(template.pair_seam, template.pairs)
                   if template.panel[np.flatnonzero((template.faces == a).any(1))[0]]
                   != template.panel[np.flatnonzero((template.faces == b).any(1))[0]]}
    carried = {dart.seams[s].name for s in np.unique(dart.pair_seam)}
    assert cross_panel <= carried, cross_panel - carried
    assert set(dart.lines) == set(template.lines)
    for name, loop in dart.lines.items():  # each line runs through the template's line vertices of its name
        line = template.vertices[template.lines[name]]
        nearest = np.linalg.norm(dart.vertices[loop][:, None] - line[None], axis=2).min(1)
        assert nearest.max() < 1e-6 and len(set(welded.index[template.lines[name]].tolist())) <= len(loop)


def test_lines_are_matched_by_angle_around_their_centre_and_by_arc_length_when_not_star_shaped():
    """A hem let out 5 cm all round (each point moved away from the centre), resampled unevenly and
    starting elsewhere: each template vertex is matched to its own point of the wider hem (within
    1 mm: the chords between the target's vertices), where arc length, whose shares the letting
    out changes, puts them up to 12 mm off. A loop that folds back about its centre (a crescent) is
    matched by arc length."""
    import torch

    from darts.crdl.targets import correspond, correspond_around

    def let_out(phases):
        points = np.stack([0.25 * np.cos(phases), np.zeros(len(phases)), 0.12 * np.sin(phases)], 1)
        return points + 0.05 * points / np.linalg.norm(points, axis=1, keepdims=True)

    angles = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    template = np.stack([0.25 * np.cos(angles), np.zeros(60), 0.12 * np.sin(angles)], 1)
    wider = let_out(np.sort(np.random.default_rng(3).uniform(0, 2 * np.pi, 240))[::-1]) + [0.02, -0.1, 0.01]
    expected = let_out(angles) + [0.02, -0.1, 0.01]
    by_angle = correspond_around(template, wider).points(torch.as_tensor(wider)).numpy()
    by_arc = correspond(template, wider).points(torch.as_tensor(wider)).numpy()
    assert np.abs(by_angle - expected).max() < 1e-3 and np.abs(by_arc - expected).max() > 5e-3
    arc = np.radians(np.linspace(-150, 150, 30))
    crescent = np.r_[np.stack([0.3 * np.cos(arc), np.zeros(30), 0.3 * np.sin(arc)], 1),
                     np.stack([0.25 * np.cos(arc[::-1]), np.zeros(30), 0.25 * np.sin(arc[::-1])], 1)]
    match = correspond_around(template, crescent)
    reference = correspond(template, crescent)
    assert np.array_equal(match.first, reference.first) and np.allclose(match.weight, reference.weight)


def test_an_openings_edit_is_recovered_from_the_loop_alone():
    """A hem shortened 8.3 cm and let out 4.6 cm (``length_and_width_edited``: the two edits
    ``darts.deform`` makes), resampled unevenly, reversed and starting elsewhere: ``fit_loop_edit`` finds both
    amounts within 0.2 mm, and the template loop edited by them is the edited loop vertex for vertex
    (within 0.2 mm), where the target's points closest to the template's lie over 5 mm from their own."""
    from darts.crdl.targets import fit_loop_edit, length_and_width_edited
    from darts.geometry.loops import closest_on_loop

    def ellipse(phases):
        return np.stack([0.09 * np.cos(phases) + 0.1, np.full(len(phases), -0.9), 0.06 * np.sin(phases)], 1)

    def edit(points, length, width):
        return length_and_width_edited(points, length, width, garment_centre)

    garment_centre = np.array([0.0, -0.3, 0.0])
    template = ellipse(np.linspace(0, 2 * np.pi, 26, endpoint=False))
    expected = edit(template, -0.083, 0.046)
    curve = edit(ellipse(np.linspace(0, 2 * np.pi, 400, endpoint=False)), -0.083, 0.046)
    target = np.roll(curve[np.sort(np.random.default_rng(5).choice(400, 150, replace=False))][::-1], 40, axis=0)
    length, width = fit_loop_edit(template, target, garment_centre)
    assert abs(length + 0.083) < 2e-4 and abs(width - 0.046) < 2e-4, (length, width)
    assert np.abs(edit(template, length, width) - expected).max() < 2e-4
    assert np.linalg.norm(closest_on_loop(template, target) - expected, axis=1).max() > 5e-3


def test_trousers_shortened_and_let_out_are_placed_on_their_openings_edit():
    """Issue 47's held-out row 6: long pants 8.3 cm shorter and 4.6 cm wider at the hems. Placed on
    the unedited template they come out millimetres low (the raised hems pull them down); refined on
    the shape of their openings' fitted edit (``placed_on_edit``) they lie within 0.5 mm of where
    the edit put them on average, and closer than the placement alone. On the trousers cut 6 mm off
    everywhere, as they were shipped when this was measured: with the sitting allowance the same
    edit is placed 1.8 mm off and refined to 0.8 mm (docs/import.md)."""
    import darts
    from darts.body.io import load_body
    from darts.crdl.deform import fit_surface, weld_garment
    from darts.dart.build import make_dart
    from darts.dart.model import welded
    from darts.meshimport.align import align_to_template, apply_matrix
    from darts.meshimport.register import placed_on_edit
    from darts.templates.categories import CATEGORIES
    from darts.templates.defaults import DEFAULT_EASE

    body = load_body(None)
    pants = make_dart("long-pants", body, seat_ease=DEFAULT_EASE)
    edited = darts.deform(pants, edits=["hem=-0.083", "hem_width=0.046"])[0]
    vertices, faces = (np.asarray(a) for a in welded(edited)[:2])
    vertices = vertices.astype(np.float64)
    turn = Rotation.from_euler("y", 15, degrees=True)
    moved, faces, loops, _ = repair_garment_mesh(turn.apply(vertices) + [0.2, -0.1, 0.3], faces, "pants")
    template = weld_garment(pants)
    surface = fit_surface(pants, body)
    placed = align_to_template(moved, faces, loops, CATEGORIES["long-pants"], template.vertices, template.faces,
                               template.lines, surface)
    refined = placed_on_edit(placed, moved, pants, surface, placed.lines)

    def off_mm(alignment):  # mean distance of the placed mesh's vertices from the edited garment's, mm
        return 1e3 * np.linalg.norm(apply_matrix(alignment.matrix, moved) - (moved - [0.2, -0.1, 0.3]) @ turn.as_matrix(),
                                    axis=1).mean()

    assert off_mm(refined) <= min(0.5, off_mm(placed)), (off_mm(placed), off_mm(refined))


def test_a_collar_folded_over_the_shirt_is_found_whole_with_its_fold_on_the_neckline():
    """``own_mesh._folded_details`` on a T-shirt built with the collar accessory (welded), against the
    same T-shirt without it: one detail, the collar's triangles (they face against the shirt they lie
    on) and nothing else, its fold the neckline it is sewn to."""
    import darts
    from darts.dart.model import welded
    from darts.meshimport.own_mesh import _folded_details

    shirt = darts.template("short-sleeve-top")
    collared = darts.template("short-sleeve-top", accessories=["collar"])
    vertices, faces, index = welded(collared)
    collar_vertex = np.zeros(len(vertices), bool)
    collar_vertex[index[np.asarray(collared.faces)[collared.panel == collared.panel_names.index("collar")]]] = True
    neckline = np.zeros(len(vertices), bool)
    neckline[np.unique(index[np.asarray(shirt.lines["neckline"])])] = True  # the shirt's vertices come first
    details = _folded_details(shirt, np.asarray(vertices, np.float64), np.asarray(faces))
    assert len(details) == 1
    inside, fold = details[0]
    assert not (inside & fold).any() and not (inside & ~collar_vertex).any()
    assert np.array_equal(fold, neckline)
    assert inside.sum() == collar_vertex.sum() - neckline.sum()
