"""The figure of the certified limits against the simulated ones: one
panel per limit, each bisection trial of ``certify`` (certified, refused,
no operating point) on the limit's axis, the certified bracket, and the
bracket that refined simulation found (docs/stability-measurements.md).
"""

from __future__ import annotations

from typing import Dict, Optional

__all__ = ["SIMULATED", "plot_certified_limits", "simulated_text"]

#: Analyze's limits at refined numerics (docs/stability-measurements.md,
#: "Limits: shipped, refined, predicted"): the last stable and first
#: unstable value of a gain; a cutoff with no limit in its range gives
#: the stable span tried.
SIMULATED = {
    ("paper", "sliding"): {"stable": 5742.0, "unstable": 5828.0},
    ("paper", "orientation"): {"stable": 412.5, "unstable": 431.2},
    ("paper", "cutoff"): {"stable_span": [120.0, 199.9]},
    ("paper_6dof", "sliding"): {"stable": 4500.0, "unstable": 4650.0},
}

_COLOURS = {
    "certified": "tab:green",
    "no_operating_point": "tab:gray",
}


def simulated_text(simulated: Optional[Dict], unit: str) -> str:
    """One line for a simulated limit (``SIMULATED``'s entry)."""
    if simulated is None:
        return "-"
    if "stable_span" in simulated:
        lo, hi = simulated["stable_span"]
        return f"none in {lo:g}-{hi:g} {unit} (both ends stable)"
    return f"{simulated['stable']:g}-{simulated['unstable']:g} {unit}"


def plot_certified_limits(limits: Dict, path, *, title: str = ""):
    """A PNG at ``path``: a panel per entry of ``limits`` ({name: {unit,
    certified, refused, trials [{value, status}], simulated}} as
    ``scripts/certified_limits.py`` writes them; with ``lowest`` {certified,
    refused}, the low end of the certified values too). Returns the
    figure's axes by name."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(limits)
    fig, axs = plt.subplots(
        len(names), 1, figsize=(8.5, 1.9 * len(names)), squeeze=False
    )
    out = {}
    for ax, name in zip(axs[:, 0], names):
        limit = limits[name]
        for trial in limit["trials"]:
            ax.plot(
                trial["value"],
                1.0,
                "o",
                color=_COLOURS.get(trial["status"], "tab:red"),
                label=trial["status"],
            )
        for end in (limit, limit.get("lowest") or {}):
            if end.get("certified") is not None:
                ax.axvline(end["certified"], color="tab:green", ls="-")
            if end.get("refused") is not None:
                ax.axvline(end["refused"], color="tab:red", ls="--")
        simulated = limit.get("simulated")
        if simulated:
            lo, hi = simulated.get(
                "stable_span",
                (simulated.get("stable"), simulated.get("unstable")),
            )
            ax.axvspan(
                lo, hi, ymin=0.05, ymax=0.45, color="tab:blue", alpha=0.3
            )
            ax.text(lo, 0.3, "simulated (refined)", fontsize=8, va="center")
        handles = {}
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
        ax.legend(
            handles.values(),
            handles.keys(),
            fontsize=7,
            loc="upper left",
            bbox_to_anchor=(1.01, 1.0),
        )
        ax.set_ylim(0.0, 1.6)
        ax.set_yticks([])
        ax.set_xlabel(f"{name} ({limit['unit']})")
        out[name] = ax
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return out
