"""Baseline controllers of the paper's comparisons (issue 11): the robust law
(22), the ideal law (12) with the true model, impedance control at constant
feed (ref. [2]) and stiff position control, selected by
``controller.kind``; the laws' terms are in :mod:`.laws` and run inside the
shared :class:`deburr_drake.controller.HybridController`. ``compare`` runs
several on one scenario."""

from deburr_drake.baselines.laws import (appendix_gains, impedance_force,
                                         robust_term, sign)

__all__ = ["appendix_gains", "impedance_force", "robust_term", "sign"]
