"""Running the cell and reporting a run (a layer above ``cell``; below
the capabilities ``analysis``, ``sweep`` and the command line):

- ``simulation``: :func:`~deburr_drake.runs.simulation.simulate` (stop
  reasons, logs that are never lost) and the ``RunLog``;
- ``pass_metrics``: a pass's metrics, one function per family;
  ``report``: logs.npz and metrics.json;
- ``figures`` (the paper's Figs. 8-12), ``replay`` (the HTML replay),
  ``graphs`` (the diagram as GraphViz);
- ``demo`` (the point-mass testbed), ``envelope`` (the tall-burr
  envelope), ``compare`` (the paper's controllers on one scenario)."""
