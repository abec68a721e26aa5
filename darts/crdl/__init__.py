"""The Constrained Rigid Deformation Layer (paper, Sec. 3) and its targets; see docs/crdl.md."""

#: How the CRDL is solved: local-global (ARAP's alternation, fast, the default) or adam (the paper's optimiser).
SOLVERS = ("local-global", "adam")
#: The silhouette terms (``darts.crdl.silhouette.silhouette_term``) and the weight each is used at by
#: default: ``outline`` (distance field and outline matching, ``darts.crdl.outline``: the same cost at
#: any picture size, the default) and ``soft`` (1 - soft IoU of a soft rasteriser: a pixel loop per face).
SILHOUETTE_WEIGHTS = {"outline": 1.0, "soft": 1.0}


def check_silhouette(name: str) -> None:
    """A DartsInputError unless ``name`` is one of the silhouette terms."""
    if name not in SILHOUETTE_WEIGHTS:
        from darts.errors import DartsInputError

        raise DartsInputError(None, f"unknown silhouette term '{name}' (one of {', '.join(SILHOUETTE_WEIGHTS)})")
