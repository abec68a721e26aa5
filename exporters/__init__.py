"""Exporters of simulation results: USD first, then OBJ/PLY sequences and previews. In progress."""
