"""The templates' default sizes (metres), apart from the code that builds them so that a
command's --help can name them without loading it."""

DEFAULT_EDGE_LENGTH = 0.011  # metres: a short-sleeve top gets about 6k vertices on the default body
#: metres: the templates of the reconstruction dataset and of ``darts reconstruct`` (2-4k vertices;
#: a 224 px picture resolves about 7 mm)
DATASET_EDGE_LENGTH = 0.02
#: metres: the edge lengths a template can be cut at (finer runs out of memory, coarser loses the body's shape)
EDGE_LENGTH_RANGE = (0.003, 0.1)
DEFAULT_EASE = 0.006  # metres between the body and the template along the body normal (skirts, trousers' waistbands)
#: metres: tops' and dresses' ease, a wearing ease (room to raise the arms and bend): cut at 6 mm the
#: short-sleeve top stretched 18.7 % (p99) squatting and crossed itself 162 edges deep; at this ease
#: 13.5 % and 116 (docs/simulation.md, table 1)
WEARING_EASE = 0.012
#: metres: the ease of the reconstruction's templates (its datasets, ``darts reconstruct``), every
#: category alike: its networks were trained on templates cut this close
DATASET_EASE = DEFAULT_EASE
#: metres: the eases a template can be cut at (its ease and a trousers' seat ease)
EASE_RANGE = (0.0, 0.05)
#: metres: trousers' sitting allowance, their ease below the waistband (which keeps ``DEFAULT_EASE``):
#: cut at 6 mm the long pants stretch 34 % (p99) sitting and squatting on the default body; cut with
#: this room they stay under 15 % (docs/simulation.md, "strain-waist")
SEAT_EASE = 0.03
#: metres below the waist line over which trousers' ease grows from ``DEFAULT_EASE`` to ``SEAT_EASE``
SEAT_EASE_TAPER = 0.12
#: metres from the crotch point over which trousers' ease grows from ``DEFAULT_EASE`` to ``SEAT_EASE``
#: (offset 3 cm there, the inseams' two sides met and left edges no sliver pass could remove)
CROTCH_EASE_TAPER = 0.08
