"""Garment meshes made elsewhere (OBJ, PLY, STL, glTF, USD) as DARTs: ``darts import``."""
