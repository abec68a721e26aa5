"""The Constrained Rigid Deformation Layer (paper, Sec. 3) and its targets; see docs/crdl.md."""
