"""The report's pictures: one function per PNG, matplotlib on the Agg backend, no pyplot state.

Every function takes plain numpy arrays / dicts prepared by :mod:`nnik.report` sections and writes one
PNG to ``path``. None of them reads files or knows about metrics.json.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")  # before anything imports pyplot; the report never opens a window

import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from nnik.files.atomic_write import replacing  # noqa: E402

DPI = 110
# Colours used consistently across the pictures.
C_FLOAT = "#1f77b4"
C_FIXED = "#d62728"
C_DELIVERED = "#7f7f7f"
C_LUT = "#2ca02c"
C_MATH = "#9467bd"
C_MLP = "#d62728"
C_KERNEL = "#ff7f0e"


def _figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save(fig: Figure, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI, facecolor="white")
    return path


def _binned_max(x: np.ndarray, y: np.ndarray, v: np.ndarray, extent, nbins: int) -> np.ndarray:
    """Per-cell maximum of v over a regular nbins x nbins grid (NaN where a cell is empty)."""
    x0, x1, y0, y1 = extent
    ix = np.clip(((x - x0) / max(x1 - x0, 1e-300) * nbins).astype(int), 0, nbins - 1)
    iy = np.clip(((y - y0) / max(y1 - y0, 1e-300) * nbins).astype(int), 0, nbins - 1)
    out = np.full(nbins * nbins, -np.inf)
    np.maximum.at(out, iy * nbins + ix, v)
    out[~np.isfinite(out)] = np.nan
    return out.reshape(nbins, nbins)


def error_map(
    path: Path,
    *,
    x: np.ndarray,
    y: np.ndarray,
    err: np.ndarray,
    outputs: Sequence[str],
    unit: str,
    title: str,
    kind: str,
    extent: tuple[float, float, float, float] | None = None,
) -> Path:
    """|error| over the workspace, one panel per output, worst point marked with a cross.

    kind = "grid":   x (nx,), y (ny,) axes of a regular grid, err (ny, nx, n_out);
    kind = "binned": x, y (N,) scattered points, err (N, n_out); each cell shows the largest
                     |error| of the points that fall in it (a heatmap from a test set);
    kind = "points": x, y (N,) points, err (N, n_out), drawn as a coloured scatter.
    """
    err = np.abs(np.asarray(err, dtype=np.float64))
    n_out = err.shape[-1]
    fig = _figure(5.2 * n_out, 4.6)
    axes = fig.subplots(1, n_out, squeeze=False)[0]
    if extent is None:
        extent = (float(np.min(x)), float(np.max(x)), float(np.min(y)), float(np.max(y)))
    for j, ax in enumerate(axes):
        e = err[..., j]
        if kind == "grid":
            im = ax.imshow(e, origin="lower", extent=(x[0], x[-1], y[0], y[-1]), cmap="viridis",
                           aspect="equal", interpolation="nearest")
            iy, ix = np.unravel_index(int(np.nanargmax(e)), e.shape)
            wx, wy, wv = x[ix], y[iy], e[iy, ix]
        elif kind == "binned":
            nbins = int(np.clip(np.sqrt(len(e) / 10), 8, 60))  # ~10 points per cell: few empty cells
            cells = _binned_max(np.asarray(x), np.asarray(y), e, extent, nbins)
            cmap = matplotlib.colormaps["viridis"].with_extremes(bad="#d9d9d9")  # grey: no test point
            im = ax.imshow(cells, origin="lower", extent=extent, cmap=cmap, aspect="equal",
                           interpolation="nearest")
            k = int(np.argmax(e))
            wx, wy, wv = x[k], y[k], e[k]
        elif kind == "points":
            order = np.argsort(e)  # the largest errors drawn last, on top
            im = ax.scatter(np.asarray(x)[order], np.asarray(y)[order], c=e[order], s=14, cmap="viridis",
                            edgecolors="none")
            ax.set_aspect("equal")
            ax.set_xlim(extent[0], extent[1])
            ax.set_ylim(extent[2], extent[3])
            k = int(np.argmax(e))
            wx, wy, wv = x[k], y[k], e[k]
        else:
            raise ValueError(kind)
        cb = fig.colorbar(im, ax=ax, shrink=0.85)
        cb.set_label(f"|error| ({unit})")
        ax.plot([wx], [wy], marker="x", color="red", markersize=12, markeredgewidth=2.5, linestyle="none",
                clip_on=False)
        # the worst point goes in the title, where no legend box can hide the data
        ax.set_title(f"{outputs[j]}: worst {wv:.4g} {unit} at ({wx:.1f}, {wy:.1f}) mm (red ×)", fontsize=10)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    fig.suptitle(title, fontsize=11)
    return _save(fig, path)


def error_histogram(
    path: Path,
    *,
    errors: Mapping[str, np.ndarray],
    outputs: Sequence[str],
    unit: str,
    title: str,
) -> Path:
    """Signed error distributions per output; one outline per model (float, fixed, delivered)."""
    colours = [C_FLOAT, C_FIXED, C_DELIVERED, C_LUT, C_MATH]
    first = next(iter(errors.values()))
    n_out = first.shape[1]
    fig = _figure(5.2 * n_out, 3.8)
    axes = fig.subplots(1, n_out, squeeze=False)[0]
    for j, ax in enumerate(axes):
        lim = max(float(np.abs(e[:, j]).max()) for e in errors.values()) or 1.0
        bins = np.linspace(-lim, lim, 81)
        for (label, e), c in zip(errors.items(), colours):
            ej = e[:, j]
            ax.hist(ej, bins=bins, histtype="step", linewidth=1.6, color=c,
                    label=f"{label} (max {np.abs(ej).max():.3g})")
        ax.set_yscale("log")
        ax.set_xlabel(f"error ({unit})")
        ax.set_ylabel("test points")
        ax.set_title(outputs[j], fontsize=11)
        ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=11)
    return _save(fig, path)


def tanh_error(
    path: Path,
    *,
    x: np.ndarray,
    float_err_lsb: np.ndarray,
    int_err_lsb: np.ndarray,
    title: str,
    sat_x: float | None = None,
) -> Path:
    """Error of a tanh replacement over its input range, in LSB of Q15 (1 LSB = 2^-15).

    x: inputs (float, e.g. every Q3.12 value); float_err_lsb: the unquantised pieces minus tanh;
    int_err_lsb: the integer implementation minus tanh.
    """
    fig = _figure(10.0, 4.2)
    ax = fig.subplots()
    x = np.asarray(x, dtype=np.float64)
    int_err_lsb = np.asarray(int_err_lsb, dtype=np.float64)
    label = f"integer (Q3.12 → Q15): max {np.abs(int_err_lsb).max():.3g} LSB"
    if len(x) > 4096:  # every int16 input: draw the integer error as its envelope per bin
        nb = len(x) // 32
        k = nb * 32
        xb = x[:k].reshape(nb, 32).mean(1)
        eb = int_err_lsb[:k].reshape(nb, 32)
        ax.fill_between(xb, eb.min(1), eb.max(1), color=C_FIXED, alpha=0.45, linewidth=0,
                        label=label + " (range per 32 inputs)")
    else:
        ax.plot(x, int_err_lsb, color=C_FIXED, linewidth=0.6, label=label)
    ax.plot(x, float_err_lsb, color=C_FLOAT, linewidth=1.2,
            label=f"float pieces: max {np.abs(float_err_lsb).max():.3g} LSB")
    for s in (-1, 1):
        ax.axhline(s, color="black", linewidth=0.6, linestyle=":")
    if sat_x is not None:
        for s in (-sat_x, sat_x):
            ax.axvline(s, color="grey", linewidth=0.8, linestyle="--")
        ax.text(sat_x, ax.get_ylim()[1], f" 1 from |x| ≥ {sat_x:g}", va="top", fontsize=8, color="grey")
    ax.set_xlabel("x (tanh input)")
    ax.set_ylabel("approximation − tanh(x)  (LSB of Q15)")
    ax.set_xlim(float(np.min(x)), float(np.max(x)))
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title(title, fontsize=11)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def training_curve(path: Path, *, history: Sequence[Mapping], title: str) -> Path:
    """Train (dashed) and validation (solid) MSE vs optimiser step, log scale, per restart.

    The restart whose state was kept (``best``) is drawn thick; the Adam -> L-BFGS switch is
    marked with a dot on each validation curve.
    """
    fig = _figure(8.0, 4.4)
    ax = fig.subplots()
    restarts = sorted({int(h["restart"]) for h in history})
    cmap = matplotlib.colormaps["tab10"]
    for r in restarts:
        hs = [h for h in history if int(h["restart"]) == r]
        t = np.array([h.get("step", h.get("t", i)) for i, h in enumerate(hs)], dtype=np.float64)
        tr = np.array([h["train"] for h in hs], dtype=np.float64)
        va = np.array([h["val"] for h in hs], dtype=np.float64)
        best = any(h.get("best") for h in hs)
        c = cmap(r % 10)
        lw = 2.6 if best else 1.0
        tag = " (kept)" if best else ""
        ax.plot(t, va, color=c, linewidth=lw, label=f"restart {r} validation{tag}")
        ax.plot(t, tr, color=c, linewidth=lw * 0.7, linestyle="--", alpha=0.8, label=f"restart {r} train")
        phases = [h.get("phase") for h in hs]
        if "lbfgs" in phases:
            k = phases.index("lbfgs")
            ax.plot([t[k]], [va[k]], marker="o", color=c, markersize=5)
        if best and len(va):
            k = int(np.nanargmin(va))
            ax.plot([t[k]], [va[k]], marker="*", color="black", markersize=12, linestyle="none",
                    label=f"best validation {va[k]:.3g}")
    ax.set_yscale("log")
    ax.set_xlabel("optimiser step (Adam steps, then L-BFGS rounds)")
    ax.set_ylabel("MSE (standardised outputs)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title(title, fontsize=11)
    return _save(fig, path)


def cost_accuracy(
    path: Path,
    *,
    points: Mapping[str, Sequence[Mapping]],
    unit: str,
    title: str,
) -> Path:
    """Cycles per IK vs max error, one panel per target.

    points[target] = [{"label", "kind" ("mlp"|"kernel"|"float"|"lut"), "cycles", "err"}, ...].
    Log-log axes; down-left is better.
    """
    targets = [t for t, ps in points.items() if ps]
    n = max(1, len(targets))
    fig = _figure(5.4 * n, 4.4)
    axes = fig.subplots(1, n, squeeze=False)[0]
    style = {"mlp": (C_MLP, "o"), "kernel": (C_KERNEL, "s"), "float": (C_MATH, "^"), "lut": (C_LUT, "D")}
    for ax, tgt in zip(axes, targets):
        ps = points[tgt]
        for i, p in enumerate(ps):
            c, m = style.get(p["kind"], ("black", "o"))
            ax.plot([p["cycles"]], [p["err"]], marker=m, color=c, markersize=9, linestyle="none")
            # alternate labels above and below so that neighbours with equal error stay readable
            ax.annotate(p["label"], (p["cycles"], p["err"]), textcoords="offset points",
                        xytext=(6, 6) if i % 2 == 0 else (6, -13), fontsize=8)
        xs = [p["cycles"] for p in ps]
        es = [p["err"] for p in ps]
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(min(xs) / 2, max(xs) * 3)
        ax.set_ylim(min(es) / 3, max(es) * 3)
        ax.set_xlabel("cycles per IK (mean)")
        ax.set_ylabel(f"max |error| ({unit}, worse output)")
        ax.set_title(tgt, fontsize=11)
        ax.grid(alpha=0.3, which="both")
    handles = [Line2D([], [], color=c, marker=m, linestyle="none", label=k)
               for k, (c, m) in (("nnik MLP", style["mlp"]), ("MLP kernel", style["kernel"]),
                                 ("float math.h IK", style["float"]), ("lookup table", style["lut"]))]
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=8)
    fig.suptitle(title, fontsize=11)
    return _save(fig, path)
