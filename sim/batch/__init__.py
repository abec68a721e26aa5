"""``darts batch``: many ``darts-sim`` runs from one SPEC, on Ray (``darts.jobs``)."""
