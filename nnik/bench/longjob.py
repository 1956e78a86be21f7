"""Long, deterministic G-code jobs for the speed bench (nnik.bench.job_speed).

``raster``: a LaserGRBL-style raster engraving (M4 dynamic power, S on every G1 that changes the
power, bidirectional rows, G0 between rows, M5 at the end) of a synthetic grey image: rings and a
diagonal gradient sampled on a pixel grid, runs of equal power merged into one G1 each as
LaserGRBL does.  ``vector``: a text-like vector job (strokes of short G1 lines and G2/G3 arcs,
tool on in the strokes, G0 between them).  Both are pure functions of their arguments.

    python -m nnik.bench.longjob raster OUT.gcode [--rows N] [--width MM] [--pixel MM] [--pitch MM]
        [--feed MM_MIN] [--dither]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path


BAYER4 = (0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5)  # ordered dither, 4 x 4


def _power(x: float, y: float, w: float, h: float, cell: int = -1) -> int:
    """The image's power at (x, y) in 0..1000 (S units), quantised to 9 levels; with a dither
    cell (0..15) ordered-dithered as a photo engraving is (nearly every pixel its own S)."""
    r = math.hypot(x, y) / (0.5 * min(w, h))
    ring = 0.5 + 0.5 * math.cos(2 * math.pi * 3 * r)
    grad = (x / w + y / h + 1.0) / 2.0
    v = 0.6 * ring + 0.4 * grad if r < 1.0 else 0.2 * grad
    if cell >= 0:
        v += (BAYER4[cell] - 7.5) / 16 * 0.25
    return int(round(min(max(v, 0.0), 1.0) * 8)) * 125


def raster(rows: int = 75, width: float = 100.0, pixel: float = 3.0, feed: int = 1500, pitch: float = 1.0,
           dither: bool = False) -> str:
    """Rows of width mm, pixel mm apart along a row, pitch mm between rows, at feed mm/min;
    dither: ordered-dithered pixels (a photo engraving: a line per pixel, nearly)."""
    h = rows * pitch
    x0, y0 = -width / 2, -h / 2
    n = int(round(width / pixel))
    out = ["; nnik bench: LaserGRBL-style raster (synthetic image, M4 dynamic power)",
           f"; {rows} rows of {width:g} mm, {n} pixels each, {pitch:g} mm apart, F{feed}",
           "G90 (use absolute coordinates)", "G21", "M4 S0", f"G0 X{x0:.3f} Y{y0:.3f} F3000"]
    for r in range(rows):
        y = y0 + r * pitch
        if r:
            out.append(f"G0 Y{y:.3f}")
        forward = r % 2 == 0
        cols = range(n) if forward else range(n - 1, -1, -1)
        last_s, first = None, True
        for c in cols:
            xe = x0 + (c + 1) * pixel if forward else x0 + c * pixel
            xc = x0 + (c + 0.5) * pixel
            cell = lambda k: (r % 4) * 4 + k % 4 if dither else -1  # noqa: E731
            s = _power(xc, y, width, h, cell(c))
            nxt = c + 1 if forward else c - 1
            if 0 <= nxt < n and _power(x0 + (nxt + 0.5) * pixel, y, width, h, cell(nxt)) == s:
                continue  # the run goes on: one G1 for the whole run
            word = f"G1 X{xe:.3f}" if first else f"X{xe:.3f}"
            if s != last_s:
                word += f" S{s}"
            if first:
                word += f" F{feed}"
            out.append(word)
            last_s, first = s, False
    out += ["M5 S0", "G0 X0 Y0 (move back to origin)", "M2"]
    return "\n".join(out) + "\n"


def vector(glyphs: int = 400, size: float = 6.0, feed: int = 1200, width: float = 160.0) -> str:
    """Text-like strokes: per glyph a few G1 polyline strokes and an arc, laid in lines."""
    per_row = int(width // (size * 1.2))
    out = ["; nnik bench: text-like vector job (G1 strokes and G2/G3 arcs, M3)", "G90", "G21", "M3 S700",
           f"G1 F{feed}"]
    seed = 12345
    for g in range(glyphs):
        seed = (1103515245 * seed + 12345) & 0x7FFFFFFF
        gx = -width / 2 + (g % per_row) * size * 1.2
        gy = 80.0 - (g // per_row) * size * 1.6
        gy = (gy + 80.0) % 160.0 - 80.0
        kind = seed % 3
        out.append(f"G0 X{gx:.3f} Y{gy:.3f}")
        pts = [(0.0, 0.0), (0.5, 1.0), (1.0, 0.0)] if kind == 0 else \
              [(0.0, 0.0), (0.0, 1.0), (0.8, 1.0), (0.8, 0.5), (0.0, 0.5)] if kind == 1 else \
              [(1.0, 0.8), (0.5, 1.0), (0.0, 0.6), (0.3, 0.2), (1.0, 0.0)]
        for k, (u, v) in enumerate(pts[1:]):
            out.append(f"G1 X{gx + u * size:.3f} Y{gy + v * size:.3f}")
        cx, cy = gx + 0.5 * size, gy + 0.5 * size
        r = 0.3 * size
        out.append(f"G0 X{cx + r:.3f} Y{cy:.3f}")
        out.append(f"G{2 + (seed >> 3) % 2} X{cx - r:.3f} Y{cy:.3f} I{-r:.3f} J0")
    out += ["M5", "G0 X0 Y0", "M2"]
    return "\n".join(out) + "\n"


def write(path: Path, text: str) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="python -m nnik.bench.longjob", description=__doc__.splitlines()[0])
    p.add_argument("kind", choices=("raster", "vector"))
    p.add_argument("out")
    p.add_argument("--rows", type=int, default=75)
    p.add_argument("--width", type=float, default=100.0)
    p.add_argument("--pixel", type=float, default=3.0)
    p.add_argument("--feed", type=int, default=1500)
    p.add_argument("--pitch", type=float, default=1.0)
    p.add_argument("--dither", action="store_true", help="ordered-dithered pixels (a photo engraving)")
    p.add_argument("--glyphs", type=int, default=400)
    a = p.parse_args(argv)
    text = (raster(a.rows, a.width, a.pixel, a.feed, a.pitch, a.dither) if a.kind == "raster"
            else vector(a.glyphs, feed=a.feed))
    path = write(Path(a.out), text)
    print(f"{path}: {text.count(chr(10))} lines")


if __name__ == "__main__":
    main()
