"""The solver's cloth model built from a DART: particles, masses, constraints per seam regime."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from darts.dart.io import load_dart
from darts.geometry.mesh import edge_manifold
from sim.engine.model import SHORT_EDGE_FRACTION, cloth_model, dihedral_angles

GARMENTS = Path(__file__).parents[1] / "scenes" / "garments"


@pytest.fixture
def skirt():
    return load_dart(GARMENTS / "short-skirt.npz")


@pytest.fixture(scope="module")
def skirt_with_slivers(body):
    """The short skirt built the way DARTs were before the builder removed slivers (a DART made
    elsewhere may look like this): the seams' sub-millimetre edges left in."""
    from darts.dart.build import make_dart
    from darts.templates import build

    original = build.remove_slivers
    build.remove_slivers = lambda vertices, faces, seams, min_length: (vertices, faces, seams, None)
    try:
        return make_dart("short-skirt", body)
    finally:
        build.remove_slivers = original


def test_stiff_seams_spring_every_pair_and_short_edges_collapse(skirt_with_slivers):
    skirt = skirt_with_slivers
    model = cloth_model(skirt)
    assert len(model.springs) == len(skirt.pairs)
    # Seam pairs still meet exactly at rest; short edges off the seams collapse (those between two
    # seam ends stay: collapsing one would have to collapse its partner too).
    assert np.array_equal(model.rest[model.springs[:, 0]], model.rest[model.springs[:, 1]])
    assert len(skirt.vertices) - 100 < len(model.rest) < len(skirt.vertices)
    sides = np.concatenate([skirt.faces[:, [0, 1]], skirt.faces[:, [1, 2]], skirt.faces[:, [2, 0]]])
    edges = np.unique(np.sort(sides, 1), axis=0)
    lengths = np.linalg.norm(skirt.vertices[edges[:, 0]] - skirt.vertices[edges[:, 1]], axis=1)
    short = SHORT_EDGE_FRACTION * np.median(lengths)
    assert (model.edge_rest < short).sum() < 0.8 * (lengths < short).sum()
    seam_end = np.isin(np.arange(len(model.rest)), model.springs)
    off_seam = ~(seam_end[model.edges[:, 0]] & seam_end[model.edges[:, 1]])
    assert (model.edge_rest[off_seam] < short).sum() < 0.5 * (lengths < short).sum()
    assert edge_manifold(model.faces) and all(len(set(f)) == 3 for f in model.faces.tolist())
    # Every DART vertex moved by less than the collapse threshold.
    shift = np.linalg.norm(model.rest[model.particle_of_vertex] - skirt.vertices, axis=1)
    assert shift.max() < SHORT_EDGE_FRACTION * np.median(lengths)
    assert np.allclose(model.spring_stiffness, 2000.0) and np.all(model.spring_rest == 0)
    tri = skirt.vertices[skirt.faces].astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    assert np.isclose(model.mass.sum(), skirt.material["density"] * area, rtol=0.01) and model.mass.min() > 0
    assert model.edge_rest.min() > 0 and 0.008 < np.median(model.edge_rest) < 0.014
    # A smooth garment: rest dihedral angles are small.
    assert np.median(np.abs(model.hinge_rest_angle)) < 0.1


def test_welded_seams_merge_their_ends_into_one_particle(skirt):
    skirt.set_seam("all", "welded")
    model = cloth_model(skirt)
    assert len(model.rest) < len(cloth_model(load_dart(GARMENTS / "short-skirt.npz")).rest) and len(model.springs) == 0
    assert np.all(model.particle_of_vertex[skirt.pairs[:, 0]] == model.particle_of_vertex[skirt.pairs[:, 1]])
    assert all(len(set(f)) == 3 for f in model.faces)  # no triangle collapsed
    # Welded panels share edges: the hinges now cross the seams.
    assert len(model.hinges) > len(cloth_model(load_dart(GARMENTS / "short-skirt.npz")).hinges)


def test_partial_and_repulsive_regimes(skirt):
    skirt.set_seam("left_side", "partial")
    skirt.set_seam("right_side", "repulsive", 150.0)
    model = cloth_model(skirt)
    left, right = skirt.seam_names.index("left_side"), skirt.seam_names.index("right_side")
    assert (model.spring_seam == left).sum() == skirt.pair_active[skirt.pair_seam == left].sum() < (skirt.pair_seam == left).sum()
    assert np.all(model.spring_rest[model.spring_seam == right] == 0.02)
    assert np.all(model.spring_stiffness[model.spring_seam == right] == 150.0)


def test_dihedral_angle_of_a_right_angle_fold():
    points = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 0, 1.0]])
    hinge = np.array([[0, 1, 2, 3]])
    assert np.isclose(abs(dihedral_angles(points, hinge)[0]), np.pi / 2)
    flat = points.copy()
    flat[3] = [0.5, -1, 0]
    assert np.isclose(dihedral_angles(flat, hinge)[0], 0.0)


@pytest.mark.parametrize("regime", ["welded", "stiff"])
def test_every_shipped_garment_gives_a_sound_model(regime):
    """Every particle has a mass and every constraint a finite rest state, whichever regime the
    seams take (welding a collar once left a particle with only zero-area faces)."""
    for path in sorted(GARMENTS.glob("*.npz")):
        dart = load_dart(path)
        dart.set_seam("all", regime)
        model = cloth_model(dart)
        assert model.mass.min() > 0, path.stem
        assert np.isfinite(model.hinge_rest_angle).all() and np.isfinite(model.edge_rest).all(), path.stem
        assert np.bincount(model.faces.reshape(-1), minlength=len(model.rest)).min() > 0, path.stem
