"""PNG of a job: the programmed path and every reached position coloured by its contour error."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

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


def job_png(path: Path, title: str, plan: Plan, cfg: MachineConfig, plot: dict, seg=None) -> Path:
    """Left: the path (with the segments: tool on solid, travel dashed) and the reached positions
    coloured by contour error; right: the contour error over the job's time."""
    reached_mm, error_um, time_s = plot["reached_mm"], plot["error_um"], plot["time_s"]
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.8), dpi=100, gridspec_kw={"width_ratios": [1.1, 1]})
    if seg is None or seg.duty is None:
        for pts in _path_points(plan, cfg):
            ax.plot(pts[:, 0], pts[:, 1], color="0.6", lw=0.8, zorder=1)
    else:
        seen = set()
        for on, pts in _tool_runs(seg, cfg):
            label = None if on in seen else ("tool on" if on else "travel")
            seen.add(on)
            ax.plot(pts[:, 0], pts[:, 1], color="black" if on else "tab:red", lw=0.9 if on else 0.8,
                    ls="-" if on else "--", zorder=3, label=label)  # over the reached positions
        if seen:
            ax.legend(loc="upper right", fontsize=7)
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
    fig.savefig(path)
    plt.close(fig)
    return path


__all__ = ["job_png", "move_dist"]
