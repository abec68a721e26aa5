"""The DART: a template split into panels and re-joined by seam springs, with its material.

Seam regimes (paper, Fig. 1), per seam:

| regime    | springs                                               | defaults                 |
|-----------|-------------------------------------------------------|--------------------------|
| welded    | the two ends become one particle                      | -                        |
| stiff     | zero rest length, high stiffness                      | 2000 N/m                 |
| loose     | zero rest length, low stiffness                       | 20 N/m                   |
| repulsive | pushes the ends apart towards a rest length > 0       | 200 N/m, 0.02 m          |
| partial   | stiff springs on the part [a, b] of the seam only     | 2000 N/m, [0, 0.5]       |

Stiffness is per spring (one per seam pair), in N/m. Vertices are in the body's canonical frame
(Y up), metres.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from darts.errors import DartsInputError

FORMAT = "dart/1"
REGIMES = ("welded", "stiff", "loose", "repulsive", "partial")
DEFAULT_STIFFNESS = {"welded": 0.0, "stiff": 2000.0, "loose": 20.0, "repulsive": 200.0, "partial": 2000.0}
DEFAULT_REST_LENGTH = {"repulsive": 0.02}
DEFAULT_PARTIAL_RANGE = (0.0, 0.5)

#: Material presets: areal density kg/m^2, stretch and bend stiffness, friction, thickness m.
MATERIALS = {
    "cotton": dict(density=0.15, stretch_stiffness=5000.0, bend_stiffness=1e-5, friction=0.4, thickness=0.002),
    "denim": dict(density=0.40, stretch_stiffness=20000.0, bend_stiffness=1e-4, friction=0.5, thickness=0.003),
    "silk": dict(density=0.08, stretch_stiffness=2000.0, bend_stiffness=1e-6, friction=0.2, thickness=0.001),
}
#: What a garment's material may be, [low, high] in SI units: from gauze to heavy leather (density
#: kg/m^2, thickness m), from knit to webbing (stretch N/m), no friction to rubber. Outside these the
#: solver's contact distances (the thickness) or time step (the masses against the stiffness) are
#: not cloth's, and the run fails on its first step instead of at the door.
MATERIAL_RANGES = {
    "density": (1e-3, 10.0), "stretch_stiffness": (1.0, 1e7), "bend_stiffness": (0.0, 1.0), "friction": (0.0, 2.0),
    "thickness": (1e-4, 0.05),
}


@dataclass
class Seam:
    """One named seam's spring settings."""

    name: str
    regime: str = "stiff"
    stiffness: float = DEFAULT_STIFFNESS["stiff"]
    rest_length: float = 0.0
    partial_range: tuple[float, float] = DEFAULT_PARTIAL_RANGE

    def check(self, source=None) -> None:
        if self.regime not in REGIMES:
            raise DartsInputError(source, f"seam '{self.name}': unknown regime '{self.regime}' (one of {', '.join(REGIMES)})")
        if not np.isfinite(self.stiffness) or self.stiffness < 0:
            raise DartsInputError(source, f"seam '{self.name}': stiffness must be >= 0, got {self.stiffness}")
        if not np.isfinite(self.rest_length) or self.rest_length < 0 or (self.regime == "repulsive" and self.rest_length <= 0):
            raise DartsInputError(source,
                                  f"seam '{self.name}': rest length must be >= 0 (> 0 when repulsive), got {self.rest_length}")
        if self.regime not in ("repulsive",) and self.rest_length != 0:
            raise DartsInputError(source, f"seam '{self.name}': a {self.regime} seam has rest length 0, got {self.rest_length}")
        a, b = self.partial_range
        if not (0.0 <= a < b <= 1.0):
            raise DartsInputError(source,
                                  f"seam '{self.name}': partial range must satisfy 0 <= a < b <= 1, got {self.partial_range}")


def seam_with_regime(seam: Seam, regime: str, stiffness: float | None = None) -> Seam:
    """``seam`` switched to ``regime`` with that regime's defaults (and ``stiffness`` if given)."""
    updated = replace(seam, regime=regime,
                      stiffness=DEFAULT_STIFFNESS.get(regime, 0.0) if stiffness is None else float(stiffness),
                      rest_length=DEFAULT_REST_LENGTH.get(regime, 0.0))
    updated.check()
    return updated


