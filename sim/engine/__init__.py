"""The simulator's engine: the cloth model (``model``, static), its state (``state``, per step), the
settings (``settings``), the body as a collider (``collider``, its kernels in ``collider_kernels``),
the garment's self-contact (``self_contact``, its kernels in ``self_contact_kernels``), an outfit's
layers (``layers``), the registered solvers (``solvers/``: a new solver is a new file there, its
kernels beside it), the kernels more than one part uses (``kernels``), launch recording
(``launch``), tethers, colouring, wind, and the frame loop that steps
them (``simulation``: Newton's split, ``Solver.step(state_in, state_out, collider, dt)``).

It knows nothing of runs, files or commands: the application on top of it (``sim.api``, ``sim.run``,
``sim.outfit``, ``sim.quality``, ``sim.body_track``, ``sim.cli``, ``sim.batch``, ``sim.dataset``)
turns garments, motions and options into a model and a body track, runs the frames and writes the
results; ``tests/test_structure.py`` holds the engine below it.
"""
