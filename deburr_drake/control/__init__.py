"""The paper's controller as Drake systems (a layer above ``math`` and
``config``; below the cell):

- ``command``: the outer-loop feedrate law at T = 25 ms
  (:class:`~deburr_drake.control.command.CommandGenerator`) and the
  first-order hold (5) (``FirstOrderHold``, R2);
- ``observer``: the chamfer state x_p, n1, n2, delta, |f_n|, |f_t|
  (``ChamferObserver``);
- ``estimator``: the contact parameters c0, c1, c2 (13)-(18)
  (``ContactParameterEstimator``, R3);
- ``controller``: the hybrid position/force controller
  (``HybridController``): everything but the law;
- ``laws``: the inner-loop laws, one per ``controller.kind`` (the paper's
  adaptive fuzzy law (23), (35)-(37) and the baselines), chosen once;
- ``loop``: the loops wired around any plant
  (``add_deburring_controller``);
- ``kinematics``: the tool point's position, velocity and Jacobian
  (``ToolPoint``), shared by the controller and the cell;
- ``layout``: named signal vectors (``CHAMFER_STATE``, ...).

Imports only ``math`` and ``config``; never the cell that simulates the
plant, so a user can wire these systems around a plant of their own."""
