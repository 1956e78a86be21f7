"""PNG of a job: the programmed path and every reached position coloured by its contour error."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
import numpy as np  # noqa: E402

from nnik.files.atomic_write import replacing  # noqa: E402
from nnik.firmware.gcode.contour import move_dist  # noqa: E402
from nnik.firmware.config import MachineConfig  # noqa: E402
from nnik.firmware.gcode.motion import Plan  # noqa: E402


MAX_POINTS = 60_000  # reached positions drawn (the figures use every one)


def _path_points(plan: Plan, cfg: MachineConfig, n: int = 400) -> list[np.ndarray]:
    """Dense points of each programmed move (mm, machine frame)."""
    origin = np.asarray(cfg.origin_um) / 1000.0
    out = []
    for mv in plan.moves:
        a, b = np.asarray(mv.start) / 1000.0, np.asarray(mv.end) / 1000.0
        if mv.kind == "line":
            t = np.linspace(0, 1, 2)[:, None]
            out.append(origin + a + t * (b - a))
            continue
        c = np.asarray(mv.center) / 1000.0
        a0 = np.arctan2(*(a - c)[::-1])
        b0 = np.arctan2(*(b - c)[::-1])
        sweep = ((b0 - a0) if mv.ccw else (a0 - b0)) % (2 * np.pi) or 2 * np.pi
        th = a0 + np.linspace(0, sweep, n) * (1 if mv.ccw else -1)
        out.append(origin + c + mv.radius / 1000.0 * np.stack([np.cos(th), np.sin(th)], 1))
    return out


def _tool_runs(seg, cfg: MachineConfig) -> list[tuple[bool, np.ndarray]]:
    """The segment path (mm, machine frame) cut into runs with the tool on or off."""
    origin = np.asarray(cfg.origin_um) / 1000.0
    pts = origin + np.concatenate([[[0, 0]], seg.ends_um]) / 1000.0
    on = np.asarray(seg.duty != cfg.tool_off_duty)
    if not len(on):
        return []
    starts = np.flatnonzero(np.r_[True, on[1:] != on[:-1]])
    ends = np.r_[starts[1:], len(on)]
    return [(bool(on[k]), pts[k:j + 1]) for k, j in zip(starts.tolist(), ends.tolist())]


def _thin(n: int, keep: np.ndarray | None = None, most: int = MAX_POINTS) -> np.ndarray:
    """Indices of at most about `most` of n points, evenly spread, plus `keep` (drawing only)."""
    if n <= most:
        return np.arange(n)
    idx = np.arange(0, n, -(-n // most))
    return np.union1d(idx, keep) if keep is not None else idx


def _lines(ax, parts: list[np.ndarray], color, lw: float, ls: str = "-", zorder: int = 1) -> None:
    """Polylines as one LineCollection, the axes' limits taken over their points."""
    ax.add_collection(LineCollection(parts, colors=color, linewidths=lw, linestyles=ls, zorder=zorder))
    ax.update_datalim(np.concatenate(parts))
    ax.autoscale_view()


def job_png(path: Path, title: str, plan: Plan, cfg: MachineConfig, plot: dict, seg=None) -> Path:
    """Left: the path (with the segments: tool on solid, travel dashed) and the reached positions
    coloured by contour error; right: the contour error over the job's time."""
    reached_mm, error_um, time_s = plot["reached_mm"], plot["error_um"], plot["time_s"]
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.8), dpi=100, gridspec_kw={"width_ratios": [1.1, 1]})
    # one collection per style (a photo engraving has a run per pixel: an artist each would take minutes)
    if seg is None or seg.duty is None:
        _lines(ax, _path_points(plan, cfg), color="0.6", lw=0.8, zorder=1)
    else:
        runs = _tool_runs(seg, cfg)
        handles = []
        for on in (True, False):
            style = {"color": "black" if on else "tab:red", "lw": 0.9 if on else 0.8, "ls": "-" if on else "--"}
            pts = [p for o, p in runs if o == on]
            if pts:
                _lines(ax, pts, zorder=3, **style)  # over the reached positions
                handles.append(Line2D([], [], label="tool on" if on else "travel", **style))
        if handles:
            ax.legend(handles=handles[::-1] if not runs[0][0] else handles, loc="upper right", fontsize=7)
    if len(reached_mm):
        k = _thin(len(reached_mm), np.argsort(error_um)[-100:])  # a long job: evenly spread, the worst kept
        sc = ax.scatter(reached_mm[k, 0], reached_mm[k, 1], c=error_um[k], s=5, cmap="viridis", zorder=2)
        fig.colorbar(sc, ax=ax, label="contour error (µm)")
        ax2.plot(time_s[k], error_um[k], lw=0.7, color="tab:blue")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title("reached positions (exact FK of the step counts)", fontsize=9)
    ax2.set_xlabel("time (s)")
    ax2.set_ylabel("contour error (µm)")
    ax2.set_title("distance to the programmed path after each step", fontsize=9)
    ax2.grid(alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path) as tmp:
        fig.savefig(tmp)
    plt.close(fig)
    return path


__all__ = ["job_png", "move_dist"]
