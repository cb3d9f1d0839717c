"""The simulated deburring cell (a layer above ``control``; below
``runs``): the plant's truth and the diagram that closes the paper's loops
around it.

- ``robot``, ``arm``, ``models``: the arm from a model file (or a shipped
  one), its cutter, inverse kinematics; ``reach``: the part within reach;
- ``edge``: the edge as configured (the real and the believed part);
  ``part``, ``tube_mesh``: the compliant hydroelastic part and its meshes;
  ``plant``: the MultibodyPlant with robot, friction and part;
  ``truth``: the plant's contact truth measured on that part;
- ``process``: the cutting process (3) and the burrs; ``sensor``: the
  wrist force sensor; ``faults``, ``friction``, ``guards``;
- ``diagram``: :func:`~deburr_drake.cell.diagram.make_deburring_diagram`;
  ``meshcat``: the cell drawn in Meshcat.

Imports ``control``, ``math`` and ``config``; never what runs or reports."""
