"""The families picture: pre-rounding error (log) against cycles and against flash, per chip.

Each family has its own colour and marker; filled markers are measured on the simulator (each
family's best), hollow ones are the rest of the ladder at their estimated cost; the pick is
circled, the MLP's best is labelled even when dominated; the float math.h IK is a reference line.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
from matplotlib.ticker import LogFormatter, NullFormatter

from nnik.report.plots import _figure, _save

STYLE = {"mlp": ("#d62728", "o"), "poly": ("#1f77b4", "s"), "lut": ("#2ca02c", "^"), "hybrid": ("#9467bd", "D")}
OTHER = ("#7f7f7f", "x")


def families_front(path: Path, *, points: Sequence[Mapping], chips: Sequence[str], max_error: float, unit: str,
                   float_ik: Mapping[str, float], title: str) -> Path:
    """points: dicts with family, err, measured {chip: (cycles, flash)} or estimated {...},
    picked (bool), best (bool), label (optional: written beside the point, measured or not).
    float_ik: chip -> cycles of the float math.h IK."""
    fig = _figure(5.2 * len(chips), 7.4)
    axes = fig.subplots(2, len(chips), squeeze=False)
    for j, chip in enumerate(chips):
        for i, what in enumerate(("cycles", "flash bytes")):
            ax = axes[i][j]
            for p in points:
                col, mk = STYLE.get(p["family"], OTHER)
                src = p.get("measured", {}).get(chip) or p.get("estimated", {}).get(chip)
                if not src or not np.isfinite(p["err"]):
                    continue
                x = src[i]
                filled = chip in p.get("measured", {})
                ax.scatter([x], [p["err"]], marker=mk, s=55 if filled else 30, color=col if filled else "none",
                           edgecolors=col, linewidths=1.2, zorder=3)
                if p.get("picked") and filled:
                    ax.scatter([x], [p["err"]], marker="o", s=320, facecolors="none", edgecolors="k", linewidths=1.6,
                               zorder=4)
                    ax.annotate("pick", (x, p["err"]), xytext=(8, 8), textcoords="offset points", fontsize=8)
                elif p.get("label") or (p["family"] == "mlp" and p.get("best") and filled):
                    # to the left: the labelled MLP is usually the costliest point, at the right edge
                    ax.annotate(p.get("label") or "MLP best", (x, p["err"]), xytext=(-8, 6),
                                textcoords="offset points", fontsize=8, color=col, ha="right").set_in_layout(False)
            ax.axhline(max_error, color="k", ls=":", lw=1)
            ax.text(0.01, max_error, f" max_error {max_error:g}", transform=ax.get_yaxis_transform(), va="bottom",
                    fontsize=7)
            if i == 0 and float_ik.get(chip):
                ax.axvline(float_ik[chip], color="#8c564b", ls="--", lw=1)
                ax.text(float_ik[chip], 0.98, " float math.h IK", transform=ax.get_xaxis_transform(), va="top",
                        fontsize=7, color="#8c564b", rotation=90)
            ax.set_yscale("log")
            ax.set_xscale("log")
            # plain numbers; the minor ticks labelled only when the axis spans less than a decade (no major tick
            # may be in view then); wider, they would overlap
            lo, hi = ax.get_xlim()
            ax.xaxis.set_major_formatter(LogFormatter(labelOnlyBase=False))
            ax.xaxis.set_minor_formatter(LogFormatter(labelOnlyBase=False, minor_thresholds=(1, 0.4))
                                         if hi < 10 * lo else NullFormatter())
            ax.set_xlabel(f"{what} on {chip}" + (" (measured; hollow: estimated)" if i == 0 else ""))
            ax.set_ylabel(f"pre-rounding max error ({unit})")
            ax.grid(True, which="both", alpha=0.25)
    handles = [axes[0][0].scatter([], [], marker=mk, color=col, label=f) for f, (col, mk) in STYLE.items()
               if any(p["family"] == f for p in points)]
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles), fontsize=8)
    fig.suptitle(title, fontsize=10)
    return _save(fig, path)
