"""Exporters of simulation results: animated USD (``usd``) and OBJ/PLY frame sequences (``sequence``)."""
