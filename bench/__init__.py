"""``make bench``: gaitopt's speed and accuracy against baselines measured in the same run.

Kept outside the ``gaitopt`` package (it is not installed with it and never imported by it):
``python -m bench --out results/bench.json`` from the project's root.  Modules: :mod:`bench.run`
(the driver), :mod:`bench.cycles` (gaitopt and the baseline timed), :mod:`bench.drake` (Drake's
runs), :mod:`bench.control` (the deadbeat decision), :mod:`bench.reference` (reference numbers and
goals), :mod:`bench.table` (the printed report), :mod:`bench.common` (shared helpers),
:mod:`bench.baselines` (hand-written SciPy return maps),
:mod:`bench.branches` (continuation and sweeps), :mod:`bench.curves` (two-parameter curves),
:mod:`bench.optimize` (optimal gaits), :mod:`bench.basin` (basin throughput: batch simulation
against the per-start loop).
"""
