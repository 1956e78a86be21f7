"""A closed-loop job's report: OUTDIR/job/JOB.json (the figures) and OUTDIR/job/JOB.png (the path
and the carriage, the contour error and the duty against time), each written whole.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from nnik.files.atomic_write import replacing, write_file_atomic


def picture(path: Path, title: str, ref_um: np.ndarray, table_um: np.ndarray, contour: np.ndarray, duty: np.ndarray,
            tick_s: float, duty_max: int) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.arange(len(ref_um)) * tick_s
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    ax[0].plot(ref_um[:, 0] / 1000, ref_um[:, 1] / 1000, "k-", lw=1, label="reference")
    ax[0].plot(table_um[:, 0] / 1000, table_um[:, 1] / 1000, "r-", lw=0.8, label="carriage")
    ax[0].set(xlabel="X mm", ylabel="Y mm", aspect="equal", title="path")
    ax[0].legend(fontsize=8)
    ax[1].plot(t, contour, lw=0.8)
    ax[1].set(xlabel="s", ylabel="µm", title="contour error (to the path)")
    ax[2].plot(t, duty[:, 0] / duty_max * 100, lw=0.8, label="X")
    ax[2].plot(t, duty[:, 1] / duty_max * 100, lw=0.8, label="Y")
    ax[2].set(xlabel="s", ylabel="% of full duty", title="duty", ylim=(-105, 105))
    ax[2].legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path) as tmp:
        fig.savefig(tmp, dpi=90)
    plt.close(fig)
    return str(path)


def write(figures: dict, out: Path, stem: str) -> dict:
    write_file_atomic(out / f"{stem}.json", json.dumps(figures, indent=2) + "\n")
    return figures
