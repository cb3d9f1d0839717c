"""Registration of a 3-D edge while cutting (pure numpy): what the
contact force along the edge's n1 can tell of a small rigid move of the
part, and the correction it gives on top of the probe's registration.

A 3-D edge's registration is a pose and a size (the probe's,
deburr_drake.math.registration.POSE_REGISTRATION_SIZE: the rotation
vector w, the translation p of x_real = R(w) x + p, the hole's size). The
correction while cutting is a small move e = (v, omega) (m, rad;
:data:`CORRECTION_SIZE` numbers) of the registered edge about the pivot
the registration carries, c' = R(w) c + p, c the believed edge's
(:func:`edge_pivot`, the centroid of its tool path): x -> R(omega) (x -
c') + c' + v (:func:`corrected`).

While cutting, the real edge lies beyond the reference contour along n1
at the tool point x by

    d(x) = n1 . (v + omega x (x - c)) = g(x) . (v, L omega),
    g(x) = (n1, (x - c) x n1 / L),

L the tool path's RMS distance from c (every column in metres): a small
rigid move seen through n1. Along a planar circle g is the first harmonic
(n1 radial: a turn about the centre and a move along the axis show
nothing); along a straight edge the turn about the tool axis is the
heading, and the move along n1 a constant. The force loop cannot tell a
part of d that is the same all along the edge from the contact threshold
c0, so what the force shows is how d varies along the arc.

The force varies along the arc for other reasons too, which no move of
the reference corrects (:func:`nuisance_terms`): a turn of the part
relative to the tool makes the edge rise and fall along the tool axis,
a (x) . (omega x (x - c)), so the cutter's side meets more or less of the
wall (the engaged height, and with it the whole contact law, scales);
and a lean of the tool relative to the edge (the part's turn, the held
tool rotation, the tool's lead) makes the depth grow along the engaged
height, n1 . (beta x a). Around a rim both are first harmonics, as the
move across the axis is; along a straight edge a turn about n1 tilts the
top face along the edge and varies the force linearly, as the heading
does. So the model keeps the translations whose d varies along the arc
by at least 1 / MAX_AMPLIFICATION of their size (RMS over the arc)
beyond what a constant and these nuisances explain, then the turns that
vary by that much beyond those translations as well
(:func:`edge_model`; each by :func:`observable_directions`, the
eigenvectors of the covariance of the residual columns over the arc),
and it estimates the nuisances' shapes with them (:class:`EdgeModel`
``nuisance``) so that the force they make does not pass for a move. What
the force cannot tell apart is left alone, as the planar model leaves the
constant part to c0: around a hole's rim, every move.

- :func:`edge_pivot`, :func:`carried_pivot`, :func:`move_of`,
  :func:`corrected`: the pivot and the correction on a registration.
- :func:`edge_offset_terms`, :func:`nuisance_terms`,
  :func:`edge_contact_regressor`, :func:`edge_registration_of`: the
  online model's regressor and its move.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from deburr_drake.math.geometry import Contour
from deburr_drake.math.rigid import matrix_rotvec, rotvec_matrix

__all__ = [
    "CORRECTION_SIZE",
    "DIRECTION_NAMES",
    "edge_pivot",
    "carried_pivot",
    "move_of",
    "corrected",
    "EdgeModel",
    "edge_offset_terms",
    "nuisance_terms",
    "observable_directions",
    "edge_model",
    "edge_contact_regressor",
    "edge_onset_regressor",
    "edge_registration_of",
]

#: The correction (v_x, v_y, v_z (m), omega_x, omega_y, omega_z (rad)),
#: world axes.
CORRECTION_SIZE = 6

#: The move's six components, in the order of r and of g's columns.
DIRECTION_NAMES = (
    "translation along x",
    "translation along y",
    "translation along z",
    "rotation about x",
    "rotation about y",
    "rotation about z",
)


@functools.lru_cache(maxsize=32)
def _pivot_and_length(contour: Contour, samples: int):
    L = contour.length if math.isfinite(contour.length) else 0.0
    s = np.linspace(0.0, L, samples, endpoint=not contour.closed)
    points = np.array([contour.point_at(x) for x in s])
    c = points.mean(axis=0)
    length = float(np.sqrt(np.mean(np.sum((points - c) ** 2, axis=1))))
    return c, max(length, 1e-9), s, points


def edge_pivot(contour: Contour, samples: int = 256):
    """(c (m, world), L (m)): the centroid of ``contour``'s tool path
    (``samples`` points evenly along it) and the path's RMS distance from
    it. Kept per contour."""
    c, length, _, _ = _pivot_and_length(contour, samples)
    return c.copy(), length


def move_of(correction, pivot):
    """(R, t) with x -> R x + t the move ``correction`` (v, omega) about
    ``pivot``: t = c + v - R c."""
    e = np.asarray(correction, float)
    R = rotvec_matrix(e[3:6])
    c = np.asarray(pivot, float)
    return R, c + e[:3] - R @ c


def carried_pivot(registration, pivot) -> np.ndarray:
    """The believed edge's ``pivot`` (m) where the pose ``registration``
    (w, p, ...) puts it: R(w) c + p."""
    r = np.asarray(registration, float)
    return rotvec_matrix(r[:3]) @ np.asarray(pivot, float) + r[3:6]


def corrected(registration, correction, pivot) -> np.ndarray:
    """The pose registration (w, p, size) that moves the believed edge as
    ``registration`` and then ``correction`` (v, omega) about the pivot it
    carries (:func:`carried_pivot` of ``pivot``); the size is kept."""
    r = np.asarray(registration, float)
    R, t = move_of(correction, carried_pivot(r, pivot))
    out = r.copy()
    out[:3] = matrix_rotvec(R @ rotvec_matrix(r[:3]))
    out[3:6] = R @ r[3:6] + t
    return out


def edge_offset_terms(points, n1, pivot, length) -> np.ndarray:
    """g (N, 6) at tool points ``points`` (N, 3) with normals ``n1``
    (N, 3): d = g . (v, L omega) is how far the edge moved by (v, omega)
    about ``pivot`` lies beyond it along n1, ``length`` = L (m)."""
    x = np.atleast_2d(np.asarray(points, float))
    n = np.atleast_2d(np.asarray(n1, float))
    arm = np.cross(x - np.asarray(pivot, float), n) / length
    return np.column_stack([n, arm])


def nuisance_terms(points, n1, axes, pivot, length) -> np.ndarray:
    """(N, 6) at tool points ``points`` (N, 3) with normals ``n1`` and
    tool axes ``axes`` (N, 3): what else varies the force along the arc,
    per unit turn omega of the part and unit lean beta of the tool
    (rad): the edge's rise along the tool axis, a . (omega x (x - c)) =
    omega . ((x - c) x a) (over ``length`` = L, the engaged height's
    change), and the depth's growth along the engaged height,
    n1 . (beta x a) = beta . (a x n1)."""
    x = np.atleast_2d(np.asarray(points, float))
    a = np.atleast_2d(np.asarray(axes, float))
    rise = np.cross(x - np.asarray(pivot, float), a) / length
    lean = np.cross(a, np.atleast_2d(np.asarray(n1, float)))
    return np.column_stack([rise, lean])


class EdgeModel(NamedTuple):
    """What the online model of a 3-D edge estimates: the pivot c (m) and
    the length L (m) of :func:`edge_offset_terms`, and ``basis`` (6, k):
    columns in (v, L omega), unit translations then unit turns, spanning
    the directions the force along n1 shows beyond what else varies it
    (:func:`edge_model`); ``shown`` (k,): each column's RMS variation of
    d along the arc per metre beyond what the nuisances (and, for a
    turn, the translations) explain. ``nuisance`` (M, j): the shapes along
    the arc of what else varies the force (:func:`nuisance_terms`'
    independent combinations, centred), tabulated at arc positions
    ``arcs`` (M,) over ``period`` (m; 0: an open edge), estimated with
    the move and never applied."""

    pivot: np.ndarray
    length: float
    basis: np.ndarray
    shown: np.ndarray
    arcs: np.ndarray
    nuisance: np.ndarray
    period: float

    def nuisance_at(self, s) -> np.ndarray:
        """The nuisances' shapes (j,) at arc position ``s`` (m)."""
        period = self.period if self.period > 0.0 else None
        return np.array(
            [
                np.interp(float(s), self.arcs, column, period=period)
                for column in self.nuisance.T
            ]
        )

    def names(self) -> list:
        """Per column of ``basis``: its largest components by name (in
        DIRECTION_NAMES), e.g. ``translation along x 0.71, ...``."""
        out = []
        for column in self.basis.T:
            order = np.argsort(-np.abs(column))
            big = [k for k in order if abs(column[k]) >= 0.3]
            out.append(
                ", ".join(f"{DIRECTION_NAMES[k]} {column[k]:+.2f}" for k in big)
            )
        return out


