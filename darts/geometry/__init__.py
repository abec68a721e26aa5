"""Mesh geometry used to build garments: level-set cuts, boundary loops, remeshing, body distance."""
