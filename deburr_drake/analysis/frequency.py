"""The normal-force loop in the frequency domain: its discrete-time loop
transfer function at the operating point (with the sample and hold of the
2.5 ms loop), gain and phase margins, Bode and Nyquist plots
(python-control).

The loop is broken where the controller reads the measured force along
n1 (the normal force of (7) and the -f of (36)). From the one-period map
Phi of :func:`deburr_drake.analysis.sampled_loop`, whose state holds the
sensor's filter y: a change of y reaches the next period through the
sensor's own filter, exactly (1 - alpha) y (y += alpha (raw - y)), and
through everything that reads it; so the input column of the loop is
b = (Phi[:, y] - (1 - alpha) I_y) n1, the open loop
Phi_ol = Phi - b c, c = n1^T y, and the loop transfer function in
negative-feedback form is L(z) = -c (z I - Phi_ol)^-1 b: closing it gives
Phi back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from deburr_drake.analysis.sampled import SampledLoop

__all__ = [
    "NormalForceLoop",
    "normal_force_loop",
    "loop_from_map",
    "frequency_response",
    "margins",
    "plot_bode_nyquist",
]


@dataclass
class NormalForceLoop:
    loop: object  # control.StateSpace, discrete (dt = the period)
    gain_margin_dB: float
    phase_margin_deg: float
    phase_crossover_hz: float
    gain_crossover_hz: float
    # max |eig| of the open loop: the margins read as usual when it is
    # <= 1 (delta_d's integrator puts one eigenvalue at z = 1)
    open_loop_spectral_radius: float = float("nan")


def frequency_response(loop, f) -> np.ndarray:
    """L(e^{j 2 pi f T}) of a discrete single-input single-output
    state-space loop at frequencies ``f`` (Hz)."""
    A, B, C, D = (np.asarray(m) for m in (loop.A, loop.B, loop.C, loop.D))
    I = np.eye(A.shape[0])
    z = np.exp(1j * 2 * np.pi * np.asarray(f, float) * loop.dt)
    return np.array(
        [(C @ np.linalg.solve(zk * I - A, B) + D)[0, 0] for zk in z]
    )


def margins(f, L):
    """(gain margin dB, phase margin deg, phase-crossover Hz, gain-crossover
    Hz) of a loop response ``L`` sampled at increasing frequencies ``f``
    (Hz), by interpolating the crossings on the grid: the smallest margins
    over all crossings (inf where there is none). Computed here rather than
    by ``control.stability_margins``, whose root-finding falls back to an
    inaccurate method on these loops (an integrator, delta_d, at z = 1)."""
    mag = np.abs(L)
    phase = np.degrees(np.unwrap(np.angle(L)))
    gm, f_pc = np.inf, np.nan
    # Phase crossings of -180 + k 360.
    k = np.floor((phase + 180.0) / 360.0)
    for i in np.flatnonzero(np.diff(k) != 0):
        level = 360.0 * max(k[i], k[i + 1]) - 180.0
        a = (level - phase[i]) / (phase[i + 1] - phase[i])
        m = mag[i] + a * (mag[i + 1] - mag[i])
        if -20 * np.log10(m) < gm:
            gm, f_pc = (
                float(-20 * np.log10(m)),
                float(f[i] + a * (f[i + 1] - f[i])),
            )
    # At the Nyquist frequency a discrete loop is real: on the negative
    # real axis it touches -180 there without crossing.
    wrapped = (phase[-1] + 180.0) % 360.0
    if min(wrapped, 360.0 - wrapped) < 1e-6 and -20 * np.log10(mag[-1]) < gm:
        gm, f_pc = float(-20 * np.log10(mag[-1])), float(f[-1])
    pm, f_gc = np.inf, np.nan
    above = mag > 1.0
    for i in np.flatnonzero(np.diff(above.astype(int)) != 0):
        a = (0.0 - np.log(mag[i])) / (np.log(mag[i + 1]) - np.log(mag[i]))
        ph = phase[i] + a * (phase[i + 1] - phase[i])
        margin = (ph + 180.0 + 180.0) % 360.0 - 180.0
        if abs(margin) < abs(pm):
            pm, f_gc = float(margin), float(f[i] + a * (f[i + 1] - f[i]))
    return gm, pm, f_pc, f_gc


def loop_from_map(Phi, b, c, period: float) -> NormalForceLoop:
    """L(z) = -c (zI - (Phi - b c))^-1 b and its margins."""
    import control

    b = np.asarray(b, float).reshape(-1, 1)
    c = np.asarray(c, float).reshape(1, -1)
    loop = control.ss(Phi - b @ c, b, -c, np.zeros((1, 1)), dt=period)
    f = np.logspace(-3, np.log10(0.5 / period), 4000)
    gm, pm, f_pc, f_gc = margins(f, frequency_response(loop, f))
    return NormalForceLoop(
        loop=loop,
        gain_margin_dB=gm,
        phase_margin_deg=pm,
        phase_crossover_hz=f_pc,
        gain_crossover_hz=f_gc,
        open_loop_spectral_radius=float(
            np.max(np.abs(np.linalg.eigvals(np.asarray(loop.A))))
        ),
    )


def normal_force_loop(
    sampled: SampledLoop, *, direction=None
) -> NormalForceLoop:
    """The normal-force loop of a sampled loop's map (module docstring);
    ``direction`` (unit, world) breaks the loop of another force component
    instead of n1 (e.g. n2: the tangential loop, where the -f of (36)
    cancels the cutting force's damping g of (3))."""
    Phi = sampled.Phi
    n = Phi.shape[0]
    rows = sampled.sensor_rows
    e_y = np.zeros((n, 3))
    e_y[rows, :] = np.eye(3)
    d = sampled.n1 if direction is None else np.asarray(direction, float)
    b = (Phi[:, rows] - (1 - sampled.sensor_alpha) * e_y) @ d
    c = e_y @ d
    return loop_from_map(Phi, b, c, sampled.period)


def plot_bode_nyquist(result: NormalForceLoop, path, *, title: str = ""):
    """Bode (magnitude, phase) and Nyquist plots of L(e^{jwT}) up to the
    Nyquist frequency, in one PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f = np.logspace(-2, np.log10(0.5 / result.loop.dt), 600)
    L = frequency_response(result.loop, f)
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    axes[0].semilogx(f, 20 * np.log10(np.abs(L)))
    axes[0].axhline(0, color="k", lw=0.5)
    axes[0].set(xlabel="frequency (Hz)", ylabel="|L| (dB)", title="Bode")
    if np.isfinite(result.phase_crossover_hz):
        axes[0].axvline(result.phase_crossover_hz, color="r", lw=0.5)
    axes[1].semilogx(f, np.degrees(np.unwrap(np.angle(L))))
    axes[1].axhline(-180, color="k", lw=0.5)
    axes[1].set(xlabel="frequency (Hz)", ylabel="phase (deg)")
    # Nyquist around -1: the unit circle, -1, both branches (w > 0 solid,
    # w < 0 dashed), the direction of increasing frequency and a few
    # frequencies marked; what lies far from -1 is clipped.
    ax = axes[2]
    th = np.linspace(0, 2 * np.pi, 200)
    ax.plot(np.cos(th), np.sin(th), ":", color="0.5", lw=0.8, label="|L| = 1")
    ax.plot(L.real, L.imag, color="C0", label="L(e^{j w T}), w > 0")
    ax.plot(L.real, -L.imag, "--", color="C0", lw=0.7, label="w < 0")
    ax.plot([-1], [0], "r+", ms=14, mew=2, label="-1")
    near = np.abs(L + 1) < 2.5
    for fk in (0.1, 1.0, 10.0):
        if f[0] <= fk <= f[-1]:
            Lk = frequency_response(result.loop, [fk])[0]
            if abs(Lk + 1) < 2.5:
                ax.plot(Lk.real, Lk.imag, "k.", ms=5)
                ax.annotate(
                    f"{fk:g} Hz",
                    (Lk.real, Lk.imag),
                    fontsize=7,
                    xytext=(3, 3),
                    textcoords="offset points",
                )
    idx = np.flatnonzero(near[:-1] & near[1:])
    if idx.size:
        i = int(idx[len(idx) // 2])
        ax.annotate(
            "",
            xy=(L[i + 1].real, L[i + 1].imag),
            xytext=(L[i].real, L[i].imag),
            arrowprops=dict(arrowstyle="->", color="C0"),
        )
    ax.set(
        xlim=(-3.0, 1.0),
        ylim=(-2.0, 2.0),
        aspect="equal",
        xlabel="Re L (-)",
        ylabel="Im L (-)",
        title="Nyquist around -1",
    )
    ax.legend(fontsize=7, loc="upper left")
    fig.suptitle(
        f"{title} normal-force loop: GM "
        f"{result.gain_margin_dB:.1f} dB, PM "
        f"{result.phase_margin_deg:.1f} deg"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
