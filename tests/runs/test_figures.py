"""Tests of deburr_drake.runs.figures (Figs. 8-12 of Hsu & Fu) on synthetic
logs."""

import time
import warnings

import matplotlib.image as mpimg
import numpy as np
import pytest

from deburr_drake.math.fuzzy import RuleBase
from deburr_drake.runs.figures import compare_figures, make_figures

N, M, B, U, A = 20000, 2000, 200, 5, 2
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def synthetic_logs(m=2, seed=0, contact_start=True):
    """Logs shaped like a run's logs.npz (SI units), U = 5, two fuzzy axes."""
    rng = np.random.default_rng(seed)
    T = 50.0
    t = np.linspace(0.0, T, N)
    tc = np.linspace(0.0, T, M)
    delta = (
        0.5e-3 * (1 - np.exp(-t / 2))
        + 2e-5 * np.sin(3 * t)
        + 5e-6 * rng.standard_normal(N)
    )
    arc = np.linspace(0.0, 0.12, B)
    burr = 0.2e-3 + sum(
        1e-3 * np.exp(-(((arc - c) / 4e-3) ** 2)) for c in (0.03, 0.06, 0.09)
    )
    depth = np.where(arc > 0.005, 0.5e-3 + 3e-5 * np.sin(arc * 300), 0.0)
    R = (2 * U + 1) ** 2
    rb = RuleBase(m, U, 0.02, 0.004, dead_zone_half_width=0.0)
    ii, jj = np.divmod(np.arange(R), 2 * U + 1)
    theta = np.stack(
        [
            k * 2.0 + 5.0 * np.tanh((jj - U) / 2.0) + 0.3 * (ii - U)
            for k in range(A)
        ]
    ).astype(float)
    assert theta.shape == (A, rb.n_rules)
    logs = {
        "chamfer.t": t,
        "chamfer.delta": delta,
        "chamfer.f_n": 20 + rng.standard_normal(N),
        "chamfer.f_t": -(10 + 0.5 * np.sin(t) + 0.3 * rng.standard_normal(N)),
        "chamfer.arc_position": 2.4e-3 * t,
        "controller.t": tc,
        "controller.delta_d": np.full(M, 0.5e-3),
        "controller.e_f": 2 * np.exp(-tc / 5) * np.cos(tc),
        "controller.s": 1e-3 * rng.standard_normal((M, 3)),
        "finish.arc": arc,
        "finish.depth": depth,
        "finish.burr_initial": burr,
        "finish.burr_remaining": np.maximum(burr - depth, 0.0),
        "theta.final": theta,
        "meta.fuzzy_order": np.array(m),
        "meta.upsilon": np.array(U),
        "meta.delta0": np.array(0.02),
        "meta.deltak": np.full(A, 0.004),
        "meta.fuzzy_axes": np.array([0, 1]),
        "meta.desired_depth": np.array(0.5e-3),
        "meta.desired_force": np.array(10.0),
    }
    if contact_start:
        logs["meta.contact_start"] = np.array(1.0)
    return logs


EXPECTED = {
    "fig08_surface_finish.png",
    "fig09_depth_force_error.png",
    "fig10_chamfering_force_error.png",
    "fig11_12_fuzzy_axis0.png",
    "fig11_12_fuzzy_axis1.png",
}


def check_png(path):
    assert path.is_file(), path
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC, path
    assert len(data) > 10_000, (path, len(data))
    img = mpimg.imread(path)
    assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 200
    assert float(np.var(img[..., :3])) > 0.0, f"{path} is blank"


@pytest.mark.parametrize("m", [0, 2])
def test_make_figures_writes_all(tmp_path, m):
    logs = synthetic_logs(m=m)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing skipped, nothing warned
        paths = make_figures(logs, tmp_path, label=f"test (m = {m})")
    elapsed = time.perf_counter() - t0
    assert {p.name for p in paths} == EXPECTED
    for p in paths:
        assert p.parent == tmp_path
        check_png(p)
    assert elapsed < 5.0, f"make_figures took {elapsed:.2f} s"


def test_make_figures_accepts_npz_and_no_contact_start(tmp_path):
    logs = synthetic_logs(contact_start=False)
    np.savez(tmp_path / "logs.npz", **logs)
    with np.load(tmp_path / "logs.npz") as npz:
        paths = make_figures(npz, tmp_path / "out")
    assert {p.name for p in paths} == EXPECTED


def test_missing_theta_skips_fig11_12(tmp_path):
    logs = synthetic_logs()
    del logs["theta.final"]
    with pytest.warns(UserWarning, match="theta.final"):
        paths = make_figures(logs, tmp_path)
    names = {p.name for p in paths}
    assert names == EXPECTED - {
        "fig11_12_fuzzy_axis0.png",
        "fig11_12_fuzzy_axis1.png",
    }
    for p in paths:
        check_png(p)
    assert not list(tmp_path.glob("fig11_12*"))


def test_missing_finish_skips_only_fig08(tmp_path):
    logs = synthetic_logs()
    for k in [k for k in logs if k.startswith("finish.")]:
        del logs[k]
    with pytest.warns(UserWarning, match="finish"):
        paths = make_figures(logs, tmp_path)
    assert {p.name for p in paths} == EXPECTED - {"fig08_surface_finish.png"}


def test_compare_figures(tmp_path):
    runs = {
        "m = 0": synthetic_logs(m=0, seed=1),
        "m = 2": synthetic_logs(m=2, seed=2),
    }
    paths = compare_figures(runs, tmp_path)
    assert {p.name for p in paths} == {
        "compare_fig08_surface_finish.png",
        "compare_fig09_depth_force_error.png",
        "compare_fig10_chamfering_force_error.png",
    }
    for p in paths:
        check_png(p)


def test_compare_figures_leaves_out_incomplete_run(tmp_path):
    partial = synthetic_logs(seed=3)
    del partial["chamfer.f_t"]
    runs = {"full": synthetic_logs(), "partial": partial}
    with pytest.warns(UserWarning, match="chamfer.f_t"):
        paths = compare_figures(runs, tmp_path)
    assert len(paths) == 3


def test_compare_figures_rejects_empty(tmp_path):
    with pytest.raises(ValueError, match="runs"):
        compare_figures({}, tmp_path)


@pytest.mark.parametrize(
    "key, bad",
    [
        ("chamfer.delta", lambda a: a[:-1]),
        ("chamfer.f_t", lambda a: a[:, None]),
        ("controller.e_f", lambda a: a[:-5]),
        ("controller.delta_d", lambda a: np.tile(a, (2, 1))),
        ("finish.depth", lambda a: a[:-1]),
        ("finish.burr_initial", lambda a: a[1:]),
        ("theta.final", lambda a: a[:, :-1]),
        ("theta.final", lambda a: a[0]),
        ("meta.deltak", lambda a: a[:1].repeat(3)),
        ("meta.fuzzy_axes", lambda a: np.arange(5)),
        ("meta.desired_force", lambda a: np.array([10.0, 10.0])),
    ],
)
def test_malformed_shape_raises_naming_key(tmp_path, key, bad):
    logs = synthetic_logs()
    logs[key] = bad(logs[key])
    with pytest.raises(ValueError, match=key.replace(".", r"\.")):
        make_figures(logs, tmp_path)


def test_malformed_shape_raises_in_compare(tmp_path):
    bad = synthetic_logs()
    bad["chamfer.delta"] = bad["chamfer.delta"][:-1]
    with pytest.raises(ValueError, match=r"chamfer\.delta"):
        compare_figures({"ok": synthetic_logs(), "bad": bad}, tmp_path)
