"""PNG of a job with axis dynamics: the programmed path, the tip with no compensation and with
the chosen one (left, with a zoom on the corner where the uncompensated tip strays most), and the
tip's contour error over time for both (right)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from nnik.files.atomic_write import replacing  # noqa: E402
from nnik.firmware.gcode.plot import _lines, _path_points  # noqa: E402

ZOOM_MM = 0.3


def _draw(ax, plan, cfg, none, chosen, label):
    # one collection (a raster has a move per pixel: an artist each took most of a long job's time)
    _lines(ax, _path_points(plan, cfg), color="0.2", lw=1.0, zorder=3)
    ax.plot(*none["tip_mm"].T, color="tab:red", lw=0.8, alpha=0.85, label="tip, no compensation", zorder=1)
    ax.plot(*chosen["tip_mm"].T, color="tab:green", lw=0.8, label=f"tip, {label}", zorder=2)


def dynamics_png(path: Path, title: str, plan, cfg, tracks: dict, chosen: str, figures: dict) -> Path:
    none, pick = tracks["none"], tracks[chosen]
    fig, (ax, axz, ax2) = plt.subplots(1, 3, figsize=(15, 4.8), dpi=100, gridspec_kw={"width_ratios": [1, 1, 1.3]})
    _draw(ax, plan, cfg, none, pick, chosen)
    ax.plot([], [], color="0.2", lw=1.0, label="programmed path")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(loc="best", fontsize=7)
    k = int(np.argmax(none["error_um"]))
    c = none["tip_mm"][k]
    _draw(axz, plan, cfg, none, pick, chosen)
    axz.set_xlim(c[0] - ZOOM_MM, c[0] + ZOOM_MM)
    axz.set_ylim(c[1] - ZOOM_MM, c[1] + ZOOM_MM)
    axz.set_aspect("equal")
    axz.set_title(f"zoom: where the uncompensated tip strays most ({none['error_um'][k]:.0f} µm)", fontsize=8)
    axz.set_xlabel("x (mm)")
    for name, tr, col in (("none", none, "tab:red"), (chosen, pick, "tab:green")):
        f = figures[name]
        ax2.plot(tr["time_s"], tr["error_um"], color=col, lw=0.7,
                 label=f"{name}: max {f['contour_um']['max']:.1f} µm, ringing {f['ringing_um']['max']:.1f} µm")
    ax2.set_xlabel("time (s)")
    ax2.set_ylabel("tip's contour error (µm)")
    ax2.legend(loc="upper right", fontsize=7)
    ax2.grid(alpha=0.3)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    with replacing(path) as tmp:
        fig.savefig(tmp)
    plt.close(fig)
    return Path(path)
