"""The Constrained Rigid Deformation Layer (paper, Sec. 3) and its targets; see docs/crdl.md."""

#: How the CRDL is solved: local-global (ARAP's alternation, fast, the default) or adam (the paper's optimiser).
SOLVERS = ("local-global", "adam")
