"""Named layouts of the vector signals between deburr_drake systems (pure
Python, no Drake).

A :class:`VectorLayout` names the blocks of a flat signal vector, so systems,
loggers and metrics read ``layout.get(v, "n1")`` instead of bare indices.
"""

from __future__ import annotations

from typing import Dict, Sequence, Tuple

import numpy as np

__all__ = [
    "VectorLayout",
    "CHAMFER_STATE",
    "CONTROLLER_DIAGNOSTICS",
    "COMMAND_STATE",
]


class VectorLayout:
    """An ordered set of named blocks ``(name, size)`` of a flat vector."""

    def __init__(self, name: str, blocks: Sequence[Tuple[str, int]]):
        self.name = name
        self._slices: Dict[str, slice] = {}
        start = 0
        for block, size in blocks:
            if block in self._slices or size < 1:
                raise ValueError(f"{name}: bad block {block!r} of size {size}")
            self._slices[block] = slice(start, start + size)
            start += size
        self.size = start
        self._scalars = start == len(self._slices)  # every block size 1

    @property
    def blocks(self):
        return tuple(self._slices)

    def slice(self, block: str) -> slice:
        return self._slices[block]

    def get(self, vector, block: str):
        """The block of ``vector`` (scalar blocks come out as scalars); works
        on the last axis of logged arrays too."""
        s = self._slices[block]
        out = vector[..., s]
        return out[..., 0] if s.stop - s.start == 1 else out

    def pack(self, dtype=float, **values) -> np.ndarray:
        """A flat vector from every block, given by name."""
        if values.keys() != self._slices.keys():
            missing = set(self._slices) - set(values)
            extra = set(values) - set(self._slices)
            raise ValueError(
                f"{self.name}.pack: missing {sorted(missing)}, "
                f"unknown {sorted(extra)}"
            )
        if self._scalars:
            try:
                return np.array(
                    [values[block] for block in self._slices], dtype=dtype
                )
            except ValueError:  # a block given as a length-1 array
                pass
        out = np.empty(self.size, dtype=dtype)
        for block, s in self._slices.items():
            out[s] = values[block]
        return out

    def names(self):
        """One name per element: ``x_p[0]``, ..., ``delta``."""
        out = []
        for block, s in self._slices.items():
            n = s.stop - s.start
            out += [block] if n == 1 else [f"{block}[{i}]" for i in range(n)]
        return out

    def split(self, array) -> Dict[str, np.ndarray]:
        """All blocks of ``array`` (vector or rows of samples) by name."""
        return {b: self.get(array, b) for b in self._slices}


#: What ChamferObserver measures (world frame, SI units).
CHAMFER_STATE = VectorLayout(
    "chamfer_state",
    [
        ("x_p", 3),  # m, tool reference point (tip on the cutter axis)
        ("xdot_p", 3),  # m/s
        ("n1", 3),  # unit, into the material (eq. 2)
        ("n2", 3),  # unit, direction of motion (eq. 2, R5)
        ("delta", 1),  # m, chamfer depth (phi < 0 in the material)
        ("delta_dot", 1),  # m/s
        ("f_n", 1),  # N, ||f_n|| = -f . n1
        ("f_t", 1),  # N, ||f_t|| = -f . n2
        ("arc_position", 1),  # m, of the projection on the contour, [0, L)
        (
            "n1_rate",
            3,
        ),  # 1/s, dn1/dt = (dn1/dx_p) xdot_p (the edge's curvature)
    ],
)

#: The outer loop's discrete state.
COMMAND_STATE = VectorLayout(
    "command_state",
    [
        ("x_c", 3),  # m, x_c(kT) on the zero-depth contour (R6)
        ("feed", 1),  # m/s, commanded feed speed v of the feedrate law
        ("arc_position", 1),  # m, unwrapped arc position of x_c
    ],
)

#: What HybridController reports besides its actuation.
CONTROLLER_DIAGNOSTICS = VectorLayout(
    "controller_diagnostics",
    [
        ("x_pd", 3),  # m, (9)
        # e, s, f_tau, u_fuzzy, zeta: on the controller's task axes (the
        # world's unless the contour's frame turns)
        ("e", 3),  # m, x_pd - x_p
        ("s", 3),  # m/s, edot + lambda e
        ("delta_d", 1),  # m, (7)
        ("e_f", 1),  # N, ||f_nd hat|| - ||f_n||
        ("f_tau", 3),  # N, task-space command (36)
        ("u_fuzzy", 3),  # N, zeta u_f + (1 - zeta) H_bar per task axis
        ("zeta", 3),  # 1 where the fuzzy law is active (37)
    ],
)