@dataclass
class Dart:
    """A DART. Arrays: vertices [V,3] f32, faces [F,3] i32, panel [F] i32, seam pairs [S,2] i32 with
    their seam index [S] and arc position [S] (0..1 along the seam); feature lines as ordered
    vertex loops (passing through both copies where they cross a seam)."""

    category: str
    vertices: np.ndarray
    faces: np.ndarray
    panel: np.ndarray
    panel_names: list[str]
    lines: dict[str, np.ndarray]
    seams: list[Seam]
    pairs: np.ndarray
    pair_seam: np.ndarray
    pair_position: np.ndarray
    body_model: str = "darts-default-v1"
    body_betas: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))
    material_name: str = "cotton"
    material: dict = field(default_factory=lambda: dict(MATERIALS["cotton"]))
    hull_vertices: np.ndarray | None = None
    hull_faces: np.ndarray | None = None
    accessories: list[str] = field(default_factory=list)

    @property
    def seam_names(self) -> list[str]:
        return [s.name for s in self.seams]

    def seam(self, name: str) -> Seam:
        for seam in self.seams:
            if seam.name == name:
                return seam
        raise DartsInputError(None, f"unknown seam '{name}' (seams: {', '.join(self.seam_names)})")

    @property
    def pair_active(self) -> np.ndarray:
        """Which seam pairs carry a spring: all of them, except outside the range of a partial seam."""
        active = np.ones(len(self.pairs), bool)
        for index, seam in enumerate(self.seams):
            if seam.regime == "partial":
                mine = self.pair_seam == index
                a, b = seam.partial_range
                active[mine] = (self.pair_position[mine] >= a) & (self.pair_position[mine] <= b)
        return active

    def set_seam(self, name: str, regime: str, stiffness: float | None = None) -> None:
        """Set the regime of seam ``name`` (or of every seam when ``name`` is 'all')."""
        targets = self.seam_names if name == "all" else [self.seam(name).name]
        self.seams = [seam_with_regime(s, regime, stiffness) if s.name in targets else s for s in self.seams]

    def seam_gaps(self, vertices: np.ndarray | None = None) -> dict[str, dict[str, float]]:
        """Mean and max distance (m) between the two ends of each seam's pairs."""
        vertices = self.vertices if vertices is None else vertices
        gaps = np.linalg.norm(vertices[self.pairs[:, 0]] - vertices[self.pairs[:, 1]], axis=1) if len(self.pairs) else np.zeros(0)
        out = {}
        for index, seam in enumerate(self.seams):
            mine = gaps[self.pair_seam == index]
            out[seam.name] = {"mean": float(mine.mean()) if len(mine) else 0.0, "max": float(mine.max()) if len(mine) else 0.0}
        return out


def parse_seam_setting(text: str) -> tuple[str, str, float | None]:
    """'NAME=REGIME[:STIFFNESS]' -> (name, regime, stiffness or None)."""
    if "=" not in text:
        raise DartsInputError(None, f"--seam expects NAME=REGIME[:STIFFNESS], got '{text}'")
    name, setting = text.split("=", 1)
    regime, _, stiffness = setting.partition(":")
    if regime not in REGIMES:
        raise DartsInputError(None, f"--seam {text}: unknown regime '{regime}' (one of {', '.join(REGIMES)})")
    value = None
    if stiffness:
        try:
            value = float(stiffness)
        except ValueError:
            raise DartsInputError(None, f"--seam {text}: stiffness '{stiffness}' is not a number") from None
        if not np.isfinite(value) or value < 0:
            raise DartsInputError(None, f"--seam {text}: stiffness must be a number >= 0")
    return name.strip(), regime, value


def merged_index(dart: Dart, pairs: np.ndarray) -> np.ndarray:
    """New index of each DART vertex when the two ends of every pair in ``pairs`` [K,2] become one."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    size = len(dart.vertices)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(size, size))
    return connected_components(graph, directed=False)[1]


def welded(dart: Dart) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The garment with every seam pair merged into one vertex (the welded regime applied to all):
    (vertices [W,3], faces [F,3], welded index of each DART vertex [V])."""
    index = merged_index(dart, dart.pairs)
    vertices = np.zeros((index.max() + 1, 3), np.float64)
    vertices[index] = dart.vertices
    return vertices, index[dart.faces], index
