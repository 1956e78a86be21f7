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


def path_dist_um(p_mm: np.ndarray, move_idx: np.ndarray, moves: list[Move], origin_mm: np.ndarray) -> np.ndarray:
    """Distance (um) of each point to its move or the moves before and after it."""
    # the points grouped by move with one stable sort (each group is the same points, in the
    # same order, that a mask per move would pick: the same arithmetic, without a pass per move;
    # BLAS rounds a product differently by its place in an array, so the groups must stay these)
    move_idx = np.asarray(move_idx)
    order = np.argsort(move_idx, kind="stable")
    ms, first = np.unique(move_idx[order], return_index=True)
    bounds = np.append(first, len(order))
    p_sorted = p_mm[order]
    d = np.full(len(p_mm), np.inf)
    geo = {}
    for m, lo, hi in zip(ms.tolist(), bounds[:-1].tolist(), bounds[1:].tolist()):
        pts, best = p_sorted[lo:hi], np.full(hi - lo, np.inf)
        for k in (m - 1, m, m + 1):
            if 0 <= k < len(moves):
                if k not in geo:
                    geo[k] = _move_geo(moves[k], origin_mm)
                fn, g = geo[k]
                best = np.minimum(best, fn(pts, g))
        d[order[lo:hi]] = best
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