def observable_directions(g, min_shown: float):
    """(basis (6, k), shown (k,)) from the rows of g (N, 6) over the arc:
    the eigenvectors of g's covariance whose RMS variation of d along the
    arc per unit move (the square root of the eigenvalue) is at least
    ``min_shown``, largest first. A direction whose d is the same all
    along the arc (or zero) is not among them: the force cannot tell it
    from the contact threshold."""
    g = np.asarray(g, float)
    centred = g - g.mean(axis=0)
    values, vectors = np.linalg.eigh(centred.T @ centred / len(g))
    shown = np.sqrt(np.clip(values, 0.0, None))
    keep = np.flatnonzero(shown >= min_shown)[::-1]
    basis = vectors[:, keep]
    # A sign per column, so the basis does not flip with round-off: its
    # largest component positive.
    signs = np.sign(basis[np.argmax(np.abs(basis), axis=0), range(len(keep))])
    return basis * signs, shown[keep]


def _beyond(columns, explained):
    """``columns`` less their least squares fit by ``explained``."""
    fit, *_ = np.linalg.lstsq(explained, columns, rcond=None)
    return columns - explained @ fit


def edge_model(contour: Contour, min_shown: float, samples: int = 256):
    """The :class:`EdgeModel` of ``contour`` (the believed edge) over
    ``samples`` points along its pass: the shapes of what else varies the
    force (:func:`nuisance_terms`, those varying by ``min_shown``), then
    the translations the force shows beyond a constant and those shapes
    (:func:`observable_directions`), then the turns that show beyond
    those as well: a move is not credited with what the part's turn or
    the tool's lean explain (around a hole's rim nothing is left: a tilt
    raises the rim on one side, and the force's first harmonic it makes
    is the hole's move across its axis)."""
    c, length, s, points = _pivot_and_length(contour, samples)
    n1 = np.array([contour.n1(p) for p in points])
    axes = np.array([contour.tool_axis_at(v) for v in s])
    g = edge_offset_terms(points, n1, c, length)
    others = nuisance_terms(points, n1, axes, c, length)
    shapes, _ = observable_directions(others, min_shown)
    nuisance = (others - others.mean(axis=0)) @ shapes
    explained = np.column_stack([np.ones(len(g)), nuisance])
    moves, shown_moves = observable_directions(
        _beyond(g[:, :3], explained), min_shown
    )
    explained = np.column_stack([explained, g[:, :3] @ moves])
    turns, shown_turns = observable_directions(
        _beyond(g[:, 3:], explained), min_shown
    )
    basis = np.zeros((6, moves.shape[1] + turns.shape[1]))
    basis[:3, : moves.shape[1]] = moves
    basis[3:, moves.shape[1] :] = turns
    period = contour.length if contour.closed else 0.0
    return EdgeModel(
        c.copy(),
        length,
        basis,
        np.concatenate([shown_moves, shown_turns]),
        np.asarray(s, float).copy(),
        nuisance,
        float(period),
    )


