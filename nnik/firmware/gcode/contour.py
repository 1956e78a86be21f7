"""Contour error of a job (Koren): how far each reached position is from the programmed path.

Reached positions are the exact forward kinematics of the step counts after every stepper tick
that moved a motor. The error splits into:
  * IK error: at each sample, the delivered IK command's position vs the path (the model's
    error plus the rounding to whole actuator units; with a shaper also its corner smoothing);
  * rounding: the same for the exact IK rounded half up (what any IK on these motors keeps);
  * chord (segmentation) error: the exact IK at consecutive samples, joined by a straight
    line in joint space (what the DDA does), mapped through the exact forward kinematics.
Distances are to the move itself or its neighbours (corners), in micrometres.
"""

from __future__ import annotations

import numpy as np

from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.motion import Move, Plan, Segments

CHORD_SAMPLES = 16


def _stats(d: np.ndarray) -> dict:
    if not len(d):
        return {"max": 0.0, "rms": 0.0, "n": 0}
    return {"max": float(d.max()), "rms": float(np.sqrt((d**2).mean())), "n": int(len(d))}


def _line_dist(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return _line_geo_dist(p, _line_geo(a, b))


def _line_geo(a: np.ndarray, b: np.ndarray) -> tuple:
    ab = b - a
    return a, ab, float(ab @ ab)


def _line_geo_dist(p: np.ndarray, geo: tuple) -> np.ndarray:
    a, ab, L2 = geo
    t = np.zeros(len(p)) if L2 == 0 else np.clip(((p - a) @ ab) / L2, 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def _ang(v: np.ndarray):
    return np.arctan2(v[..., 1], v[..., 0])


def _arc_dist(p: np.ndarray, c: np.ndarray, r: float, a: np.ndarray, b: np.ndarray, ccw: bool) -> np.ndarray:
    """Distance to the arc from a to b about c (radius r), counter-clockwise if ccw."""
    return _arc_geo_dist(p, _arc_geo(c, r, a, b, ccw))


def _arc_geo(c: np.ndarray, r: float, a: np.ndarray, b: np.ndarray, ccw: bool) -> tuple:
    a0, b0 = _ang(a - c), _ang(b - c)
    sweep = (b0 - a0) % (2 * np.pi) if ccw else (a0 - b0) % (2 * np.pi)
    if sweep == 0:
        sweep = 2 * np.pi  # end = start: a full turn
    return c, r, a, b, ccw, a0, sweep


def _arc_geo_dist(p: np.ndarray, geo: tuple) -> np.ndarray:
    c, r, a, b, ccw, a0, sweep = geo
    rel = (_ang(p - c) - a0) % (2 * np.pi) if ccw else (a0 - _ang(p - c)) % (2 * np.pi)
    radial = np.abs(np.linalg.norm(p - c, axis=1) - r)
    ends = np.minimum(np.linalg.norm(p - a, axis=1), np.linalg.norm(p - b, axis=1))
    return np.where(rel <= sweep, radial, ends)


def _move_geo(mv: Move, origin_mm: np.ndarray) -> tuple:
    """What move_dist takes from a move before it looks at the points."""
    a = origin_mm + np.asarray(mv.start) / 1000.0
    b = origin_mm + np.asarray(mv.end) / 1000.0
    if mv.kind == "line":
        return _line_geo_dist, _line_geo(a, b)
    c = origin_mm + np.asarray(mv.center) / 1000.0
    return _arc_geo_dist, _arc_geo(c, mv.radius / 1000.0, a, b, mv.ccw)


def move_dist(p_mm: np.ndarray, mv: Move, origin_mm: np.ndarray) -> np.ndarray:
    fn, geo = _move_geo(mv, origin_mm)
    return fn(p_mm, geo)


_GEOMETRY: list = [None, None, None]  # moves, origin, arrays: the last job's (four passes use it)


def _geometry(moves: list[Move], origin_mm: np.ndarray) -> dict:
    """Every move's _move_geo as arrays (rows: moves), for distances to many moves at once."""
    key = np.asarray(origin_mm, dtype=np.float64).tolist()
    if _GEOMETRY[0] is moves and _GEOMETRY[1] == key and len(_GEOMETRY[2]["r"]) == len(moves):
        return _GEOMETRY[2]
    _GEOMETRY[:] = [moves, key, _geometry_of(moves, origin_mm)]
    return _GEOMETRY[2]


def _geometry_of(moves: list[Move], origin_mm: np.ndarray) -> dict:
    n = len(moves)
    g = {"arc": np.zeros(n, bool), "a": np.zeros((n, 2)), "b": np.zeros((n, 2)), "ab": np.zeros((n, 2)),
         "L2": np.zeros(n), "c": np.zeros((n, 2)), "r": np.zeros(n), "ccw": np.zeros(n, bool), "a0": np.zeros(n),
         "sweep": np.zeros(n)}
    for k, mv in enumerate(moves):
        fn, geo = _move_geo(mv, origin_mm)
        if fn is _line_geo_dist:
            g["a"][k], g["ab"][k], g["L2"][k] = geo
        else:
            g["arc"][k] = True
            g["c"][k], g["r"][k], g["a"][k], g["b"][k], g["ccw"][k], g["a0"][k], g["sweep"][k] = geo
    return g


def _dist_to(p: np.ndarray, g: dict, n: np.ndarray, gm: np.ndarray) -> np.ndarray:
    """Distance of each point to its group's move (inf: none), as _line_geo_dist / _arc_geo_dist
    give it. The points are groups of consecutive rows (n[j] of them, move gm[j], -1: none), sorted
    by size; the groups of one size are one (groups, size, 2) array and every operation runs on it
    with each group's own move broadcast, so each group's arithmetic is move_dist's, the line's dot
    product included: BLAS rounds a row by its place in its matrix, and the stacked matmul is a
    gemv per group, each group its own matrix as in move_dist."""
    d = np.full(len(p), np.inf)
    start = np.cumsum(n) - n
    sizes, first, many = np.unique(n, return_index=True, return_counts=True)
    for size, j0, cnt in zip(sizes.tolist(), first.tolist(), many.tolist()):
        lo = int(start[j0])
        q = p[lo:lo + size * cnt].reshape(cnt, size, 2)
        m = gm[j0:j0 + cnt]
        mk = np.maximum(m, 0)
        out = np.full((cnt, size), np.inf)
        line, arc = (m >= 0) & ~g["arc"][mk], (m >= 0) & g["arc"][mk]
        if line.any():
            a, ab, L2 = g["a"][mk][:, None, :], g["ab"][mk], g["L2"][mk][:, None]
            diff = q - a
            v = np.where((line & (L2[:, 0] != 0))[:, None], ab, 0.0)
            dot = (diff @ v[:, :, None])[:, :, 0]
            with np.errstate(divide="ignore", invalid="ignore"):
                t = np.where(L2 == 0, 0.0, np.clip(dot / L2, 0.0, 1.0))
            dl = np.linalg.norm(q - (a + t[:, :, None] * ab[:, None, :]), axis=2)
            out[line] = dl[line]
        if arc.any():
            ma = mk[arc]
            c, a, b = g["c"][ma][:, None, :], g["a"][ma][:, None, :], g["b"][ma][:, None, :]
            a0, sweep, r = g["a0"][ma][:, None], g["sweep"][ma][:, None], g["r"][ma][:, None]
            qa = q[arc]
            ang = _ang(qa - c)
            rel = np.where(g["ccw"][ma][:, None], (ang - a0) % (2 * np.pi), (a0 - ang) % (2 * np.pi))
            radial = np.abs(np.linalg.norm(qa - c, axis=2) - r)
            ends = np.minimum(np.linalg.norm(qa - a, axis=2), np.linalg.norm(qa - b, axis=2))
            out[arc] = np.where(rel <= sweep, radial, ends)
        d[lo:lo + size * cnt] = out.reshape(-1)
    return d


BIG_GROUP = 128  # points: a move with more goes through move_dist alone, fewer are done together


def path_dist_um(p_mm: np.ndarray, move_idx: np.ndarray, moves: list[Move], origin_mm: np.ndarray) -> np.ndarray:
    """Distance (um) of each point to its move or the moves before and after it."""
    # the points grouped by move with one stable sort: each group is the same points, in the same
    # order, as a mask per move would pick; a big group goes through move_dist per neighbour, the
    # small ones (a job of many short moves) through _dist_to at once, with the same arithmetic
    move_idx = np.asarray(move_idx, dtype=np.int64)
    d = np.full(len(p_mm), np.inf)
    if not len(p_mm):
        return d * 1000.0
    order = np.argsort(move_idx, kind="stable")
    ms, first, counts = np.unique(move_idx[order], return_index=True, return_counts=True)
    p = np.ascontiguousarray(p_mm[order], dtype=np.float64)
    best = np.full(len(p), np.inf)
    big = counts >= BIG_GROUP
    geo = {}
    for m, lo, n in zip(ms[big].tolist(), first[big].tolist(), counts[big].tolist()):
        pts, b = p[lo:lo + n], np.full(n, np.inf)
        for k in (m - 1, m, m + 1):
            if 0 <= k < len(moves):
                if k not in geo:
                    geo[k] = _move_geo(moves[k], origin_mm)
                fn, gk = geo[k]
                b = np.minimum(b, fn(pts, gk))
        best[lo:lo + n] = b
    if (~big).any():
        by = np.argsort(counts[~big], kind="stable")  # the small groups by size, each whole and in order
        sm, sf, sn = ms[~big][by], first[~big][by], counts[~big][by]
        rows = np.repeat(sf - (np.cumsum(sn) - sn), sn) + np.arange(sn.sum())
        g = _geometry(moves, origin_mm)
        valid = lambda m: np.where((m >= 0) & (m < len(moves)), m, -1)  # noqa: E731
        q, b = p[rows], np.full(len(rows), np.inf)
        for j in (-1, 0, 1):
            b = np.minimum(b, _dist_to(q, g, sn, valid(sm + j)))
        best[rows] = b
    d[order] = best
    return d * 1000.0


def segment_moves(plan: Plan) -> np.ndarray:
    """Move index of every stepper segment (plan_steps sets it: a sample's block's move; a rest
    or the shaper's tail belongs to the move before, the first move if none)."""
    if plan.seg_move is None:
        raise ValueError("segment_moves needs plan_steps to have run on the plan")
    return plan.seg_move


def units_to_mm(scn, units: np.ndarray) -> np.ndarray:
    m = scn.mechanism
    return m.forward(m.q_rest + scn.actuator.from_units(np.asarray(units, dtype=np.float64)))


def reached(seg: Segments, events: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Counts after every tick that stepped (T, 2), its segment (T,) and its tick from the
    start of the job (T,), the segments running back to back."""
    from nnik.firmware.gcode.steps import positions

    counts = positions(seg, events)[1:]
    if not len(events):
        return counts, np.zeros(0, np.int64), np.zeros(0, np.int64)
    key = events[:, 0] * (int(seg.ticks.max()) + 1) + events[:, 1]
    last = np.r_[key[1:] != key[:-1], True]  # the last event of each (segment, tick)
    start = np.concatenate([[0], np.cumsum(seg.ticks)[:-1]])
    return counts[last], events[last, 0], start[events[last, 0]] + events[last, 1]


def contour_report(scn, cfg: MachineConfig, plan: Plan, seg: Segments, events: np.ndarray) -> dict:
    origin_mm = np.asarray(cfg.origin_um, dtype=np.float64) / 1000.0
    seg_move = segment_moves(plan)
    ends_mm = origin_mm + seg.ends_um / 1000.0
    counts, seg_of, tick = reached(seg, events)
    p_reached = units_to_mm(scn, counts) if len(counts) else np.zeros((0, 2))
    total = path_dist_um(p_reached, seg_move[seg_of], plan.moves, origin_mm) if len(counts) else np.zeros(0)
    ik = path_dist_um(units_to_mm(scn, seg.steps[1:]), seg_move, plan.moves, origin_mm)
    out = {"segments": int(len(seg.ticks)), "steps": int(len(events)), "ticks": int(seg.ticks.sum()),
           "seconds": float(seg.ticks.sum() / cfg.tick_hz), "clamped": int(seg.clamped.sum()),
           "contour_um": _stats(total), "ik_um": _stats(ik),
           "plot": {"reached_mm": p_reached, "error_um": total, "time_s": tick / cfg.tick_hz}}
    if scn.mechanism.analytic:
        from nnik.machine.data import exact_targets

        start_mm = origin_mm[None, :]
        exact = exact_targets(scn, np.concatenate([start_mm, ends_mm]))
        rounded = np.floor(exact + 0.5)
        out["rounding_um"] = _stats(path_dist_um(units_to_mm(scn, rounded[1:]), seg_move, plan.moves, origin_mm))
        t = (np.arange(1, CHORD_SAMPLES) / CHORD_SAMPLES)[None, :, None]
        q = exact[:-1, None, :] + t * (exact[1:, None, :] - exact[:-1, None, :])  # (S, k, 2)
        p = units_to_mm(scn, q.reshape(-1, 2))
        chord = path_dist_um(p, np.repeat(seg_move, CHORD_SAMPLES - 1), plan.moves, origin_mm)
        out["chord_um"] = _stats(chord)
    return out
