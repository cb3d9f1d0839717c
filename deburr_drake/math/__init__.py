"""Pure math, no Drake: the B-spline fuzzy rule base (``fuzzy``), the
edge geometry (``geometry``: contours, normals, arc positions) and the
metrics over arrays (``metrics``). The ground layer: every other layer
(``config`` too) may import it, it imports nothing of the package (the
layer contract in pyproject.toml holds it, and that it imports no
``pydrake``)."""