def edge_contact_regressor(
    model: EdgeModel, contour: Contour, x_p, base=None
) -> np.ndarray:
    """phi with ||f_n|| = phi . theta, theta = (c0, c1, c1 a, b) (N, N/m,
    N per metre of a, N per unit of the nuisances' shapes), at the tool
    point ``x_p`` (m) on the reference ``contour`` (the believed edge
    moved by the pose registration ``base``, whose pivot it carries):
    ||f_n|| = c0 + c1 (delta_0 - d) + b . q(s), d = g . B a, q the
    nuisances' shapes at the tool point's arc position s."""
    x_p = np.asarray(x_p, float)
    pivot = model.pivot if base is None else carried_pivot(base, model.pivot)
    g = edge_offset_terms(x_p, contour.n1(x_p), pivot, model.length)[0]
    return np.concatenate(
        [
            [1.0, float(contour.depth(x_p))],
            -(g @ model.basis),
            model.nuisance_at(contour.arc_position(x_p)),
        ]
    )


def edge_onset_regressor(
    model: EdgeModel, contour: Contour, x_p, depth_at_detection=0.0, base=None
) -> np.ndarray:
    """phi with 0 = phi . theta where contact first comes: the real depth
    there is ``depth_at_detection`` (m), so no c0, and no force for the
    nuisances to vary."""
    phi = edge_contact_regressor(model, contour, x_p, base)
    phi[0] = 0.0
    phi[1] -= depth_at_detection
    phi[2 + model.basis.shape[1] :] = 0.0
    return phi


def edge_registration_of(model: EdgeModel, params) -> np.ndarray:
    """(v, omega) of the online model's ``params`` (c0, c1, c1 a, b): B a
    in (v, L omega); zero while c1 is not positive."""
    c1 = float(params[1])
    if not c1 > 0.0:
        return np.zeros(CORRECTION_SIZE)
    k = model.basis.shape[1]
    move = model.basis @ (np.asarray(params[2 : 2 + k], float) / c1)
    return np.concatenate([move[:3], move[3:] / model.length])
