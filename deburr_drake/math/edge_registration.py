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
c0, so what the force shows is how d varies along the arc: the
translations whose d varies by at least 1 / MAX_AMPLIFICATION of their
size (RMS over the arc), then the turns that vary by that much beyond
what those translations explain (:func:`edge_model`; each by
:func:`observable_directions`, the eigenvectors of the covariance of
g's columns over the arc). The rest is left alone, as the planar
model leaves the constant part to c0.

- :func:`edge_pivot`, :func:`carried_pivot`, :func:`move_of`,
  :func:`corrected`: the pivot and the correction on a registration.
- :func:`edge_offset_terms`, :func:`edge_contact_regressor`,
  :func:`edge_registration_of`: the online model's regressor and its
  move.
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


class EdgeModel(NamedTuple):
    """What the online model of a 3-D edge estimates: the pivot c (m) and
    the length L (m) of :func:`edge_offset_terms`, and ``basis`` (6, k):
    columns in (v, L omega), unit translations then unit turns, spanning
    the directions the force along n1 shows (:func:`edge_model`);
    ``shown`` (k,): each column's RMS variation of d along the arc per
    metre (a turn's: beyond what the translations explain)."""

    pivot: np.ndarray
    length: float
    basis: np.ndarray
    shown: np.ndarray

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


def edge_model(contour: Contour, min_shown: float, samples: int = 256):
    """The :class:`EdgeModel` of ``contour`` (the believed edge) over
    ``samples`` points along its pass: first the translations the force
    shows (:func:`observable_directions` of g's translation columns), then
    the turns that show beyond them (of the turn columns less their least
    squares fit by a constant and those translations): a turn is not
    credited with what a translation explains (around a hole whose rim
    rises and falls a tilt adds a little to the first harmonic of the
    offset, which is the hole's move)."""
    c, length, s, points = _pivot_and_length(contour, samples)
    n1 = np.array([contour.n1(p) for p in points])
    g = edge_offset_terms(points, n1, c, length)
    moves, shown_moves = observable_directions(g[:, :3], min_shown)
    explained = np.column_stack([np.ones(len(g)), g[:, :3] @ moves])
    fit, *_ = np.linalg.lstsq(explained, g[:, 3:], rcond=None)
    turns, shown_turns = observable_directions(
        g[:, 3:] - explained @ fit, min_shown
    )
    basis = np.zeros((6, moves.shape[1] + turns.shape[1]))
    basis[:3, : moves.shape[1]] = moves
    basis[3:, moves.shape[1] :] = turns
    return EdgeModel(
        c.copy(), length, basis, np.concatenate([shown_moves, shown_turns])
    )


def edge_contact_regressor(
    model: EdgeModel, contour: Contour, x_p, base=None
) -> np.ndarray:
    """phi with ||f_n|| = phi . theta, theta = (c0, c1, c1 a) (N, N/m, N
    per metre of a), at the tool point ``x_p`` (m) on the reference
    ``contour`` (the believed edge moved by the pose registration
    ``base``, whose pivot it carries): ||f_n|| = c0 + c1 (delta_0 - d),
    d = g . B a."""
    x_p = np.asarray(x_p, float)
    pivot = model.pivot if base is None else carried_pivot(base, model.pivot)
    g = edge_offset_terms(x_p, contour.n1(x_p), pivot, model.length)[0]
    return np.concatenate(
        [[1.0, float(contour.depth(x_p))], -(g @ model.basis)]
    )


def edge_onset_regressor(
    model: EdgeModel, contour: Contour, x_p, depth_at_detection=0.0, base=None
) -> np.ndarray:
    """phi with 0 = phi . theta where contact first comes: the real depth
    there is ``depth_at_detection`` (m), so no c0."""
    phi = edge_contact_regressor(model, contour, x_p, base)
    phi[0] = 0.0
    phi[1] -= depth_at_detection
    return phi


def edge_registration_of(model: EdgeModel, params) -> np.ndarray:
    """(v, omega) of the online model's ``params`` (c0, c1, c1 a): B a
    in (v, L omega); zero while c1 is not positive."""
    c1 = float(params[1])
    if not c1 > 0.0:
        return np.zeros(CORRECTION_SIZE)
    move = model.basis @ (np.asarray(params[2:], float) / c1)
    return np.concatenate([move[:3], move[3:] / model.length])
