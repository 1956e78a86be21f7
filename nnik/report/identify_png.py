"""The picture `nnik identify` draws: per axis, the measured counts against the identified model's
prediction (top), and the measured speed against the predicted one (bottom, counts/s)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nnik.report.plots import _figure, _save


def identify_png(path: Path, title: str, t: np.ndarray, measured: np.ndarray, predicted: np.ndarray,
                 labels: tuple[str, str]) -> Path:
    """measured, predicted: (N, 2) counts of x and y; labels: each axis's model in words."""
    fig = _figure(12, 7)
    axes = fig.subplots(2, 2, sharex=True)
    tick = float(np.median(np.diff(t)))
    for i, name in enumerate(("x", "y")):
        top, bottom = axes[0, i], axes[1, i]
        top.plot(t, measured[:, i], color="black", lw=1.0, label="measured")
        top.plot(t, predicted[:, i], color="tab:red", lw=1.0, ls="--", label="predicted")
        top.set_title(f"{name}: {labels[i]}", fontsize="small")
        top.set_ylabel("counts")
        bottom.plot(t[1:], np.diff(measured[:, i]) / tick, color="black", lw=0.6, label="measured")
        bottom.plot(t[1:], np.diff(predicted[:, i]) / tick, color="tab:red", lw=0.8, label="predicted")
        bottom.set_ylabel("speed, counts/s")
        bottom.set_xlabel("time, s")
        for ax in (top, bottom):
            ax.grid(color="lightgrey")
            ax.legend(loc="upper right", fontsize="x-small")
    fig.suptitle(title, fontsize="medium")
    return _save(fig, Path(path))
