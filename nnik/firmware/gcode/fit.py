"""A job's extent against the machine's travel: the frame transform of ``--fit``, ``--scale`` and
``--offset``, and the one-line refusal of a job that leaves the workspace without them.

The transform maps the job's machine frame (millimetres from the work origin, where the motors
start) to the machine's: p * scale + offset. ``--fit`` shrinks the job uniformly (never enlarges
it), keeping its aspect ratio, just enough to fit, and centres it on the workspace.
"""

from __future__ import annotations

from dataclasses import dataclass

from nnik.firmware.config import SCALE_ONE


@dataclass(frozen=True)
class Frame:
    scale_q16: int = SCALE_ONE
    shift_um: tuple[int, int] = (0, 0)
    how: str = "as written"

    def apply(self, p: tuple[int, int]) -> tuple[int, int]:
        return tuple((p[k] * self.scale_q16 + 32768 >> 16) + self.shift_um[k] for k in range(2))


def extent(points: list[tuple[int, int]]) -> tuple[tuple[int, int], tuple[int, int]] | None:
    if not points:
        return None
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return (min(xs), min(ys)), (max(xs), max(ys))


def inside(points, bounds) -> bool:
    (x0, y0), (x1, y1) = bounds
    return all(x0 <= p[0] <= x1 and y0 <= p[1] <= y1 for p in points)


def fit_frame(ext, bounds) -> Frame:
    """The largest scale <= 1 (Q16, floor) that fits the extent, centred on the workspace."""
    (ex0, ey0), (ex1, ey1) = ext
    (bx0, by0), (bx1, by1) = bounds
    spans = [(ex1 - ex0, bx1 - bx0), (ey1 - ey0, by1 - by0)]
    scale = SCALE_ONE
    for e, b in spans:
        if e > 0:
            scale = min(scale, b * SCALE_ONE // e)
    scale = max(scale, 1)
    cx, cy = (ex0 + ex1) / 2, (ey0 + ey1) / 2
    shift = (round((bx0 + bx1) / 2 - cx * scale / SCALE_ONE), round((by0 + by1) / 2 - cy * scale / SCALE_ONE))
    return Frame(scale, shift, f"fitted: scale {scale / SCALE_ONE:.4g}, centred on the workspace")


def user_frame(scale: float | None, offset_mm: tuple[float, float] | None, unit_um: int) -> Frame:
    """--scale S and --offset X,Y (in the job's units: unit_um per unit)."""
    s = SCALE_ONE if scale is None else int(round(scale * SCALE_ONE))
    o = (0, 0) if offset_mm is None else tuple(int(round(v * unit_um)) for v in offset_mm)
    parts = ([f"scale {scale:g}"] if scale is not None else []) + ([f"offset {offset_mm[0]:g},{offset_mm[1]:g}"]
                                                                   if offset_mm is not None else [])
    return Frame(s, o, ", ".join(parts) or "as written")


def mm(v: int) -> str:
    return f"{v / 1000:.3f}".rstrip("0").rstrip(".")


def refusal(ext, bounds) -> str:
    """One line: where the job goes, where the machine can go, and what would fit it."""
    (ex0, ey0), (ex1, ey1) = ext
    (bx0, by0), (bx1, by1) = bounds
    span_fits = ex1 - ex0 <= bx1 - bx0 and ey1 - ey0 <= by1 - by0
    if span_fits:
        dx = (bx0 + bx1 - ex0 - ex1) // 2
        dy = (by0 + by1 - ey0 - ey1) // 2
        hint = f"--offset {mm(dx)},{mm(dy)} would centre it, or --fit"
    else:
        fr = fit_frame(ext, bounds)
        hint = f"--fit would scale it by {fr.scale_q16 / SCALE_ONE:.4g} and centre it"
    return (f"the job leaves the workspace: it spans X {mm(ex0)}..{mm(ex1)} Y {mm(ey0)}..{mm(ey1)} mm from the "
            f"work origin; the machine reaches X {mm(bx0)}..{mm(bx1)} Y {mm(by0)}..{mm(by1)} mm; {hint}")
